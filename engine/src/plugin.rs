//! Plugins: how functionality reaches the `pge` table of every session.

use mlua::{Lua, Table};

use crate::Engine;

/// A set of constructors and functions added to the `pge` Lua table.
///
/// # Lifecycle
/// Plugins are added to an [`EngineBuilder`](crate::EngineBuilder) once; the engine calls
/// [`Plugin::register`] for every new session (one Lua state), after the support library is
/// in place and before the script runs, in the order the plugins were added. A plugin may
/// therefore rely on `pge.vec3`, `pge.mesh` and the other support functions, and on plugins
/// added before it. An error from `register` aborts the creation of the session.
///
/// Plugins are shared by every thread that creates sessions, hence `Send + Sync`; per-session
/// state belongs in the Lua state (userdata, app data), not in the plugin. A plugin that runs
/// other scripts in sessions of their own (a forest growing each species variant) is handed
/// the engine that creates the session by [`Plugin::register_in`], so the sandbox and the
/// limits hold there too.
///
/// # Example
/// ```
/// use pge_engine::{Engine, Plugin};
///
/// struct Greeter;
/// impl Plugin for Greeter {
///     fn register(&self, lua: &mlua::Lua, pge: &mlua::Table) -> mlua::Result<()> {
///         pge.set("greet", lua.create_function(|_, name: String| Ok(format!("hi {name}")))?)
///     }
/// }
///
/// let engine = Engine::builder().plugin(Greeter).build().unwrap();
/// let session = engine.session(Default::default()).unwrap();
/// let s: String = session.eval("return pge.greet('oak')").unwrap();
/// assert_eq!(s, "hi oak");
/// ```
pub trait Plugin: Send + Sync + 'static {
    /// A unique name; the type name by default.
    fn name(&self) -> &str {
        std::any::type_name::<Self>()
    }

    /// Adds this plugin's functions and constructors to the `pge` table of a new session.
    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()>;

    /// What the engine calls: [`register`](Plugin::register) for a session that `engine`
    /// creates. A plugin that opens sessions of its own overrides it and keeps `engine`
    /// (same plugins, limits and library) in the functions it registers; `register` is
    /// then what a Lua state the engine did not create gets. The default calls `register`.
    fn register_in(&self, engine: &Engine, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        let _ = engine;
        self.register(lua, pge)
    }

    /// The names [`register`](Plugin::register) sets in the `pge` table, for a plugin whose
    /// registration does nothing else a script could see before it touches one of them (no
    /// session services, no globals). The session then registers the plugin when a script
    /// first reads or assigns `pge.NAME` for one of them, or iterates `pge` with `pairs`:
    /// a script pays only for the plugins it uses. Until then `rawget(pge, NAME)` is nil and
    /// `pge` has a metatable. Empty (the default): registered with every session, in order.
    fn lazy_names(&self) -> &'static [&'static str] {
        &[]
    }
}
