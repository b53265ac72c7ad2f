//! The sandbox: which files scripts may read, `require`, `pge.load`, and the base library
//! functions that would reach outside.

use std::path::{Component, Path, PathBuf};

use mlua::{Lua, Table, Value};

use super::chunks::{ShippedChunk, shipped_chunk};
use super::errors::{caller_location, script_error};
use super::params;
use super::state::{self, Chunk, EngineHandle, SessionState};
use crate::files::{DiskFiles, Files};
use crate::{Error, Location};

const LOADED_KEY: &str = "pge.loaded";

/// The global `setmetatable`, refusing metatables with a `__gc` field (see [`register`]).
pub(crate) static GUARDED_SETMETATABLE: ShippedChunk = ShippedChunk {
    name: "=pge",
    source: r#"local setmetatable, rawget, type, error = ...
return function(t, mt, ...)
  if type(mt) == "table" and rawget(mt, "__gc") ~= nil then
    error("setmetatable: __gc finalizers are not allowed (Lua runs them outside the time limit)", 2)
  end
  return setmetatable(t, mt, ...)
end"#,
    compiled: include_bytes!("compiled/setmetatable.luac"),
    file: "setmetatable.luac",
};

pub(crate) fn register(lua: &Lua, pge: &Table) -> mlua::Result<()> {
    let globals = lua.globals();
    globals.set("dofile", Value::Nil)?;
    globals.set("loadfile", Value::Nil)?;
    // `load` of text only: binary chunks can break the VM's invariants. Without a chunk
    // name the chunk is named after the calling line (`main.lua:12: in load()`), so its
    // errors point at the script; without an `env` argument it sees the globals, as in
    // standard Lua.
    let load: mlua::Function = globals.get("load")?;
    globals.set(
        "load",
        lua.create_function(move |lua, args: mlua::MultiValue| {
            let mut args: Vec<Value> = args.into_iter().collect();
            if args.len() < 3 {
                args.resize(3, Value::Nil);
            }
            if args[1].is_nil() {
                let name = format!("={}: in load()", caller_location(lua));
                args[1] = Value::String(lua.create_string(name)?);
            }
            args[2] = Value::String(lua.create_string("t")?);
            load.call::<mlua::MultiValue>(mlua::MultiValue::from_iter(args))
        })?,
    )?;
    // Finalizers run with the instruction hook off, so a `__gc` that loops would escape the
    // time limit: metatables with a `__gc` field are refused. (Lua only marks a table for
    // finalization when its metatable has `__gc` as it is set.)
    let setmetatable: mlua::Function = globals.get("setmetatable")?;
    let guarded = shipped_chunk(lua, &GUARDED_SETMETATABLE)?.call::<mlua::Function>((
        setmetatable,
        globals.get::<mlua::Function>("rawget")?,
        globals.get::<mlua::Function>("type")?,
        globals.get::<mlua::Function>("error")?,
    ))?;
    globals.set("setmetatable", guarded)?;
    // `print` writes to stderr so that stdout stays clean for `--stats` and `derive`.
    globals.set(
        "print",
        lua.create_function(|_, args: mlua::Variadic<Value>| {
            let parts: Vec<String> = args.iter().map(display_value).collect();
            eprintln!("{}", parts.join("\t"));
            Ok(())
        })?,
    )?;
    lua.set_named_registry_value(LOADED_KEY, lua.create_table()?)?;
    globals.set("require", lua.create_function(require)?)?;
    pge.set(
        "load",
        lua.create_function(|lua, (path, overrides): (String, Option<Table>)| {
            load_script(lua, &path, overrides)
        })?,
    )?;
    Ok(())
}

fn display_value(v: &Value) -> String {
    match v {
        Value::String(s) => s.to_string_lossy(),
        Value::Nil => "nil".into(),
        Value::Boolean(b) => b.to_string(),
        Value::Integer(i) => i.to_string(),
        Value::Number(n) => n.to_string(),
        other => other
            .to_string()
            .unwrap_or_else(|_| other.type_name().to_string()),
    }
}

