//! The engine's error type.

use std::fmt;
use std::path::PathBuf;

use crate::geometry::GeometryError;

/// A place in a script: the file as the user named it and a 1-based line, when known.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct Location {
    /// The script's path, as given on the command line or resolved by `require`/`pge.load`.
    pub file: String,
    /// 1-based line number, if known.
    pub line: Option<u32>,
}

impl Location {
    /// A location with a line.
    #[must_use]
    pub fn new(file: impl Into<String>, line: u32) -> Location {
        Location {
            file: file.into(),
            line: Some(line),
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{line}", self.file),
            None => write!(f, "{}", self.file),
        }
    }
}

/// Everything that can go wrong while generating.
///
/// Every error that a script can cause carries the file and line to fix and prints as
/// `FILE:LINE: message` on one line: an [`Error::Script`] for a mistake, or one of the limits
/// ([`Error::TimeLimit`], [`Error::MemoryLimit`], [`Error::InstructionLimit`],
/// [`Error::ModuleLimit`], [`Error::Cancelled`]) that a host can match on. Errors stay typed
/// while they cross Lua (see [`crate::lua::script_error`] and [`crate::lua::to_engine_error`]).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A script failed: syntax, runtime, a bad argument or option to a `pge` function.
    #[error("{location}: {message}")]
    Script {
        /// Where it failed.
        location: Location,
        /// What went wrong, on one line.
        message: String,
        /// The Lua traceback, when there is one.
        traceback: Option<String>,
    },
    /// The run went past its wall-clock limit (`--time-limit`, [`crate::Limits::time`]).
    #[error("{location}: time limit exceeded (see --time-limit)")]
    TimeLimit {
        /// Where the script (or the algorithm it started) was when the time ran out.
        location: Location,
    },
    /// The run went past its memory limit (`--memory-limit`, [`crate::Limits::memory`]): its
    /// Lua state, or a buffer the work it asked for needed ([`crate::Budget`]).
    #[error("{location}: {}memory limit of {} MiB exceeded (see --memory-limit)", what_prefix(what), limit >> 20)]
    MemoryLimit {
        /// Where the script was when the allocation failed.
        location: Location,
        /// The limit in bytes.
        limit: usize,
        /// What needed the memory and the option that sized it, when a size was checked
        /// before allocating (`the terrain mesh (resolution = 0.01) needs 120 GiB`).
        what: Option<String>,
    },
    /// The Lua code executed more instructions than [`crate::Limits::instructions`] allows.
    #[error("{location}: instruction limit of {limit} exceeded")]
    InstructionLimit {
        /// Where the script was when the budget ran out.
        location: Location,
        /// The budget.
        limit: u64,
    },
    /// A rewriting system's string grew past its module cap (`maxModules`,
    /// [`crate::Limits::max_modules`]).
    #[error(
        "{location}: L-system '{system}': step {step}: the string reached {count} modules, \
         more than maxModules ({max})"
    )]
    ModuleLimit {
        /// Where the L-system was created.
        location: Location,
        /// The L-system's name.
        system: String,
        /// The derivation step (0 for the axiom).
        step: u32,
        /// How many modules the string had when it stopped.
        count: u64,
        /// The cap.
        max: usize,
    },
    /// The run was cancelled from another thread ([`crate::SessionOptions::cancel`]).
    #[error("{location}: cancelled")]
    Cancelled {
        /// Where the script (or algorithm) was when it noticed.
        location: Location,
    },
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A mesh or texture broke an invariant.
    #[error("invalid geometry: {0}")]
    Geometry(#[from] GeometryError),
    /// The model could not be written in the requested format.
    #[error("export: {0}")]
    Export(String),
    /// Two plugins registered under the same name.
    #[error("plugin '{0}' is added twice")]
    DuplicatePlugin(String),
    /// A plugin failed to register its functions.
    #[error("plugin '{plugin}' failed to register: {message}")]
    Plugin {
        /// Plugin name.
        plugin: String,
        /// The cause.
        message: String,
    },
}

/// An option of an algorithm outside what it accepts, found by the algorithm's checks
/// before it runs (a script sees it as a script error at the constructor's call).
///
/// ```
/// use pge_engine::OptionError;
///
/// let e = OptionError::out_of_range("scale", "a number > 0", -1.0);
/// assert_eq!(e.to_string(), "scale must be a number > 0, got -1");
/// ```
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum OptionError {
    /// A value outside the option's range.
    #[error("{option} must be {expected}, got {got}")]
    OutOfRange {
        /// The option, as scripts spell it.
        option: &'static str,
        /// What it needs ("a number > 0").
        expected: &'static str,
        /// The value given, as it prints.
        got: String,
    },
    /// A value that is not what the option takes (a vector that is not finite, an empty list).
    #[error("{option} must be {expected}")]
    Invalid {
        /// The option, as scripts spell it.
        option: &'static str,
        /// What it needs.
        expected: &'static str,
    },
}

impl OptionError {
    /// `option` must be `expected`, and `got` is not.
    #[must_use]
    pub fn out_of_range(
        option: &'static str,
        expected: &'static str,
        got: impl fmt::Display,
    ) -> OptionError {
        OptionError::OutOfRange {
            option,
            expected,
            got: got.to_string(),
        }
    }

    /// `option` must be `expected`.
    #[must_use]
    pub fn invalid(option: &'static str, expected: &'static str) -> OptionError {
        OptionError::Invalid { option, expected }
    }
}

/// `what: ` before a limit's phrase, when the error says what needed the memory.
fn what_prefix(what: &Option<String>) -> String {
    what.as_ref().map(|w| format!("{w}: ")).unwrap_or_default()
}

