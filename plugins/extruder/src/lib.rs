//! The extrusion modeller of the PGE thesis (§3.4.4): [`Extruder`] sweeps a 2D shape along a
//! path, [`MatrixManipulator`] moves the path and the shape. [`ExtruderPlugin`] adds
//! `pge.Extruder{...}` and `pge.MatrixManipulator()` to scripts:
//!
//! ```lua
//! local e = pge.Extruder{ smooth = false, color = "#c8b89a" }
//! e:polygon(4, 1)                 -- or e:addPoint2(x, z) ...
//! local path = e:getPathMatrix()
//! e:extrude(2)                    -- a box 2 high
//! path:rotateZ(20)
//! e:getShapeMatrix():scale(0.5)
//! e:extrude(1)                    -- a bent, tapered continuation
//! return e                        -- anything with :model()
//! ```

mod extruder;
#[cfg(feature = "lua")]
mod lua;
mod matrix;
mod triangulate;
mod tube;

pub use extruder::{Extruder, ExtruderError, ExtruderOptions, MAX_SHAPE_POINTS, MAX_STATE_DEPTH};
pub use matrix::{MAX_STACK_DEPTH, MatrixError, MatrixManipulator};
pub use triangulate::{EAR_CLIPPING_MAX, triangulate};

#[cfg(feature = "lua")]
pub use lua::{LuaExtruder, LuaMatrixManipulator};

#[cfg(feature = "lua")]
/// Registers `pge.Extruder` and `pge.MatrixManipulator`.
#[derive(Clone, Copy, Debug, Default)]
pub struct ExtruderPlugin;

#[cfg(feature = "lua")]
impl pge_engine::Plugin for ExtruderPlugin {
    fn name(&self) -> &str {
        "extruder"
    }

    fn lazy_names(&self) -> &'static [&'static str] {
        &["Extruder", "MatrixManipulator"]
    }

    fn register(&self, lua: &mlua::Lua, pge: &mlua::Table) -> mlua::Result<()> {
        lua::register(lua, pge)
    }
}
