//! Metaballs and marching cubes, the organic modeller of the PGE thesis (§3.4.4): a
//! [`Metaballs`] field of charged particles and [`MarchingCubes`], which extracts its
//! isosurface as a closed mesh with normals from the field's gradient. [`MetaballsPlugin`]
//! adds them to scripts:
//!
//! ```lua
//! local meta = pge.Metaballs{ radius = 1 }         -- default radius of influence
//! local mc = pge.MarchingCubes(meta, { resolution = 64, iso = 0.5 })
//! meta:addParticle({0, 0, 0}, 1)                   -- position, charge [, radius]
//! meta:addParticle({0.8, 0, 0}, 1, 0.7)
//! print(meta:calc({0.4, 0, 0}), meta:gradient({0.4, 0, 0}))
//! return mc                                        -- its :model() is the surface
//! ```

mod field;
mod lua;
mod march;
pub mod table;

pub use field::{FieldError, MAX_PARTICLES, Metaballs, Particle};
pub use lua::{LuaMarchingCubes, LuaMetaballs};
pub use march::{MAX_RESOLUTION, MarchError, MarchOptions, MarchStats, MarchingCubes};

/// Registers `pge.Metaballs` and `pge.MarchingCubes`.
#[derive(Clone, Copy, Debug, Default)]
pub struct MetaballsPlugin;

impl pge_engine::Plugin for MetaballsPlugin {
    fn name(&self) -> &str {
        "metaballs"
    }

    fn register(&self, lua: &mlua::Lua, pge: &mlua::Table) -> mlua::Result<()> {
        pge_engine::lua::register_model_maker(lua, lua::model_of);
        lua::register(lua, pge)
    }
}