/// Runs `f` with the files of the session's engine (the file system without one).
pub(crate) fn with_files<R>(lua: &Lua, f: impl FnOnce(&dyn Files) -> R) -> R {
    match lua.app_data_ref::<EngineHandle>() {
        Some(engine) => f(engine.0.files()),
        None => f(&DiskFiles),
    }
}

/// The bytes of a file a script names, once resolved ([`resolve_path`]): read from the
/// engine's files (the file system, or memory in a browser).
pub fn read_file(lua: &Lua, path: &Path) -> std::io::Result<Vec<u8>> {
    with_files(lua, |files| files.read(path))
}

/// How a canonical path is shown: relative to the working folder when inside it
/// (`scripts/species/oak.lua`), else as it is; with `/` between folders.
pub fn shown_path(lua: &Lua, canonical: &Path) -> String {
    shown_from_cwd(lua, canonical)
        .to_string_lossy()
        .replace('\\', "/")
}

/// Runs a script file as a chunk named after its shown path; records it for reload.
pub(crate) fn exec_file(lua: &Lua, display: String, path: PathBuf) -> mlua::Result<Value> {
    let source = read_file(lua, &path).and_then(|bytes| {
        String::from_utf8(bytes)
            .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()))
    });
    let source = source.map_err(|e| {
        mlua::Error::external(Error::script(
            Location {
                file: display.clone(),
                line: None,
            },
            format!("cannot read script: {e}"),
        ))
    })?;
    exec_source(lua, display, path, source)
}

/// Runs `source` as the chunk of the file `path` (which need not exist: a script held by a
/// host), named after its shown path; records it for reload.
pub(crate) fn exec_source(
    lua: &Lua,
    display: String,
    path: PathBuf,
    source: String,
) -> mlua::Result<Value> {
    // Like `lua script.lua`, a first line starting with '#' (a shebang) is skipped.
    let source = if source.starts_with('#') {
        source
            .find('\n')
            .map_or(String::new(), |i| source[i..].to_string())
    } else {
        source
    };
    if let Some(mut st) = lua.app_data_mut::<SessionState>() {
        st.chunks.push(Chunk {
            display: display.clone(),
            path: path.clone(),
        });
        st.record_file(path);
    }
    lua.load(source)
        .set_name(format!("@{display}"))
        .set_mode(mlua::chunk::ChunkMode::Text)
        .call(())
}

/// The folder of the script that is calling (its shown path and its canonical path).
fn caller_dir(lua: &Lua) -> (PathBuf, PathBuf) {
    let loc = caller_location(lua);
    let st = lua.app_data_ref::<SessionState>();
    let chunk = st.as_ref().and_then(|s| s.chunk(&loc.file).cloned());
    match chunk {
        Some(c) => (
            Path::new(&c.display)
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_default(),
            c.path.parent().map(Path::to_path_buf).unwrap_or_default(),
        ),
        None => {
            let main = st.and_then(|s| s.main_dir.clone()).unwrap_or_default();
            (PathBuf::new(), main)
        }
    }
}

/// Lexically normalises `a/./b/../c` to `a/c` (for shown names only).
fn normalize(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    out.push("..");
                }
            }
            other => out.push(other),
        }
    }
    out
}

/// How to show a canonical path: relative to the working folder when inside it.
fn shown_from_cwd(lua: &Lua, dir: &Path) -> PathBuf {
    with_files(lua, |files| files.working_folder())
        .and_then(|cwd| dir.strip_prefix(cwd).ok().map(Path::to_path_buf))
        .unwrap_or_else(|| dir.to_path_buf())
}

fn is_allowed(lua: &Lua, canonical: &Path) -> bool {
    lua.app_data_ref::<SessionState>()
        .is_some_and(|s| s.roots.iter().any(|r| canonical.starts_with(r)))
        || state::library(lua).is_some_and(|l| canonical.starts_with(l))
}

