//! Turning Lua failures into `FILE:LINE: message` errors.

use mlua::Lua;

use super::state::SessionState;
use crate::{Error, Location};

/// The file and line of the Lua code that called the running Rust function (the innermost
/// Lua frame on the stack), or the last place the Lua code was seen when no Lua frame is
/// active.
#[must_use]
pub fn caller_location(lua: &Lua) -> Location {
    for level in 0..64 {
        let found = lua.inspect_stack(level, |d| {
            let source = d.source();
            if source.what == "C" {
                return None;
            }
            let name = source.source.as_deref().unwrap_or("?");
            let file = name
                .strip_prefix('@')
                .or_else(|| name.strip_prefix('='))
                .unwrap_or(name);
            Some(Location {
                file: file.to_string(),
                line: d.current_line().map(|l| l as u32),
            })
        });
        match found {
            None => break,
            Some(Some(loc)) => return loc,
            Some(None) => {}
        }
    }
    lua.app_data_ref::<SessionState>()
        .and_then(|s| s.last_location.clone())
        .unwrap_or_else(|| Location {
            file: "?".into(),
            line: None,
        })
}

/// A script error located at the calling Lua code: what a plugin returns when a script
/// passes something wrong. It crosses Lua typed (an [`Error::Script`] behind
/// [`mlua::Error::ExternalError`]) and [`to_engine_error`] gets it back as it was; it prints
/// as `FILE:LINE: message`.
#[must_use]
pub fn script_error(lua: &Lua, message: impl std::fmt::Display) -> mlua::Error {
    let location = caller_location(lua);
    if location.file == "?" {
        // No Lua code is running (a plugin called from Rust): the caller adds the place.
        return mlua::Error::RuntimeError(message.to_string());
    }
    mlua::Error::external(Error::script(location, message.to_string()))
}

/// The engine error inside an mlua error, if one crossed Lua (see [`script_error`]).
#[must_use]
pub fn engine_error_of(err: &mlua::Error) -> Option<&Error> {
    match err {
        mlua::Error::ExternalError(e) => e.downcast_ref::<Error>(),
        mlua::Error::CallbackError { cause, .. } => engine_error_of(cause),
        _ => None,
    }
}

/// The one-line message of an error without its location: the message of an engine error
/// that crossed Lua, or the first line of any other error with the calling code's
/// `FILE:LINE: ` (which Lua puts in front of `error("...")`) left out. For adapters that
/// put a failure from a nested call into their own message.
#[must_use]
pub fn error_message(lua: &Lua, err: &mlua::Error) -> String {
    if let Some(e) = engine_error_of(err) {
        return e.message();
    }
    let message = match err {
        mlua::Error::RuntimeError(m) => m.clone(),
        mlua::Error::CallbackError { cause, .. } => return error_message(lua, cause),
        other => other.to_string(),
    };
    let line = message.lines().next().unwrap_or("").to_string();
    let prefix = format!("{}: ", caller_location(lua));
    line.strip_prefix(&prefix)
        .map(str::to_string)
        .unwrap_or(line)
}

/// Converts an mlua error into an engine error with the script's file and line. Engine
/// errors that crossed Lua come back as they were (a host can match
/// [`Error::TimeLimit`]); Lua's own errors (`error("...")`, syntax) become
/// [`Error::Script`] with the place Lua names.
#[must_use]
pub fn to_engine_error(lua: &Lua, err: mlua::Error) -> Error {
    let traceback = traceback_of(&err);
    let fallback = || {
        traceback
            .as_deref()
            .and_then(|t| location_in_traceback(lua, t))
            .or_else(|| {
                lua.app_data_ref::<SessionState>()
                    .and_then(|s| s.last_location.clone())
            })
            .unwrap_or_else(|| Location {
                file: "?".into(),
                line: None,
            })
    };
    match describe(lua, &err) {
        Described::Message(message, location) => Error::Script {
            location: location.unwrap_or_else(fallback),
            message,
            traceback,
        },
        Described::Typed(e) if e.location().is_some_and(|l| l.file == "?") => e.at(fallback()),
        Described::Typed(e) => e,
    }
}

/// What an mlua error stands for: a message (and the place it names), or an engine error
/// other than a script error that crossed Lua (a limit).
enum Described {
    Message(String, Option<Location>),
    Typed(Error),
}

fn traceback_of(err: &mlua::Error) -> Option<String> {
    match err {
        mlua::Error::CallbackError { traceback, cause } => {
            traceback_of(cause).or_else(|| Some(traceback.clone()))
        }
        mlua::Error::WithContext { cause, .. } => traceback_of(cause),
        _ => None,
    }
}

