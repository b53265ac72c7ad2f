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

/// A runtime error `FILE:LINE: message` located at the calling Lua code: what a plugin
/// returns when a script passes something wrong.
#[must_use]
pub fn script_error(lua: &Lua, message: impl std::fmt::Display) -> mlua::Error {
    let location = caller_location(lua);
    if location.file == "?" {
        // No Lua code is running (a plugin called from Rust): the caller adds the place.
        return mlua::Error::RuntimeError(message.to_string());
    }
    mlua::Error::RuntimeError(format!("{location}: {message}"))
}

/// Converts an mlua error into an engine error with the script's file and line.
#[must_use]
pub fn to_engine_error(lua: &Lua, err: mlua::Error) -> Error {
    let traceback = traceback_of(&err);
    let (message, location) = describe(lua, &err);
    let location = location
        .or_else(|| {
            traceback
                .as_deref()
                .and_then(|t| location_in_traceback(lua, t))
        })
        .or_else(|| {
            lua.app_data_ref::<SessionState>()
                .and_then(|s| s.last_location.clone())
        })
        .unwrap_or_else(|| Location {
            file: "?".into(),
            line: None,
        });
    Error::Script {
        location,
        message,
        traceback,
    }
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

/// The one-line message of an error and the location it names, if any.
fn describe(lua: &Lua, err: &mlua::Error) -> (String, Option<Location>) {
    use mlua::Error as E;
    match err {
        E::SyntaxError { message, .. } | E::RuntimeError(message) => parse_message(lua, message),
        E::MemoryError(_) => {
            let limit = lua
                .app_data_ref::<SessionState>()
                .map(|s| s.memory_limit)
                .unwrap_or(0);
            (
                format!(
                    "memory limit of {} MiB exceeded (see --memory-limit)",
                    limit >> 20
                ),
                None,
            )
        }
        E::CallbackError { cause, .. } => describe(lua, cause),
        E::WithContext { context, cause } => {
            let (m, l) = describe(lua, cause);
            (format!("{context}: {m}"), l)
        }
        E::BadArgument {
            to,
            pos,
            name,
            cause,
        } => {
            let (m, l) = describe(lua, cause);
            let what = match (to, name) {
                (Some(to), Some(name)) => format!("bad argument #{pos} ({name}) to '{to}'"),
                (Some(to), None) => format!("bad argument #{pos} to '{to}'"),
                (None, Some(name)) => format!("bad argument #{pos} ({name})"),
                (None, None) => format!("bad argument #{pos}"),
            };
            (format!("{what}: {m}"), l)
        }
        E::FromLuaConversionError { from, to, message } => {
            let extra = message
                .as_deref()
                .map(|m| format!(" ({m})"))
                .unwrap_or_default();
            (format!("expected {to}, got {from}{extra}"), None)
        }
        E::ExternalError(e) => match e.downcast_ref::<Error>() {
            Some(Error::Script {
                location, message, ..
            }) => (message.clone(), Some(location.clone())),
            _ => (one_line(&e.to_string()), None),
        },
        other => parse_message(lua, &other.to_string()),
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
        None => (message, None),
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
