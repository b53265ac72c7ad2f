//! The Lua adapter: `pge.lod.budget{...}` (API.md §6) and the reading of the tree
//! generators' `lod = {...}` option.

use mlua::{Lua, Table, Value};
use pge_engine::Plugin;
use pge_engine::lua::script_error;

use crate::budget::{Budget, assign};
use crate::foliage::{LodOptions, MAX_SECTORS};

/// Adds `pge.lod` with `budget`.
pub struct LodPlugin;

impl Plugin for LodPlugin {
    fn name(&self) -> &str {
        "lod"
    }

    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        let lod = lua.create_table()?;
        lod.set(
            "budget",
            lua.create_function(|lua, t: Value| budget_from_lua(lua, t))?,
        )?;
        pge.set("lod", lod)
    }
}

/// A bad `lod = {...}` option: which one and what it needs (`lod.sectors must be ...`).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{option} {message}")]
pub struct OptionError {
    /// The option's path, e.g. `lod.sectors`.
    pub option: String,
    /// What was wrong, starting with a verb.
    pub message: String,
}

const LOD_KEYS: &[&str] = &["sectors", "atlas"];
const BUDGET_KEYS: &[&str] = &["distances", "leaves", "roots", "total", "near", "far"];

/// Reads a generator's `lod` option: `nil` or `false` for none, `true` for the defaults, or
/// a table `{sectors = n (1..=64, default 1), atlas = bool (default false)}`; unknown keys
/// are errors.
pub fn options_from_value(value: &Value) -> Result<Option<LodOptions>, OptionError> {
    let err = |option: &str, message: String| OptionError {
        option: option.into(),
        message,
    };
    let t = match value {
        Value::Nil | Value::Boolean(false) => return Ok(None),
        Value::Boolean(true) => return Ok(Some(LodOptions::default())),
        Value::Table(t) => t,
        other => {
            return Err(err(
                "lod",
                format!(
                    "must be a table {{sectors = n, atlas = bool}} or a boolean, got {}",
                    other.type_name()
                ),
            ));
        }
    };
    if let Some(key) = unknown_key(t, LOD_KEYS) {
        return Err(err(
            &format!("lod.{key}"),
            format!("is not an option (known: {})", LOD_KEYS.join(", ")),
        ));
    }
    let mut options = LodOptions::default();
    match t.raw_get::<Value>("sectors").unwrap_or(Value::Nil) {
        Value::Nil => {}
        v => {
            let n = match v {
                Value::Integer(i) => Some(i),
                Value::Number(x) if x.fract() == 0.0 && x.abs() < 1e15 => Some(x as i64),
                _ => None,
            };
            match n {
                Some(n) if (1..=i64::from(MAX_SECTORS)).contains(&n) => options.sectors = n as u32,
                _ => {
                    return Err(err(
                        "lod.sectors",
                        format!(
                            "must be an integer between 1 and {MAX_SECTORS}, got {}",
                            shown(&v)
                        ),
                    ));
                }
            }
        }
    }
    match t.raw_get::<Value>("atlas").unwrap_or(Value::Nil) {
        Value::Nil => {}
        Value::Boolean(b) => options.atlas = b,
        other => {
            return Err(err(
                "lod.atlas",
                format!("must be a boolean, got {}", other.type_name()),
            ));
        }
    }
    Ok(Some(options))
}

/// The first string key of `t` not in `known`, in sorted order (so the error is the same
/// whatever the table's iteration order).
fn unknown_key(t: &Table, known: &[&str]) -> Option<String> {
    let mut unknown: Vec<String> = t
        .pairs::<Value, Value>()
        .filter_map(Result::ok)
        .filter_map(|(k, _)| match k {
            Value::String(s) => Some(s.to_string_lossy()),
            _ => None,
        })
        .filter(|k| !known.contains(&k.as_str()))
        .collect();
    unknown.sort();
    unknown.into_iter().next()
}

/// A value as an error message shows it.
fn shown(v: &Value) -> String {
    match v {
        Value::Integer(i) => i.to_string(),
        Value::Number(x) => x.to_string(),
        Value::String(s) => format!("\"{}\"", s.to_string_lossy()),
        other => other.type_name().to_string(),
    }
}

