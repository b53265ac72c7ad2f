//! Algorithms crossing into Lua: handles returned by constructors, and `pge.Algorithm`.

use mlua::{Function, Lua, ObjectLike, Table, UserData, UserDataMethods, Value};

use super::errors::{caller_location, script_error, to_engine_error};
use super::model::{LuaModel, to_model, to_model_in};
use super::skeleton::{LuaSkeleton, skeleton_of_model};
use crate::algorithm::{Finished, grow, run};
use crate::geometry::Model;
use crate::{Algorithm, Error, Location, RunContext, Step};

/// An algorithm handed to a script: what `pge.SpaceColonization{...}`, `pge.Algorithm{...}`
/// or an L-system's `algorithm()` return. A script returns it to have it run; `:model()`
/// runs it to the end at once (to add a grown tree to a bigger model).
pub struct AlgorithmHandle(pub Box<dyn Algorithm>);

impl AlgorithmHandle {
    /// Wraps an algorithm.
    #[must_use]
    pub fn new(algorithm: Box<dyn Algorithm>) -> AlgorithmHandle {
        AlgorithmHandle(algorithm)
    }
}

impl UserData for AlgorithmHandle {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method_mut("model", |lua, me, ()| {
            let ctx = RunContext {
                steps: None,
                ..super::run_context(lua)
            };
            run(&mut *me.0, &ctx, &mut |_| {})
                .map(LuaModel)
                .map_err(mlua::Error::external)
        });
        m.add_method_mut("skeleton", |lua, me, ()| {
            let ctx = RunContext {
                steps: None,
                ..super::run_context(lua)
            };
            grow(&mut *me.0, &ctx).map_err(mlua::Error::external)?;
            let skeleton = match me.0.skeleton() {
                Some(s) => s,
                None => {
                    let model = me.0.finish(&ctx).map_err(mlua::Error::external)?;
                    skeleton_of_model(&model).ok_or_else(|| {
                        script_error(
                            lua,
                            format!("{}:skeleton(): it grew no skeleton", me.0.name()),
                        )
                    })?
                }
            };
            LuaSkeleton::new(skeleton).into_lua_charged(lua)
        });
        m.add_method("name", |_, me, ()| Ok(me.0.name().to_string()));
    }
}

/// A step-wise generator written in Lua: `pge.Algorithm{ init = f, step = f, finish = f }`.
/// Each function is called with the table as its argument (`self`), so it can keep state
/// there. `step` returns true to continue; `finish` returns a model, a mesh or anything with
/// `:model()`.
pub struct ScriptAlgorithm {
    table: Table,
    init: Option<Function>,
    step: Function,
    finish: Function,
    location: Location,
}

impl ScriptAlgorithm {
    fn lua_error(&self, f: &Function, e: mlua::Error) -> Error {
        match f.weak_lua().try_upgrade() {
            Some(lua) => to_engine_error(&lua, e),
            None => Error::script(self.location.clone(), e.to_string()),
        }
    }
}

impl Algorithm for ScriptAlgorithm {
    fn name(&self) -> &str {
        "pge.Algorithm"
    }

    fn init(&mut self, _: &RunContext) -> crate::Result<()> {
        if let Some(f) = &self.init {
            f.call::<()>(self.table.clone())
                .map_err(|e| self.lua_error(f, e))?;
        }
        Ok(())
    }

    fn step(&mut self, ctx: &RunContext) -> crate::Result<Step> {
        ctx.check_deadline(&self.location)?;
        let more: Value = self
            .step
            .call(self.table.clone())
            .map_err(|e| self.lua_error(&self.step, e))?;
        Ok(match more {
            Value::Nil | Value::Boolean(false) => Step::Done,
            _ => Step::Continue,
        })
    }

    fn finish(&mut self, ctx: &RunContext) -> crate::Result<Model> {
        let result: Value = self
            .finish
            .call(self.table.clone())
            .map_err(|e| self.lua_error(&self.finish, e))?;
        let made = match self.finish.weak_lua().try_upgrade() {
            Some(lua) => to_model_in(&lua, &result, ctx),
            None => to_model(&result),
        };
        made.map_err(|e| match e {
            e if super::errors::engine_error_of(&e).is_some() => self.lua_error(&self.finish, e),
            mlua::Error::RuntimeError(m)
                if m.contains(": ") && super::errors::split_location(&m).is_some() =>
            {
                self.lua_error(&self.finish, mlua::Error::RuntimeError(m))
            }
            other => Error::script(
                self.location.clone(),
                format!("pge.Algorithm finish: {other}"),
            ),
        })
    }
}

