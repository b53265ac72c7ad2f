//! The Lua side of the engine: the sandbox, the support library (`pge.*`) and the helpers
//! plugins use to bind their objects.
//!
//! Plugins read option tables with [`Options`] (one wording for every mistake), convert
//! vectors with [`LuaVec3`], report other mistakes with [`script_error`] (a typed error that
//! points at the script's file and line), hand algorithms back as [`AlgorithmHandle`]s and
//! resolve files with [`resolve_path`].

mod algorithm;
mod args;
mod chunks;
mod errors;
mod lazy;
mod math;
mod model;
mod noise;
pub mod options;
mod order;
pub mod params;
pub(crate) mod random;
mod sandbox;
pub mod services;
mod skeleton;
pub(crate) mod state;

pub use algorithm::{AlgorithmHandle, ScriptAlgorithm, algorithm_from};
pub use args::{conversion_message, finite_f32, finite_number, no_new_fields, vec3_arg};
pub use chunks::engine_chunk;
pub use errors::{caller_location, engine_error_of, error_message, script_error, to_engine_error};
pub(crate) use lazy::register_lazily;
pub use math::{LuaMat4, LuaQuat, LuaVec3};
pub use model::{LuaMesh, LuaModel, material_from_table, to_model, to_model_in};
pub use options::{Bounds, KeyStyle, Options};
pub use order::{key_order, sorted_keys, sorted_pairs};
pub use random::{LuaRng, current_uniform, swap_rng};
pub(crate) use sandbox::exec_file as sandbox_exec;
pub(crate) use sandbox::with_files;
pub use sandbox::{read_file, resolve_path, shown_path, writable_path, write_inside};
pub use services::{
    DefaultInterpreter, InstanceFactory, ModelMaker, ReadOnlyPhase, check_mutable,
    default_instance, interpreters, read_only_phase, register_interpreter, register_model_maker,
    set_default_instance,
};
pub use skeleton::{LuaSkeleton, skeleton_from_value, skeleton_of_model};

use crate::RunContext;

/// The run context of the session this Lua state belongs to (seed, `--steps`, deadline,
/// module cap, cancel flag): what a method called from a script (`turtle:model()`,
/// `algorithm:model()`) runs with. Code that is handed a [`RunContext`] (an algorithm's
/// `init`, `step`, `finish`) uses that one instead.
#[must_use]
pub fn run_context(lua: &mlua::Lua) -> RunContext {
    lua.app_data_ref::<state::SessionState>()
        .map(|s| s.ctx.clone())
        .unwrap_or_default()
}

/// The session's memory budget in bytes: the memory limit of its Lua state (what
/// `--memory-limit` set), and what one object's Rust-side buffers may take at most, so that
/// plugins refuse an allocation that would exceed it (an image, a mesh being extruded, a
/// marching-cubes grid).
#[must_use]
pub fn memory_budget(lua: &mlua::Lua) -> usize {
    lua.app_data_ref::<state::SessionState>()
        .map_or(crate::Limits::default().memory, |s| s.memory_limit)
}

/// Registers the support library into the `pge` table.
pub(crate) fn register_support(lua: &mlua::Lua, pge: &mlua::Table) -> mlua::Result<()> {
    sandbox::register(lua, pge)?;
    order::register(lua)?;
    params::register(lua, pge)?;
    random::register(lua, pge)?;
    math::register(lua, pge)?;
    noise::register(lua, pge)?;
    model::register(lua, pge)?;
    algorithm::register(lua, pge)?;
    skeleton::register(lua, pge)?;
    Ok(())
}
