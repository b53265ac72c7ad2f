//! Plugins registered on first use: the `pge` table's metatable registers a plugin that
//! declares [`Plugin::lazy_names`] when a script first reads or assigns one of its names,
//! or iterates `pge` (then every plugin still waiting), and goes away once none waits.

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::Arc;

use mlua::{Function, Lua, Table, Value};

use crate::{Engine, Error, Plugin};

/// The plugins not registered yet, and the engine they are registered for.
struct Lazy {
    engine: Engine,
    plugins: RefCell<Vec<Arc<dyn Plugin>>>,
}

type Waiting = Rc<Lazy>;

/// Registers `plugin` into `pge` for `engine`, its errors naming it.
fn register(lua: &Lua, pge: &Table, engine: &Engine, plugin: &Arc<dyn Plugin>) -> mlua::Result<()> {
    plugin.register_in(engine, lua, pge).map_err(|e| {
        mlua::Error::external(Error::Plugin {
            plugin: plugin.name().to_string(),
            message: e.to_string(),
        })
    })
}

/// Removes the metatable once no plugin waits (`pge` is then as an eager session's).
fn done_if_empty(pge: &Table, waiting: &Waiting) -> mlua::Result<()> {
    if waiting.plugins.borrow().is_empty() {
        pge.set_metatable(None)?;
    }
    Ok(())
}

/// Registers the waiting plugin that owns `key`, if any.
fn register_owner(lua: &Lua, pge: &Table, waiting: &Waiting, key: &Value) -> mlua::Result<()> {
    let Value::String(key) = key else {
        return Ok(());
    };
    let owner = {
        let mut w = waiting.plugins.borrow_mut();
        let key = key.as_bytes();
        let i = w
            .iter()
            .position(|p| p.lazy_names().iter().any(|n| n.as_bytes() == &key[..]));
        i.map(|i| w.remove(i))
    };
    if let Some(plugin) = owner {
        register(lua, pge, &waiting.engine, &plugin)?;
        done_if_empty(pge, waiting)?;
    }
    Ok(())
}

/// Gives `pge` the metatable that registers the plugins of `lazy` on first use, for the
/// session `engine` creates.
pub(crate) fn register_lazily(
    lua: &Lua,
    pge: &Table,
    engine: &Engine,
    lazy: Vec<Arc<dyn Plugin>>,
) -> mlua::Result<()> {
    if lazy.is_empty() {
        return Ok(());
    }
    let waiting: Waiting = Rc::new(Lazy {
        engine: engine.clone(),
        plugins: RefCell::new(lazy),
    });
    let meta = lua.create_table()?;
    let w = waiting.clone();
    meta.raw_set(
        "__index",
        lua.create_function(move |lua, (pge, key): (Table, Value)| {
            register_owner(lua, &pge, &w, &key)?;
            pge.raw_get::<Value>(key)
        })?,
    )?;
    let w = waiting.clone();
    meta.raw_set(
        "__newindex",
        lua.create_function(move |lua, (pge, key, value): (Table, Value, Value)| {
            register_owner(lua, &pge, &w, &key)?;
            pge.raw_set(key, value)
        })?,
    )?;
    // `pairs(pge)` sees every plugin's names, and returns the global `next` as it would
    // without a metatable.
    let next: Function = lua.globals().get("next")?;
    meta.raw_set(
        "__pairs",
        lua.create_function(move |lua, pge: Table| {
            let all: Vec<_> = waiting.plugins.borrow_mut().drain(..).collect();
            for plugin in &all {
                register(lua, &pge, &waiting.engine, plugin)?;
            }
            done_if_empty(&pge, &waiting)?;
            Ok((next.clone(), pge, Value::Nil))
        })?,
    )?;
    pge.set_metatable(Some(meta))
}

#[cfg(test)]
mod tests {
    use crate::{Engine, Plugin, SessionOptions};

    /// Registers two functions, counting its registrations in a global.
    struct Pair;
    impl Plugin for Pair {
        fn register(&self, lua: &mlua::Lua, pge: &mlua::Table) -> mlua::Result<()> {
            let n: i64 = lua.globals().get::<Option<i64>>("registered")?.unwrap_or(0);
            lua.globals().set("registered", n + 1)?;
            pge.set("one", lua.create_function(|_, ()| Ok(1))?)?;
            pge.set("two", lua.create_function(|_, ()| Ok(2))?)
        }
        fn lazy_names(&self) -> &'static [&'static str] {
            &["one", "two"]
        }
    }

    fn session() -> crate::Session {
        Engine::builder()
            .plugin(Pair)
            .build()
            .expect("engine")
            .session(SessionOptions::default())
            .expect("session")
    }

    #[test]
    fn a_lazy_plugin_is_registered_once_at_its_first_use() {
        let s = session();
        let before: (Option<i64>, bool) = s
            .eval("return registered, rawget(pge, 'one') == nil")
            .expect("runs");
        assert_eq!(before, (None, true));
        let (a, b, n, meta): (i64, i64, i64, bool) = s
            .eval("return pge.two(), pge.one(), registered, getmetatable(pge) == nil")
            .expect("runs");
        assert_eq!((a, b, n, meta), (2, 1, 1, true));
        // Other names read as nil, as before.
        assert!(s.eval::<bool>("return pge.three == nil").expect("runs"));
    }

    #[test]
    fn an_assignment_comes_after_the_registration() {
        let s = session();
        let (one, two, n): (Option<i64>, i64, i64) = s
            .eval("pge.one = nil\nreturn pge.one, pge.two(), registered")
            .expect("runs");
        assert_eq!((one, two, n), (None, 2, 1));
        let s = session();
        let v: i64 = s
            .eval("pge.two = function() return 22 end\nreturn pge.two() + pge.one()")
            .expect("runs");
        assert_eq!(v, 23);
    }

    #[test]
    fn pairs_sees_every_name_in_order() {
        let s = session();
        let names: String = s
            .eval(
                "local t = {}\nfor k in pairs(pge) do t[#t + 1] = k end\n\
                 return table.concat(t, ',')",
            )
            .expect("runs");
        assert!(
            names.contains("one,params") || names.contains(",one,"),
            "{names}"
        );
        assert!(names.contains("two"), "{names}");
        let sorted: bool = s
            .eval(
                "local prev = ''\nfor k in pairs(pge) do\n  if k < prev then return false end\n  prev = k\nend\nreturn registered == 1 and select(1, pairs(pge)) == next",
            )
            .expect("runs");
        assert!(sorted);
    }
}
