//! The Lua side: `pge.SpaceColonization{...}` ([`colonization`]) and the `pge.shape.*`
//! constructors ([`shapes`]). A thin adapter: options are read with the engine's
//! [`Options`](pge_engine::lua::Options) reader (errors at the calling line name the option
//! and what it needs) and handed as plain Rust values to
//! [`SpaceColonization`](crate::SpaceColonization) and [`Shape`](crate::Shape).

mod colonization;
mod shapes;

use mlua::{Lua, Table, Value};
use pge_engine::Plugin;

pub use shapes::LuaShape;

/// Adds `pge.SpaceColonization` and `pge.shape` (sphere, ellipsoid, box, capsule, cone,
/// cylinder, revolve, mesh, union, difference, predicate) to every session.
#[derive(Clone, Copy, Debug, Default)]
pub struct SpaceColonizationPlugin;

impl Plugin for SpaceColonizationPlugin {
    fn name(&self) -> &str {
        "spacecol"
    }

    fn lazy_names(&self) -> &'static [&'static str] {
        &["SpaceColonization", "shape"]
    }

    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        pge.set(
            "SpaceColonization",
            lua.create_function(|lua, v: Value| colonization::new_colonization(lua, v))?,
        )?;
        pge.set("shape", shapes::shape_table(lua)?)
    }
}
