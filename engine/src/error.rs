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
/// Every error that a script can cause is an [`Error::Script`] with the file and line to fix;
/// it prints as `FILE:LINE: message` on one line.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A script failed: syntax, runtime, a bad argument to a `pge` function, a limit.
    #[error("{location}: {message}")]
    Script {
        /// Where it failed.
        location: Location,
        /// What went wrong, on one line.
        message: String,
        /// The Lua traceback, when there is one.
        traceback: Option<String>,
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

impl Error {
    /// A script error at `location`.
    pub fn script(location: Location, message: impl Into<String>) -> Error {
        Error::Script {
            location,
            message: message.into(),
            traceback: None,
        }
    }

    /// The script location, for script errors.
    #[must_use]
    pub fn location(&self) -> Option<&Location> {
        match self {
            Error::Script { location, .. } => Some(location),
            _ => None,
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
}
