//! Session services that plugins share through the engine instead of through each other:
//! the read-only phase of rewriting rules, the default interpreters and the default instance
//! of L-systems, and the models of host objects.
//!
//! The session creates an empty registry before the plugins register; a plugin fills it from
//! its [`Plugin::register`](crate::Plugin::register) (the turtle adds its interpreter, its
//! default instance and its model), and another plugin reads it (the L-system interprets
//! modules with the registered interpreters). Nothing here is reachable from scripts: a
//! script that redefines `pge.turtle` or `pge.random` does not change what the engine uses.

use std::cell::RefCell;
use std::rc::Rc;

use mlua::{AnyUserData, Lua, Value};

use super::errors::script_error;
use crate::RunContext;
use crate::geometry::Model;

/// Interprets one module for an instance it knows (a turtle): returns `Ok(false)` when the
/// instance is not of its type or the module is not one of its commands.
pub type DefaultInterpreter = fn(&Lua, &AnyUserData, &str, &[f64]) -> mlua::Result<bool>;

/// Makes the default instance of an L-system (`this` when the script gave no
/// `createInstance`).
pub type InstanceFactory = fn(&Lua) -> mlua::Result<Value>;

/// The model of a host object, built with the run context of the caller: `Ok(None)` when
/// the object is not of its type.
pub type ModelMaker = fn(&Lua, &AnyUserData, &RunContext) -> mlua::Result<Option<Model>>;

/// The rewriting rule running now, if any: while it is set, `this` and the global table are
/// read-only and [`check_mutable`] refuses changes. Cloning shares the same phase.
#[derive(Clone, Debug, Default)]
pub struct ReadOnlyPhase(Rc<RefCell<Option<Rc<str>>>>);

impl ReadOnlyPhase {
    /// Enters the phase for rewriting rule `rule` (its left side, named in errors).
    #[inline]
    pub fn enter(&self, rule: Rc<str>) {
        *self.0.borrow_mut() = Some(rule);
    }

    /// Leaves the phase.
    #[inline]
    pub fn leave(&self) {
        *self.0.borrow_mut() = None;
    }

    /// The rule running now, if any.
    #[must_use]
    #[inline]
    pub fn rule(&self) -> Option<Rc<str>> {
        self.0.borrow().clone()
    }
}

/// The registry of one session.
#[derive(Default)]
pub(crate) struct Services {
    read_only: ReadOnlyPhase,
    interpreters: Vec<DefaultInterpreter>,
    default_instance: Option<InstanceFactory>,
    model_makers: Vec<ModelMaker>,
}

fn with<R>(lua: &Lua, f: impl FnOnce(&mut Services) -> R) -> R {
    if lua.app_data_ref::<Services>().is_none() {
        lua.set_app_data(Services::default());
    }
    match lua.app_data_mut::<Services>() {
        Some(mut s) => f(&mut s),
        None => f(&mut Services::default()),
    }
}

/// The session's read-only phase (shared: entering it through one handle is seen by all).
#[must_use]
pub fn read_only_phase(lua: &Lua) -> ReadOnlyPhase {
    with(lua, |s| s.read_only.clone())
}

/// The error a host object's mutating method raises while a rewriting rule (RRule) runs:
/// during derivation `this` and the global table are read-only. `what` names the method
/// (`"turtle:forward"`). Call it at the start of every method that changes the object.
pub fn check_mutable(lua: &Lua, what: &str) -> mlua::Result<()> {
    match read_only_phase(lua).rule() {
        Some(rule) => Err(script_error(
            lua,
            format!(
                "RRule '{rule}': {what} is not allowed: `this` and the global table are \
                 read-only during rewriting rules (change them in an IRule)"
            ),
        )),
        None => Ok(()),
    }
}

/// Adds a default interpretation of L-system modules. Interpreters are tried in the order
/// they were added; adding one twice has no effect.
pub fn register_interpreter(lua: &Lua, interpreter: DefaultInterpreter) {
    with(lua, |s| {
        if !s.interpreters.contains(&interpreter) {
            s.interpreters.push(interpreter);
        }
    });
}

