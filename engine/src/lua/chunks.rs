//! The engine's own Lua chunks (the ordered `pairs`, the guarded `setmetatable`, a plugin's
//! helpers), compiled once per process: every later session loads the compiled chunk
//! instead of parsing the source again (parsing was a third of the time a session took to
//! create); the few that every session runs are shipped compiled ([`ShippedChunk`]). Scripts
//! still load only text: the sandbox's `load` refuses binary chunks.

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

/// An engine chunk shipped compiled, for the few that every session runs (the guarded
/// `setmetatable`, the first-call `next` and `pairs`): `compiled` is what [`engine_chunk`]
/// keeps of `source` (its [`Function::dump`] with line information) on a 64-bit
/// little-endian host, loaded as it is so that a fresh process parses none of them (a
/// fifth of the first session's set-up). Where those bytes do not load (a Lua build or host
/// whose binary chunks differ: the header says so) the source is compiled as before. A test
/// checks the bytes are the source's on such a host, and writes them when asked.
pub(crate) struct ShippedChunk {
    /// The chunk's name in errors and tracebacks (`"=pge"`).
    pub(crate) name: &'static str,
    /// The chunk's source.
    pub(crate) source: &'static str,
    /// The source compiled, from `compiled/<file>`.
    pub(crate) compiled: &'static [u8],
    /// The file under `compiled/` that holds `compiled`.
    #[cfg_attr(not(test), allow(dead_code))]
    pub(crate) file: &'static str,
}

/// The function of `chunk`, loaded from its compiled bytes when this Lua takes them.
pub(crate) fn shipped_chunk(lua: &Lua, chunk: &ShippedChunk) -> mlua::Result<Function> {
    let loaded = lua
        .load(chunk.compiled)
        .set_name(chunk.name)
        .set_mode(ChunkMode::Binary)
        .into_function();
    match loaded {
        Ok(function) => Ok(function),
        Err(_) => engine_chunk(lua, chunk.name, chunk.source),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every chunk shipped compiled.
    fn shipped() -> [&'static ShippedChunk; 2] {
        [
            &super::super::sandbox::GUARDED_SETMETATABLE,
            &super::super::order::ON_FIRST_CALL,
        ]
    }

    #[test]
    fn the_shipped_chunks_are_their_sources_compiled() {
        // `PGE_WRITE_COMPILED_CHUNKS=1 cargo test -p pge-engine shipped` writes them after a
        // change of a source (or of the Lua it is compiled by).
        let write = std::env::var_os("PGE_WRITE_COMPILED_CHUNKS").is_some();
        for chunk in shipped() {
            let lua = Lua::new();
            let dumped = lua
                .load(chunk.source)
                .set_name(chunk.name)
                .set_mode(ChunkMode::Text)
                .into_function()
                .expect("compiles")
                .dump(false);
            if write {
                let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("src/lua/compiled")
                    .join(chunk.file);
                std::fs::write(&path, &dumped).expect("written");
                continue;
            }
            if cfg!(all(target_pointer_width = "64", target_endian = "little")) {
                assert!(
                    dumped == chunk.compiled,
                    "compiled/{} is not its source compiled: run the tests with \
                     PGE_WRITE_COMPILED_CHUNKS=1",
                    chunk.file
                );
            }
            // Loaded from the bytes or compiled, the same function.
            assert!(shipped_chunk(&lua, chunk).expect("loads").dump(false) == dumped);
        }
    }

    #[test]
    fn a_shipped_chunk_whose_bytes_do_not_load_is_compiled() {
        let chunk = ShippedChunk {
            name: "=test",
            source: "return 1 + 2",
            compiled: b"\x1bLua\x00 not a chunk of this Lua",
            file: "",
        };
        let lua = Lua::new();
        let f = shipped_chunk(&lua, &chunk).expect("compiled from the source");
        assert_eq!(f.call::<i64>(()).expect("runs"), 3);
    }

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