/// `pge.lod.budget{ distances = {...}, leaves = n, roots = r, total = T, near = d, far = d }`:
/// for each distance, how many of the species' `leaves` to draw (see [`assign`]); `roots` is
/// the coarsest level's leaf count (`extras.pge.lod.roots`, default 1).
fn budget_from_lua(lua: &Lua, t: Value) -> mlua::Result<Vec<u32>> {
    const W: &str = "pge.lod.budget";
    let Value::Table(t) = t else {
        return Err(script_error(
            lua,
            format!(
                "{W}: expected a table {{distances, leaves, total, near, far}}, got {}",
                t.type_name()
            ),
        ));
    };
    if let Some(key) = unknown_key(&t, BUDGET_KEYS) {
        return Err(script_error(
            lua,
            format!(
                "{W}: {key} is not an option (known: {})",
                BUDGET_KEYS.join(", ")
            ),
        ));
    }
    let number = |key: &str, required: bool| -> mlua::Result<Option<f64>> {
        match t.raw_get::<Value>(key)? {
            Value::Nil if !required => Ok(None),
            Value::Integer(i) => Ok(Some(i as f64)),
            Value::Number(x) => Ok(Some(x)),
            other => Err(script_error(
                lua,
                format!("{W}: {key} must be a number, got {}", other.type_name()),
            )),
        }
    };
    let count = |key: &str, required: bool, max: f64| -> mlua::Result<Option<u64>> {
        match number(key, required)? {
            None => Ok(None),
            Some(x) if x.fract() == 0.0 && (0.0..=max).contains(&x) => Ok(Some(x as u64)),
            Some(x) => Err(script_error(
                lua,
                format!("{W}: {key} must be an integer between 0 and {max}, got {x}"),
            )),
        }
    };
    let leaves = count("leaves", true, f64::from(u32::MAX))?.unwrap_or(0) as u32;
    let roots = count("roots", false, f64::from(u32::MAX))?.map_or(1, |r| r as u32);
    let total = count("total", true, 2f64.powi(53))?.unwrap_or(0);
    let near = number("near", true)?.unwrap_or(0.0) as f32;
    let far = number("far", true)?.unwrap_or(0.0) as f32;
    let list: Table = match t.raw_get::<Value>("distances")? {
        Value::Table(list) => list,
        other => {
            return Err(script_error(
                lua,
                format!(
                    "{W}: distances must be an array of numbers, got {}",
                    other.type_name()
                ),
            ));
        }
    };
    let mut distances = Vec::with_capacity(list.raw_len());
    for i in 1..=list.raw_len() {
        let d = match list.raw_get::<Value>(i)? {
            Value::Integer(d) => d as f32,
            Value::Number(d) => d as f32,
            other => {
                return Err(script_error(
                    lua,
                    format!(
                        "{W}: distances[{i}] must be a number, got {}",
                        other.type_name()
                    ),
                ));
            }
        };
        distances.push(d);
    }
    let budget = Budget { near, far, total };
    assign(&distances, leaves, roots, &budget).map_err(|e| script_error(lua, format!("{W}: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::{Engine, SessionOptions};

    fn eval(source: &str) -> Result<Vec<u32>, String> {
        let engine = Engine::builder().plugin(LodPlugin).build().expect("engine");
        let session = engine.session(SessionOptions::default()).expect("session");
        session.eval::<Vec<u32>>(source).map_err(|e| e.to_string())
    }

    #[test]
    fn the_budget_is_callable_from_lua() {
        let counts = eval(
            "return pge.lod.budget{ distances = {5, 500, 50}, leaves = 100, roots = 4, \
             total = 120, near = 10, far = 100 }",
        )
        .expect("budget");
        assert_eq!(counts.len(), 3);
        assert_eq!(counts[1], 0);
        assert!(counts.iter().sum::<u32>() <= 120);
        assert!(counts[0] >= counts[2]);
    }

    #[test]
    fn bad_budgets_name_the_option() {
        let e = eval("return pge.lod.budget{ distances = {1, 0/0}, leaves = 10, total = 5, near = 1, far = 2 }")
            .expect_err("nan");
        assert!(
            e.contains("pge.lod.budget: distances[2] must be a finite number >= 0, got NaN"),
            "{e}"
        );
        let e = eval(
            "return pge.lod.budget{ distances = {}, leaves = 10, total = 5, near = 3, far = 2 }",
        )
        .expect_err("order");
        assert!(e.contains("near must be at most far"), "{e}");
        let e = eval(
            "return pge.lod.budget{ distances = {}, leaves = 10, total = 5, near = -1, far = 2 }",
        )
        .expect_err("negative");
        assert!(
            e.contains("near must be a finite number >= 0, got -1"),
            "{e}"
        );
        let e = eval(
            "return pge.lod.budget{ distance = {}, leaves = 10, total = 5, near = 1, far = 2 }",
        )
        .expect_err("unknown");
        assert!(
            e.contains("distance is not an option (known: distances,"),
            "{e}"
        );
    }

    #[test]
    fn lod_options_are_read_and_checked() {
        let lua = Lua::new();
        let read = |src: &str| {
            let v: Value = lua.load(src).eval().expect("lua");
            options_from_value(&v)
        };
        assert_eq!(read("return nil"), Ok(None));
        assert_eq!(read("return true"), Ok(Some(LodOptions::default())));
        let o = read("return { sectors = 8, atlas = true }")
            .expect("ok")
            .expect("some");
        assert_eq!((o.sectors, o.atlas), (8, true));
        let e = read("return { sectors = 65 }").expect_err("range");
        assert_eq!(
            e.to_string(),
            "lod.sectors must be an integer between 1 and 64, got 65"
        );
        let e = read("return { sectors = 0 }").expect_err("range");
        assert_eq!(
            e.to_string(),
            "lod.sectors must be an integer between 1 and 64, got 0"
        );
        let e = read("return { sector = 2 }").expect_err("unknown");
        assert_eq!(
            e.to_string(),
            "lod.sector is not an option (known: sectors, atlas)"
        );
        let e = read("return 3").expect_err("type");
        assert!(e.to_string().starts_with("lod must be a table"));
    }
}
