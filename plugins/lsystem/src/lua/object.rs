//! `pge.LSystem(name)`: the object scripts configure with methods.

use mlua::{Function, Lua, UserData, UserDataMethods, Value};
use pge_engine::lua::{AlgorithmHandle, caller_location, script_error};

use super::algorithm::LSystemAlgorithm;
use super::config::{Axiom, Config, LuaIRule, LuaRule};
use super::{session_symbols, with_shared};
use crate::classic;
use crate::{LsError, Sym, System};
use pge_engine::lua::check_mutable;

/// A `pge.LSystem` object.
pub struct LuaLSystem(pub(crate) Config);

pub(crate) fn new_lsystem(lua: &Lua, name: Option<String>) -> mlua::Result<LuaLSystem> {
    let index = with_shared(lua, |s| {
        s.instances += 1;
        s.instances - 1
    });
    Ok(LuaLSystem(Config {
        name: name.unwrap_or_else(|| "lsystem".into()),
        location: caller_location(lua),
        axiom: None,
        iterations: 0,
        create: None,
        before: None,
        after: None,
        globals: lua.create_table()?,
        system: System::new(),
        rrules: Vec::new(),
        irules: Vec::new(),
        locations: Vec::new(),
        max_modules: None,
        every_step: true,
        index,
    }))
}

fn rule_error(lua: &Lua, e: LsError) -> mlua::Error {
    script_error(lua, e)
}

impl UserData for LuaLSystem {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method_mut("axiom", |lua, me, v: Value| {
            let axiom = match v {
                Value::String(s) => Axiom::Text(s.to_str()?.to_string()),
                Value::Table(t) => Axiom::Lua(t),
                other => {
                    return Err(script_error(
                        lua,
                        format!(
                            "axiom: expected a string in classic notation or an array of \
                             symbols, got {}",
                            other.type_name()
                        ),
                    ));
                }
            };
            me.0.axiom = Some((axiom, caller_location(lua)));
            Ok(())
        });
        m.add_method_mut("iterations", |lua, me, n: Value| {
            me.0.iterations = count_arg(lua, "iterations", n, 1_000_000)? as u32;
            Ok(())
        });
        m.add_method_mut("maxModules", |lua, me, n: Value| {
            me.0.max_modules = Some(count_arg(lua, "maxModules", n, u32::MAX as u64)? as usize);
            Ok(())
        });
        m.add_method_mut("interpretEveryStep", |_, me, on: bool| {
            me.0.every_step = on;
            Ok(())
        });
        m.add_method_mut("createInstance", |_, me, f: Function| {
            me.0.create = Some(f);
            Ok(())
        });
        m.add_method_mut("beforeStep", |_, me, f: Function| {
            me.0.before = Some(f);
            Ok(())
        });
        m.add_method_mut("afterStep", |_, me, f: Function| {
            me.0.after = Some(f);
            Ok(())
        });
        m.add_method("set", |lua, me, (key, value): (String, Value)| {
            check_mutable(lua, &format!("set(\"{key}\") on L-system '{}'", me.0.name))?;
            me.0.globals.set(key, value)
        });
        m.add_method("get", |_, me, key: String| me.0.globals.get::<Value>(key));
        m.add_method_mut("declare", |_, me, names: String| {
            me.0.system.declare(&names);
            Ok(())
        });
        m.add_method_mut("ignore", |lua, me, names: String| {
            let symbols = session_symbols(lua);
            me.0.system.ignore(&names, &mut symbols.borrow_mut());
            Ok(())
        });
        m.add_method_mut("rule", |lua, me, (text, weight): (String, Option<f64>)| {
            let origin = me.0.locations.len() as u32;
            let symbols = session_symbols(lua);
            me.0.system
                .add_production(&text, weight, origin, &mut symbols.borrow_mut())
                .map_err(|e| rule_error(lua, e))?;
            me.0.locations.push(caller_location(lua));
            Ok(())
        });
        m.add_method_mut("RRule", |lua, me, (lhs, func): (String, Value)| {
            let Value::Function(func) = func else {
                return Err(script_error(
                    lua,
                    format!("RRule '{lhs}': the right side must be a function"),
                ));
            };
            let origin = me.0.locations.len() as u32;
            let id = me.0.rrules.len() as u32;
            let symbols = session_symbols(lua);
            me.0.system
                .add_external(&lhs, id, origin, &mut symbols.borrow_mut())
                .map_err(|e| rule_error(lua, e))?;
            me.0.rrules.push(LuaRule {
                func,
                text: lhs.trim().into(),
                origin,
            });
            me.0.locations.push(caller_location(lua));
            Ok(())
        });
        m.add_method_mut("IRule", |lua, me, (lhs, func): (String, Value)| {
            let Value::Function(func) = func else {
                return Err(script_error(
                    lua,
                    format!("IRule '{lhs}': the right side must be a function"),
                ));
            };
            // `[` and `]` may be interpreted (a host object saving and restoring its state).
            if matches!(lhs.trim(), "[" | "]") {
                let sym = if lhs.trim() == "[" {
                    Sym::PUSH
                } else {
                    Sym::POP
                };
                me.0.irules.push(LuaIRule {
                    sym,
                    left: Vec::new(),
                    func,
                });
                return Ok(());
            }
            let parsed = classic::parse_lhs(&lhs, &|t| Ok(classic::parse_lua_patterns(t)))
                .map_err(|e| script_error(lua, format!("IRule '{}': {e}", lhs.trim())))?;
            if parsed.condition.is_some() {
                return Err(script_error(
                    lua,
                    format!(
                        "IRule '{}': a rule function takes no ':' condition; test the \
                         parameters in the function and return nil when it does not apply",
                        lhs.trim()
                    ),
                ));
            }
            if !parsed.right.is_empty() {
                return Err(script_error(
                    lua,
                    format!(
                        "IRule '{}': an interpretation rule has no right context (the modules \
                         to its right are not derived yet when it is interpreted)",
                        lhs.trim()
                    ),
                ));
            }
            let symbols = session_symbols(lua);
            let mut table = symbols.borrow_mut();
            let sym = table.intern(&parsed.pred.name);
            let left = parsed.left.iter().map(|p| table.intern(&p.name)).collect();
            me.0.irules.push(LuaIRule { sym, left, func });
            Ok(())
        });
        m.add_method("name", |_, me, ()| Ok(me.0.name.clone()));
        m.add_method("algorithm", |lua, me, ()| {
            let algorithm = LSystemAlgorithm::new(lua, me.0.clone(), false);
            Ok(AlgorithmHandle::new(Box::new(algorithm)))
        });
        m.add_method("model", |lua, me, ()| {
            let mut algorithm = LSystemAlgorithm::new(lua, me.0.clone(), false);
            let ctx = pge_engine::RunContext {
                steps: None,
                ..pge_engine::lua::run_context(lua)
            };
            pge_engine::algorithm::run(&mut algorithm, &ctx, &mut |_| {})
                .map(pge_engine::lua::LuaModel)
                .map_err(mlua::Error::external)
        });
    }
}

fn count_arg(lua: &Lua, what: &str, v: Value, max: u64) -> mlua::Result<u64> {
    let n = match v {
        Value::Integer(i) => i as f64,
        Value::Number(n) => n,
        other => {
            return Err(script_error(
                lua,
                format!("{what}: expected a number, got {}", other.type_name()),
            ));
        }
    };
    if !(n >= 0.0 && n.fract() == 0.0 && n <= max as f64) {
        return Err(script_error(
            lua,
            format!("{what}: expected a whole number from 0 to {max}, got {n}"),
        ));
    }
    Ok(n as u64)
}