/// Resolves `relative` against the calling script's folder: the shown path and the
/// canonical one, checked to be inside the allowed folders.
fn resolve(lua: &Lua, relative: &str, what: &str) -> mlua::Result<(String, PathBuf)> {
    let (shown_dir, real_dir) = caller_dir(lua);
    let rel = Path::new(relative);
    if rel.is_absolute() {
        return Err(script_error(
            lua,
            format!(
                "{what} '{relative}': absolute paths are not allowed; give a path relative to the script"
            ),
        ));
    }
    let candidate = real_dir.join(rel);
    let canonical = with_files(lua, |files| files.canonicalize(&candidate))
        .map_err(|e| script_error(lua, format!("{what} '{relative}': {e}")))?;
    if !is_allowed(lua, &canonical) {
        return Err(script_error(
            lua,
            format!("{what} '{relative}' is outside the script's folder and the library folder"),
        ));
    }
    let shown = normalize(&shown_dir.join(rel))
        .to_string_lossy()
        .replace('\\', "/");
    Ok((shown, canonical))
}

/// Resolves a path relative to the calling script, checks that it lies inside the script's
/// folder tree or the library folder, and records it as a dependency (for live reload).
pub fn resolve_path(lua: &Lua, relative: &str) -> mlua::Result<PathBuf> {
    let (_, canonical) = resolve(lua, relative, "file")?;
    if let Some(mut st) = lua.app_data_mut::<SessionState>() {
        st.record_file(canonical.clone());
    }
    Ok(canonical)
}

/// Where a script may write `relative`: a relative path without `..`, taken from the
/// output's folder when the session has one ([`crate::Session::set_output_folder`], `pge
/// run -o`), else from the main script's folder; missing folders on the way are created by
/// the caller. Never outside those folders: a symbolic link anywhere below the folder, at the
/// target included (a dangling one too), is refused. Write with [`write_inside`], which
/// also never follows a link planted after this check.
pub fn writable_path(lua: &Lua, relative: &str) -> mlua::Result<PathBuf> {
    if !with_files(lua, |files| files.writable()) {
        return Err(script_error(
            lua,
            format!("cannot write '{relative}': this host keeps no files a script writes"),
        ));
    }
    let p = Path::new(relative);
    if relative.is_empty()
        || p.is_absolute()
        || p.components()
            .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
    {
        return Err(script_error(
            lua,
            format!("cannot write '{relative}': give a relative path without '..'"),
        ));
    }
    let base = lua
        .app_data_ref::<SessionState>()
        .and_then(|s| s.output_dir.clone().or_else(|| s.main_dir.clone()));
    let Some(base) = base else {
        return Err(script_error(
            lua,
            format!("cannot write '{relative}': no script or output folder to write into"),
        ));
    };
    std::fs::create_dir_all(&base)
        .map_err(|e| script_error(lua, format!("cannot write '{relative}': {e}")))?;
    // Every step below the folder, read without following links: a link (to a folder or a
    // file, dangling or not) could lead out.
    let mut step = base.clone();
    for part in p.components() {
        let Component::Normal(name) = part else {
            continue;
        };
        step.push(name);
        match std::fs::symlink_metadata(&step) {
            Ok(meta) if meta.file_type().is_symlink() => {
                return Err(script_error(
                    lua,
                    format!(
                        "cannot write '{relative}': it leads outside the folder scripts write \
                         into through the symbolic link '{}'",
                        step.display()
                    ),
                ));
            }
            Ok(_) => {}
            Err(_) => break,
        }
    }
    Ok(base.join(p))
}

