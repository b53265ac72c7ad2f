//! The Lua side of the engine: the sandbox, the support library (`pge.*`) and the helpers
//! plugins use to bind their objects.
//!
//! Plugins read option tables with [`Options`] (one wording for every mistake), convert
//! vectors with [`LuaVec3`], report other mistakes with [`script_error`] (a typed error that
//! points at the script's file and line), hand algorithms back as [`AlgorithmHandle`]s and
//! resolve files with [`resolve_path`].

mod algorithm;
mod errors;
mod math;
mod model;
mod noise;
pub mod options;
pub mod params;
pub(crate) mod random;
mod sandbox;
mod skeleton;
pub(crate) mod state;

pub use algorithm::{AlgorithmHandle, ScriptAlgorithm, algorithm_from};
pub use errors::{caller_location, engine_error_of, error_message, script_error, to_engine_error};
pub use math::{LuaMat4, LuaQuat, LuaVec3};
pub use model::{LuaMesh, LuaModel, material_from_table, to_model};
pub use options::{Bounds, KeyStyle, Options};
pub use random::{LuaRng, swap_rng, uniform};
pub(crate) use sandbox::exec_file as sandbox_exec;
pub use sandbox::{resolve_path, writable_path};
pub use skeleton::{LuaSkeleton, skeleton_from_value, skeleton_of_model};

use crate::RunContext;

/// The run context of the session this Lua state belongs to (seed, `--steps`, deadline,
/// module cap, cancel flag).
#[must_use]
pub fn run_context(lua: &mlua::Lua) -> RunContext {
    lua.app_data_ref::<state::SessionState>()
        .map(|s| s.ctx.clone())
        .unwrap_or_default()
}

/// The memory limit of the session's Lua state in bytes (what `--memory-limit` set), so that
/// plugins can refuse a Rust-side allocation that would exceed it.
#[must_use]
pub fn memory_limit(lua: &mlua::Lua) -> usize {
    lua.app_data_ref::<state::SessionState>()
        .map_or(crate::Limits::default().memory, |s| s.memory_limit)
}

/// A finite number from a script value, or a `FILE:LINE:` error that names `what` (the
/// method and argument) and says what was wrong.
pub fn finite_number(lua: &mlua::Lua, v: &mlua::Value, what: &str) -> mlua::Result<f64> {
    let x = match v {
        mlua::Value::Integer(i) => *i as f64,
        mlua::Value::Number(n) => *n,
        other => {
            return Err(script_error(
                lua,
                format!("{what}: expected a number, got {}", other.type_name()),
            ));
        }
    };
    if x.is_finite() {
        Ok(x)
    } else {
        Err(script_error(
            lua,
            format!("{what}: the number is NaN or infinite"),
        ))
    }
}

/// Registers the support library into the `pge` table.
pub(crate) fn register_support(lua: &mlua::Lua, pge: &mlua::Table) -> mlua::Result<()> {
    sandbox::register(lua, pge)?;
    params::register(lua, pge)?;
    random::register(lua, pge)?;
    math::register(lua, pge)?;
    noise::register(lua, pge)?;
    model::register(lua, pge)?;
    algorithm::register(lua, pge)?;
    skeleton::register(lua, pge)?;
    Ok(())
}
