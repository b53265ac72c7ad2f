//! PGE's turtle: the ABOP turtle commands in 3D (`F f + - & ^ \ / | [ ] ! ' $ ~`) with
//! tropism, width and colour, recording a branch [`Skeleton`](pge_engine::geometry::Skeleton)
//! that the tree mesher (`pge-tree`) turns into bark and leaves.
//!
//! In Lua, `pge.turtle{ angle = 25, width = 0.2 }` is a modeller object with methods named
//! after the commands (`forward`, `turn`, `push`, ... `model`), and it is the default instance
//! of an L-system: modules without an IRule are interpreted by it.
//!
//! ```
//! use pge_turtle::{Turtle, TurtleOptions};
//!
//! let mut t = Turtle::new(TurtleOptions { angle: 25.0, ..TurtleOptions::default() });
//! for c in ["F", "[", "+", "F", "]", "F"] {
//!     t.command(c, &[]).unwrap();
//! }
//! let skeleton = &t.skeletons()[0].1;
//! assert_eq!(skeleton.len(), 4);
//! assert_eq!(skeleton.tips().len(), 2);
//! ```

mod lua;
mod turtle;

use mlua::{Lua, Table, Value};
use pge_engine::Plugin;

pub use lua::LuaTurtle;
pub use turtle::{State, Turtle, TurtleError, TurtleOptions};

/// The `pge.turtle` plugin; it also makes turtles interpret L-system modules by default.
#[derive(Clone, Copy, Debug, Default)]
pub struct TurtlePlugin;

impl Plugin for TurtlePlugin {
    fn name(&self) -> &str {
        "turtle"
    }

    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        // Engine services: turtles interpret L-system modules, are the default instance of
        // an L-system, and are modelled with the run context of the algorithm that grew them.
        pge_engine::lua::register_interpreter(lua, lua::interpret);
        pge_engine::lua::set_default_instance(lua, |lua| {
            lua.create_userdata(LuaTurtle::new(lua, Value::Nil)?)
                .map(Value::UserData)
        });
        pge_engine::lua::register_model_maker(lua, lua::model_of);
        pge.set(
            "turtle",
            lua.create_function(|lua, options: Value| LuaTurtle::new(lua, options))?,
        )
    }
}