fn make_algorithm(lua: &Lua, t: Table) -> mlua::Result<AlgorithmHandle> {
    let func = |k: &str, required: bool| -> mlua::Result<Option<Function>> {
        match t.raw_get::<Value>(k)? {
            Value::Function(f) => Ok(Some(f)),
            Value::Nil if !required => Ok(None),
            other => Err(script_error(
                lua,
                format!(
                    "pge.Algorithm: '{k}' must be a function, not {}",
                    other.type_name()
                ),
            )),
        }
    };
    let init = func("init", false)?;
    let step =
        func("step", true)?.ok_or_else(|| script_error(lua, "pge.Algorithm: 'step' is missing"))?;
    let finish = func("finish", true)?
        .ok_or_else(|| script_error(lua, "pge.Algorithm: 'finish' is missing"))?;
    Ok(AlgorithmHandle::new(Box::new(ScriptAlgorithm {
        table: t,
        init,
        step,
        finish,
        location: caller_location(lua),
    })))
}

pub(crate) fn register(lua: &Lua, pge: &Table) -> mlua::Result<()> {
    pge.set("Algorithm", lua.create_function(make_algorithm)?)
}

/// The algorithm a script's value stands for: an [`AlgorithmHandle`]; an object with an
/// `algorithm()` method (an L-system); or a finished model (a model, a mesh, anything with
/// `:model()`). `location` is blamed when the value is none of these.
pub fn algorithm_from(
    lua: &Lua,
    value: Value,
    location: &Location,
) -> crate::Result<Box<dyn Algorithm>> {
    let mut value = value;
    for _ in 0..4 {
        if let Value::UserData(ud) = &value
            && ud.is::<AlgorithmHandle>()
        {
            let handle: AlgorithmHandle = ud.take().map_err(|e| to_engine_error(lua, e))?;
            return Ok(handle.0);
        }
        let method = match &value {
            Value::UserData(ud) => has_function(ud.get::<Value>("algorithm")),
            Value::Table(t) => has_function(t.get::<Value>("algorithm")),
            _ => false,
        };
        if !method {
            break;
        }
        value = match &value {
            Value::UserData(ud) => ud.call_method::<Value>("algorithm", ()),
            Value::Table(t) => t.call_method::<Value>("algorithm", ()),
            _ => unreachable!("checked above"),
        }
        .map_err(|e| to_engine_error(lua, e))?;
    }
    let model_like = match &value {
        Value::UserData(ud) => {
            super::model::is_model_or_mesh(ud) || has_function(ud.get::<Value>("model"))
        }
        Value::Table(t) => has_function(t.get::<Value>("model")),
        _ => false,
    };
    if !model_like {
        return Err(Error::script(
            location.clone(),
            format!(
                "the script returned {}; expected a model, a mesh, or something that grows \
                 (pge.LSystem, pge.SpaceColonization, pge.Algorithm, ...)",
                describe_value(&value)
            ),
        ));
    }
    // Something that makes a model: its own failure is the error to show.
    match to_model_in(lua, &value, &super::run_context(lua)) {
        Ok(model) => Ok(Box::new(Finished(model))),
        Err(e) => {
            let e = to_engine_error(lua, e);
            match e {
                Error::Script {
                    location: l,
                    message,
                    traceback,
                } if l.file == "?" => Err(Error::Script {
                    location: location.clone(),
                    message,
                    traceback,
                }),
                other => Err(other),
            }
        }
    }
}

fn has_function(v: mlua::Result<Value>) -> bool {
    matches!(v, Ok(Value::Function(_)))
}

fn describe_value(v: &Value) -> String {
    match v {
        Value::Nil => "nothing".into(),
        Value::UserData(ud) => match ud.type_name() {
            Ok(name) => with_article(&name.to_string_lossy()),
            _ => "a userdata".into(),
        },
        other => with_article(other.type_name()),
    }
}

fn with_article(noun: &str) -> String {
    let article = if noun.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    };
    format!("{article} {noun}")
}