/// Writes `bytes` to `relative` in the folder scripts write into (checked by
/// [`writable_path`]; missing folders are created): into a new temporary file beside the
/// target, renamed over it. Nothing is half-written, and a link planted at the target is
/// replaced by the file, never followed.
pub fn write_inside(lua: &Lua, relative: &str, bytes: &[u8]) -> mlua::Result<PathBuf> {
    use std::io::Write;
    let target = writable_path(lua, relative)?;
    let fail =
        |e: &dyn std::fmt::Display| script_error(lua, format!("cannot write '{relative}': {e}"));
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| fail(&e))?;
    // The folders just made are checked again: a link may have been planted on the way.
    writable_path(lua, relative)?;
    let mut file = tempfile::Builder::new()
        .prefix(".pge-write-")
        .tempfile_in(&dir)
        .map_err(|e| fail(&e))?;
    file.write_all(bytes).map_err(|e| fail(&e))?;
    file.persist(&target).map_err(|e| fail(&e.error))?;
    Ok(target)
}

fn require(lua: &Lua, name: String) -> mlua::Result<Value> {
    let (shown, canonical) = find_module(lua, &name)?;
    let loaded: Table = lua.named_registry_value(LOADED_KEY)?;
    let key = canonical.to_string_lossy().to_string();
    match loaded.raw_get::<Value>(key.as_str())? {
        Value::Nil => {}
        Value::LightUserData(_) => {
            return Err(script_error(
                lua,
                format!("require '{name}': circular require"),
            ));
        }
        value => return Ok(value),
    }
    loaded.raw_set(
        key.as_str(),
        Value::LightUserData(mlua::LightUserData(std::ptr::null_mut())),
    )?;
    let result = exec_file(lua, shown, canonical);
    let value = match result {
        Ok(Value::Nil) => Value::Boolean(true),
        Ok(v) => v,
        Err(e) => {
            loaded.raw_set(key.as_str(), Value::Nil)?;
            return Err(e);
        }
    };
    loaded.raw_set(key.as_str(), value.clone())?;
    Ok(value)
}

/// Finds a module: a path with `/` relative to the calling script, or a dotted name looked
/// up in the caller's folder, the main script's folder and the library folder.
fn find_module(lua: &Lua, name: &str) -> mlua::Result<(String, PathBuf)> {
    if name.contains('/') || name.contains('\\') {
        let with_ext = if name.ends_with(".lua") {
            name.to_string()
        } else {
            format!("{name}.lua")
        };
        return resolve(lua, &with_ext, "require");
    }
    let rel = name.replace('.', "/");
    let (shown_dir, real_dir) = caller_dir(lua);
    let main = lua
        .app_data_ref::<SessionState>()
        .and_then(|s| s.main_dir.clone());
    let library = state::library(lua);
    let mut dirs = vec![(shown_dir, real_dir)];
    for d in [main, library].into_iter().flatten() {
        dirs.push((shown_from_cwd(lua, &d), d));
    }
    let mut looked = Vec::new();
    for (shown, real) in &dirs {
        for file in [format!("{rel}.lua"), format!("{rel}/init.lua")] {
            let candidate = real.join(&file);
            looked.push(candidate.display().to_string());
            if let Ok(canonical) = with_files(lua, |files| files.canonicalize(&candidate)) {
                if !is_allowed(lua, &canonical) {
                    continue;
                }
                let shown = normalize(&shown.join(&file))
                    .to_string_lossy()
                    .replace('\\', "/");
                return Ok((shown, canonical));
            }
        }
    }
    Err(script_error(
        lua,
        format!(
            "module '{name}' not found (looked for {})",
            looked.join(", ")
        ),
    ))
}

fn load_script(lua: &Lua, path: &str, overrides: Option<Table>) -> mlua::Result<Value> {
    let (shown, canonical) = resolve(lua, path, "pge.load")?;
    let location = caller_location(lua);
    params::push_scope(lua, &shown, overrides)?;
    let result = exec_file(lua, shown, canonical);
    let unused = params::pop_scope(lua);
    let value = result?;
    if let Err(message) = unused {
        return Err(mlua::Error::external(Error::script(
            location,
            format!("pge.load('{path}'): {message}"),
        )));
    }
    Ok(value)
}
