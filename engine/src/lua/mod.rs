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
mod held;
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
mod std_math;

pub use algorithm::{AlgorithmHandle, ScriptAlgorithm, algorithm_from};
pub use args::{conversion_message, finite_f32, finite_number, no_new_fields, vec3_arg};
pub use chunks::engine_chunk;
pub use errors::{caller_location, engine_error_of, error_message, script_error, to_engine_error};
pub(crate) use lazy::register_lazily;
pub use math::{LuaMat4, LuaQuat, LuaVec3};
pub use model::{LuaMesh, LuaModel, is_model_or_mesh, material_from_table, to_model, to_model_in};
pub use options::{Bounds, KeyStyle, Options};
pub use order::{key_order, sorted_keys, sorted_pairs};
pub use random::{LuaRng, current_uniform, swap_rng};
pub(crate) use sandbox::exec_file as sandbox_exec;
pub(crate) use sandbox::exec_source as sandbox_exec_source;
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

/// The main script of the session of `lua` (its canonical path, the first file the session
/// read), once one runs.
#[must_use]
pub fn main_script(lua: &mlua::Lua) -> Option<std::path::PathBuf> {
    lua.app_data_ref::<state::SessionState>()
        .and_then(|s| s.loaded_files.first().cloned())
}

/// The folder the scripts of the session of `lua` write into (`img:save`): the run's output
/// folder when it has one, else the main script's folder once it runs.
#[must_use]
pub fn write_folder(lua: &mlua::Lua) -> Option<std::path::PathBuf> {
    lua.app_data_ref::<state::SessionState>()
        .and_then(|s| s.output_dir.clone().or_else(|| s.main_dir.clone()))
}

/// The bytes the run's memory budget has left (`--memory-limit` less what the run's Lua
/// states and kept buffers hold now): what one object's Rust-side buffers may take at
/// most, so that plugins refuse an allocation that would exceed it (an image, a mesh being
/// extruded, a marching-cubes grid). [`charge`] keeps a buffer in the budget.
#[must_use]
pub fn memory_budget(lua: &mlua::Lua) -> usize {
    sync_lua_memory(lua);
    lua.app_data_ref::<state::SessionState>()
        .map_or(crate::Limits::default().memory, |s| {
            s.ctx.budget.available()
        })
}

/// Brings the Lua state's use up to date in the run's budget.
fn sync_lua_memory(lua: &mlua::Lua) {
    let used = lua.used_memory();
    if let Some(mut s) = lua.app_data_mut::<state::SessionState>() {
        s.sync_memory(used);
    }
}

/// Charges the encoded bytes of `texture` (a value the script now holds, such as
/// `image:texture()`'s) to the run's budget for as long as the texture lives, once per Lua
/// state: a material or model that holds the same texture later is not charged it again.
pub fn charge_texture(
    lua: &mlua::Lua,
    texture: &std::sync::Arc<crate::geometry::Texture>,
) -> mlua::Result<()> {
    held::charge_texture(lua, texture)
}

/// Charges `bytes` that a value the script keeps holds on the Rust side (a skeleton's
/// nodes, a model's meshes and textures) to the run's budget, for as long as `value` lives:
/// the charge is its user value, given back when Lua collects it. When the budget is
/// short, Lua's garbage is collected first (it may hold charged values nothing uses); then
/// an [`crate::Error::MemoryLimit`] at the calling line, `what` naming the value.
pub fn charge(
    lua: &mlua::Lua,
    value: &mlua::AnyUserData,
    bytes: usize,
    what: &str,
) -> mlua::Result<()> {
    if bytes == 0 {
        return Ok(());
    }
    let budget = run_context(lua).budget;
    let attempt = || {
        sync_lua_memory(lua);
        budget.charge(bytes, &caller_location(lua), || {
            format!("{what} holds {} MiB", bytes.div_ceil(1 << 20))
        })
    };
    let charge = match attempt() {
        Ok(c) => c,
        Err(_) => {
            lua.gc_collect()?;
            lua.gc_collect()?;
            attempt().map_err(mlua::Error::external)?
        }
    };
    value.set_user_value(Held { _charge: charge })
}

/// Holds `bytes` for `value` instead of what [`charge`] charged it (its buffers grew or
/// shrank), with the same garbage collection and error when the budget is short.
pub fn recharge(
    lua: &mlua::Lua,
    value: &mlua::AnyUserData,
    bytes: usize,
    what: &str,
) -> mlua::Result<()> {
    let held = match value.user_value::<Option<mlua::AnyUserData>>()? {
        Some(held) if held.is::<Held>() => held,
        _ => return charge(lua, value, bytes, what),
    };
    let attempt = || -> mlua::Result<crate::Result<()>> {
        sync_lua_memory(lua);
        let mut held = held.borrow_mut::<Held>()?;
        Ok(held._charge.resize(bytes, &caller_location(lua), || {
            format!("{what} holds {} MiB", bytes.div_ceil(1 << 20))
        }))
    };
    if attempt()?.is_err() {
        lua.gc_collect()?;
        lua.gc_collect()?;
        attempt()?.map_err(mlua::Error::external)?;
    }
    Ok(())
}

/// A [`crate::Charge`] kept as a value's user value.
struct Held {
    _charge: crate::Charge,
}
impl mlua::UserData for Held {}

/// Registers the support library into the `pge` table.
pub(crate) fn register_support(lua: &mlua::Lua, pge: &mlua::Table) -> mlua::Result<()> {
    sandbox::register(lua, pge)?;
    order::register(lua)?;
    params::register(lua, pge)?;
    random::register(lua, pge)?;
    math::register(lua, pge)?;
    std_math::register(lua)?;
    noise::register(lua, pge)?;
    model::register(lua, pge)?;
    algorithm::register(lua, pge)?;
    skeleton::register(lua, pge)?;
    Ok(())
}