/// The default interpreters, in the order they were added.
#[must_use]
pub fn interpreters(lua: &Lua) -> Vec<DefaultInterpreter> {
    with(lua, |s| s.interpreters.clone())
}

/// Sets the maker of the L-systems' default instance (the last plugin to set it wins).
pub fn set_default_instance(lua: &Lua, factory: InstanceFactory) {
    with(lua, |s| s.default_instance = Some(factory));
}

/// A new default instance, or `None` when no plugin provides one.
pub fn default_instance(lua: &Lua) -> mlua::Result<Option<Value>> {
    match with(lua, |s| s.default_instance) {
        Some(f) => f(lua).map(Some),
        None => Ok(None),
    }
}

/// Adds a maker of models for a kind of host object (tried before the object's own
/// `:model()` method by [`to_model_in`](super::to_model_in)).
pub fn register_model_maker(lua: &Lua, maker: ModelMaker) {
    with(lua, |s| {
        if !s.model_makers.contains(&maker) {
            s.model_makers.push(maker);
        }
    });
}

/// The model of `ud` made by a registered maker with `ctx`, if one knows its type.
pub(crate) fn make_model(
    lua: &Lua,
    ud: &AnyUserData,
    ctx: &RunContext,
) -> mlua::Result<Option<Model>> {
    for maker in with(lua, |s| s.model_makers.clone()) {
        if let Some(model) = maker(lua, ud, ctx)? {
            return Ok(Some(model));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Engine, Plugin, SessionOptions};

    /// A host object: counts `F` modules; `grow` changes it.
    struct Counter(u32);
    impl mlua::UserData for Counter {
        fn add_methods<M: mlua::UserDataMethods<Self>>(m: &mut M) {
            m.add_method_mut("grow", |lua, me, ()| {
                check_mutable(lua, "counter:grow")?;
                me.0 += 1;
                Ok(me.0)
            });
        }
    }

    fn count(_: &Lua, ud: &AnyUserData, name: &str, _: &[f64]) -> mlua::Result<bool> {
        let Ok(mut c) = ud.borrow_mut::<Counter>() else {
            return Ok(false);
        };
        c.0 += u32::from(name == "F");
        Ok(name == "F")
    }

    struct Counters;
    impl Plugin for Counters {
        fn register(&self, lua: &Lua, pge: &mlua::Table) -> mlua::Result<()> {
            register_interpreter(lua, count);
            register_interpreter(lua, count);
            set_default_instance(lua, |lua| {
                lua.create_userdata(Counter(0)).map(Value::UserData)
            });
            pge.set("counter", lua.create_function(|_, ()| Ok(Counter(0)))?)
        }
    }

    #[test]
    fn plugins_fill_the_registry_and_scripts_cannot_reach_it() {
        let engine = Engine::builder().plugin(Counters).build().expect("engine");
        let session = engine.session(SessionOptions::default()).expect("session");
        let lua = session.lua();
        assert_eq!(interpreters(lua).len(), 1, "added once");
        // A script replacing the constructor does not change the default instance.
        session.eval::<()>("pge.counter = nil").expect("runs");
        let Some(Value::UserData(ud)) = default_instance(lua).expect("made") else {
            panic!("a counter");
        };
        for f in interpreters(lua) {
            assert!(f(lua, &ud, "F", &[]).expect("interprets"));
            assert!(!f(lua, &ud, "+", &[]).expect("interprets"));
        }
        assert_eq!(ud.borrow::<Counter>().expect("counter").0, 1);
    }

    #[test]
    fn the_read_only_phase_refuses_changes_naming_the_rule() {
        let engine = Engine::builder().plugin(Counters).build().expect("engine");
        let session = engine.session(SessionOptions::default()).expect("session");
        let lua = session.lua();
        session.eval::<()>("c = pge.counter()").expect("runs");
        let phase = read_only_phase(lua);
        phase.enter("A".into());
        let e = session.eval::<()>("\nc:grow()").expect_err("read-only");
        assert!(
            e.to_string()
                .starts_with("eval:2: RRule 'A': counter:grow is not allowed"),
            "{e}"
        );
        read_only_phase(lua).leave();
        assert_eq!(session.eval::<u32>("return c:grow()").expect("grows"), 1);
    }
}