impl Error {
    /// A script error at `location`.
    pub fn script(location: Location, message: impl Into<String>) -> Error {
        Error::Script {
            location,
            message: message.into(),
            traceback: None,
        }
    }

    /// The script location, for script errors and limits.
    #[must_use]
    pub fn location(&self) -> Option<&Location> {
        match self {
            Error::Script { location, .. }
            | Error::TimeLimit { location }
            | Error::MemoryLimit { location, .. }
            | Error::InstructionLimit { location, .. }
            | Error::ModuleLimit { location, .. }
            | Error::Cancelled { location } => Some(location),
            _ => None,
        }
    }

    /// What went wrong without the location: the message of a script error, the phrase of a
    /// limit (`time limit exceeded (see --time-limit)`), the whole text of other errors.
    #[must_use]
    pub fn message(&self) -> String {
        match self {
            Error::Script { message, .. } => message.clone(),
            Error::TimeLimit { .. } => "time limit exceeded (see --time-limit)".into(),
            Error::MemoryLimit { limit, what, .. } => format!(
                "{}memory limit of {} MiB exceeded (see --memory-limit)",
                what_prefix(what),
                limit >> 20
            ),
            Error::InstructionLimit { limit, .. } => {
                format!("instruction limit of {limit} exceeded")
            }
            Error::ModuleLimit {
                system,
                step,
                count,
                max,
                ..
            } => format!(
                "L-system '{system}': step {step}: the string reached {count} modules, more \
                 than maxModules ({max})"
            ),
            Error::Cancelled { .. } => "cancelled".into(),
            other => other.to_string(),
        }
    }

    /// The same error placed at `location` (script errors and limits; others unchanged).
    #[must_use]
    pub fn at(mut self, at: Location) -> Error {
        match &mut self {
            Error::Script { location, .. }
            | Error::TimeLimit { location }
            | Error::MemoryLimit { location, .. }
            | Error::InstructionLimit { location, .. }
            | Error::ModuleLimit { location, .. }
            | Error::Cancelled { location } => *location = at,
            _ => {}
        }
        self
    }

    /// Whether this is one of the limits a session runs under (time, memory, instructions,
    /// modules) or a cancellation, rather than a mistake in the script.
    #[must_use]
    pub fn is_limit(&self) -> bool {
        matches!(
            self,
            Error::TimeLimit { .. }
                | Error::MemoryLimit { .. }
                | Error::InstructionLimit { .. }
                | Error::ModuleLimit { .. }
                | Error::Cancelled { .. }
        )
    }

    /// A copy of the error (an I/O error keeps its kind and message), for errors that crossed
    /// Lua behind a shared pointer.
    #[must_use]
    pub fn duplicate(&self) -> Error {
        match self {
            Error::Script {
                location,
                message,
                traceback,
            } => Error::Script {
                location: location.clone(),
                message: message.clone(),
                traceback: traceback.clone(),
            },
            Error::TimeLimit { location } => Error::TimeLimit {
                location: location.clone(),
            },
            Error::MemoryLimit {
                location,
                limit,
                what,
            } => Error::MemoryLimit {
                location: location.clone(),
                limit: *limit,
                what: what.clone(),
            },
            Error::InstructionLimit { location, limit } => Error::InstructionLimit {
                location: location.clone(),
                limit: *limit,
            },
            Error::ModuleLimit {
                location,
                system,
                step,
                count,
                max,
            } => Error::ModuleLimit {
                location: location.clone(),
                system: system.clone(),
                step: *step,
                count: *count,
                max: *max,
            },
            Error::Cancelled { location } => Error::Cancelled {
                location: location.clone(),
            },
            Error::Io { path, source } => Error::Io {
                path: path.clone(),
                source: std::io::Error::new(source.kind(), source.to_string()),
            },
            Error::Geometry(g) => Error::Geometry(g.clone()),
            Error::Export(m) => Error::Export(m.clone()),
            Error::DuplicatePlugin(p) => Error::DuplicatePlugin(p.clone()),
            Error::Plugin { plugin, message } => Error::Plugin {
                plugin: plugin.clone(),
                message: message.clone(),
            },
        }
    }
}

/// The engine's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn script_errors_print_file_line_message() {
        let e = Error::script(Location::new("scripts/a.lua", 12), "boom");
        assert_eq!(e.to_string(), "scripts/a.lua:12: boom");
        let e = Error::script(
            Location {
                file: "x.lua".into(),
                line: None,
            },
            "gone",
        );
        assert_eq!(e.to_string(), "x.lua: gone");
    }

    #[test]
    fn limits_print_their_location_then_their_message() {
        let at = Location::new("a.lua", 3);
        let limits = [
            Error::TimeLimit {
                location: at.clone(),
            },
            Error::MemoryLimit {
                location: at.clone(),
                limit: 16 << 20,
                what: None,
            },
            Error::InstructionLimit {
                location: at.clone(),
                limit: 100,
            },
            Error::ModuleLimit {
                location: at.clone(),
                system: "big".into(),
                step: 7,
                count: 128,
                max: 100,
            },
            Error::Cancelled {
                location: at.clone(),
            },
        ];
        for e in &limits {
            assert!(e.is_limit());
            assert_eq!(e.to_string(), format!("a.lua:3: {}", e.message()));
            assert_eq!(e.duplicate().to_string(), e.to_string());
            let moved = e.duplicate().at(Location::new("b.lua", 9));
            assert_eq!(moved.location(), Some(&Location::new("b.lua", 9)));
        }
        assert_eq!(
            limits[1].message(),
            "memory limit of 16 MiB exceeded (see --memory-limit)"
        );
        assert_eq!(
            limits[3].message(),
            "L-system 'big': step 7: the string reached 128 modules, more than maxModules (100)"
        );
        assert!(!Error::script(at, "x").is_limit());
    }
}
