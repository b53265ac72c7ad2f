//! The engine's own Lua chunks (the ordered `pairs`, the guarded `setmetatable`, a plugin's
//! helpers), compiled once per process: every later session loads the compiled chunk
//! instead of parsing the source again (parsing was a third of the time a session took to
//! create). Scripts still load only text: the sandbox's `load` refuses binary chunks.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use mlua::chunk::ChunkMode;
use mlua::{Function, Lua};

/// Compiled chunks by their source text.
type Cache = Mutex<HashMap<&'static str, Arc<[u8]>>>;

fn cache() -> &'static Cache {
    static CACHE: OnceLock<Cache> = OnceLock::new();
    CACHE.get_or_init(Cache::default)
}

/// The function of `source`, a chunk of the engine or of a plugin named `name` in errors
/// and tracebacks (`"=pge"`), as `lua.load(source).set_name(name)` makes it, but compiled
/// only the first time the process asks for it: the compiled chunk (with its line
/// information) is kept and loaded into every later state.
pub fn engine_chunk(lua: &Lua, name: &'static str, source: &'static str) -> mlua::Result<Function> {
    let compiled = cache().lock().ok().and_then(|c| c.get(source).cloned());
    if let Some(bytes) = compiled {
        return lua
            .load(&bytes[..])
            .set_name(name)
            .set_mode(ChunkMode::Binary)
            .into_function();
    }
    let function = lua
        .load(source)
        .set_name(name)
        .set_mode(ChunkMode::Text)
        .into_function()?;
    if let Ok(mut c) = cache().lock() {
        c.insert(source, function.dump(false).into());
    }
    Ok(function)
}

#[cfg(test)]
mod tests {
    use super::*;

    const CHUNK: &str = "local a = ...\nreturn function(b)\n  if b == nil then error('no b', 2) end\n  if b == 0 then error('zero') end\n  return a + b\nend";

    #[test]
    fn a_chunk_loaded_again_behaves_as_the_source_and_keeps_its_lines() {
        for _ in 0..2 {
            let lua = Lua::new();
            let make = engine_chunk(&lua, "=test", CHUNK).expect("loads");
            let add: Function = make.call(2).expect("runs");
            assert_eq!(add.call::<i64>(3).expect("adds"), 5);
            // The inner function's error points at its caller, whose line is known.
            let caller = lua
                .load("local f = ...\nreturn pcall(function()\n  local r = f()\n  return r\nend)")
                .set_name("=caller");
            let (ok, message): (bool, String) = caller.call(add.clone()).expect("calls");
            assert!(!ok);
            assert_eq!(message, "caller:3: no b");
            // Its own errors keep the chunk's name and line.
            let e = add.call::<i64>(0).expect_err("zero");
            assert!(e.to_string().contains("test:4: zero"), "{e}");
        }
        assert!(
            cache().lock().expect("cache").contains_key(CHUNK),
            "kept after the first state"
        );
    }
}