/// The one-line message of an error and the location it names, if any; limits as they are.
fn describe(lua: &Lua, err: &mlua::Error) -> Described {
    use Described::{Message, Typed};
    use mlua::Error as E;
    match err {
        E::SyntaxError { message, .. } | E::RuntimeError(message) => {
            let (m, l) = parse_message(lua, message);
            Message(m, l)
        }
        E::MemoryError(_) => {
            let limit = lua
                .app_data_ref::<SessionState>()
                .map(|s| s.ctx.budget.limit())
                .unwrap_or(0);
            Typed(Error::MemoryLimit {
                location: Location {
                    file: "?".into(),
                    line: None,
                },
                limit,
                what: None,
            })
        }
        E::CallbackError { cause, .. } => describe(lua, cause),
        E::WithContext { context, cause } => match describe(lua, cause) {
            Message(m, l) => Message(format!("{context}: {m}"), l),
            typed => typed,
        },
        E::BadArgument {
            to,
            pos,
            name,
            cause,
        } => {
            let what = match (to, name) {
                (Some(to), Some(name)) => format!("bad argument #{pos} ({name}) to '{to}'"),
                (Some(to), None) => format!("bad argument #{pos} to '{to}'"),
                (None, Some(name)) => format!("bad argument #{pos} ({name})"),
                (None, None) => format!("bad argument #{pos}"),
            };
            match describe(lua, cause) {
                Message(m, l) => Message(format!("{what}: {m}"), l),
                typed => typed,
            }
        }
        E::FromLuaConversionError { from, to, message } => {
            let extra = message
                .as_deref()
                .map(|m| format!(" ({m})"))
                .unwrap_or_default();
            Message(format!("expected {to}, got {from}{extra}"), None)
        }
        E::ExternalError(e) => match e.downcast_ref::<Error>() {
            Some(Error::Script {
                location, message, ..
            }) => Message(message.clone(), Some(location.clone())),
            Some(other) if other.location().is_some() => Typed(other.duplicate()),
            _ => Message(one_line(&e.to_string()), None),
        },
        other => {
            let (m, l) = parse_message(lua, &other.to_string());
            Message(m, l)
        }
    }
}

/// Splits `file:line: message` (as Lua writes runtime and syntax errors), mapping a name Lua
/// shortened (`...tail`) back to the full path.
fn parse_message(lua: &Lua, message: &str) -> (String, Option<Location>) {
    let message = one_line(message);
    match split_location(&message) {
        Some((file, line, rest)) => {
            let file = full_chunk_name(lua, file);
            (
                rest.to_string(),
                Some(Location {
                    file,
                    line: Some(line),
                }),
            )
        }
        None => (without_address(message), None),
    }
}

/// An error raised with a value that is not a message (`error({})`) reaches Rust as the
/// value's address (`table: 0x55d0...`): said as what it is instead.
fn without_address(message: String) -> String {
    let value = message
        .split_once(": 0x")
        .filter(|(_, hex)| !hex.is_empty() && hex.chars().all(|c| c.is_ascii_hexdigit()));
    match value {
        Some((kind, _)) if ["table", "function", "userdata", "thread"].contains(&kind) => {
            format!("an error raised with a {kind} value, not a message")
        }
        _ => message,
    }
}

fn full_chunk_name(lua: &Lua, shown: &str) -> String {
    lua.app_data_ref::<SessionState>()
        .and_then(|s| s.chunk(shown).map(|c| c.display.clone()))
        .unwrap_or_else(|| shown.to_string())
}

/// The first Lua frame (`file:line: in ...`) of a traceback.
fn location_in_traceback(lua: &Lua, traceback: &str) -> Option<Location> {
    traceback.lines().find_map(|l| {
        let l = l.trim();
        if l.starts_with("[C]") {
            return None;
        }
        let (file, line, _) = split_location(l)?;
        Some(Location {
            file: full_chunk_name(lua, file),
            line: Some(line),
        })
    })
}

/// `path/to/x.lua:12: rest` -> (`path/to/x.lua`, 12, `rest`).
pub(crate) fn split_location(s: &str) -> Option<(&str, u32, &str)> {
    let bytes = s.as_bytes();
    for (i, _) in s.match_indices(':') {
        let digits = bytes[i + 1..]
            .iter()
            .take_while(|b| b.is_ascii_digit())
            .count();
        let end = i + 1 + digits;
        if i > 0 && digits > 0 && bytes.get(end) == Some(&b':') {
            let line = s[i + 1..end].parse().ok()?;
            return Some((&s[..i], line, s[end + 1..].trim_start()));
        }
    }
    None
}

/// The message up to any traceback, on one line.
fn one_line(s: &str) -> String {
    let s = s.split("\nstack traceback:").next().unwrap_or(s);
    s.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_file_line_message() {
        assert_eq!(
            split_location("a/b.lua:12: boom: x"),
            Some(("a/b.lua", 12, "boom: x"))
        );
        assert_eq!(split_location("no location here"), None);
        assert_eq!(split_location("x:y: z"), None);
    }

    #[test]
    fn one_line_drops_tracebacks() {
        assert_eq!(one_line("a\n  b\nstack traceback:\n\t[C]: in ?"), "a b");
    }
}
