//! The Lua adapter: `pge.lod.budget{...}` (docs/lua-api.md) and the reading of the tree
//! generators' `lod = {...}` option.

use mlua::{Lua, Table, Value};
use pge_engine::Plugin;
use pge_engine::lua::{Bounds, Options, caller_location};

use crate::budget::{Budget, assign};
use crate::foliage::{LodOptions, MAX_SECTORS};

/// Adds `pge.lod` with `budget`.
pub struct LodPlugin;

impl Plugin for LodPlugin {
    fn name(&self) -> &str {
        "lod"
    }

    fn lazy_names(&self) -> &'static [&'static str] {
        &["lod"]
    }

    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        let lod = lua.create_table()?;
        lod.set(
            "budget",
            lua.create_function(|lua, t: Value| {
                let o = Options::new(lua, t, "pge.lod.budget")?;
                budget_from_options(&o)
            })?,
        )?;
        pge.set("lod", lod)
    }
}

/// Reads a generator's `lod` option: absent or `false` for none, `true` for the defaults,
/// or a table `{sectors = n (1..=64, default 1), atlas = bool (default false)}` whose
/// unknown keys are errors. The options remember the calling line for warnings.
pub fn lod_options(o: &Options) -> mlua::Result<Option<LodOptions>> {
    let source = caller_location(o.lua()).to_string();
    // The simplification keeps to the run's deadline.
    let selection = crate::Selection {
        deadline: pge_engine::lua::run_context(o.lua()).deadline,
        ..crate::Selection::default()
    };
    match o.value("lod")? {
        Value::Nil | Value::Boolean(false) => Ok(None),
        Value::Boolean(true) => Ok(Some(LodOptions {
            source,
            selection,
            ..LodOptions::default()
        })),
        Value::Table(t) => {
            let lod = o.child("lod", t);
            let mut options = LodOptions {
                source,
                selection,
                ..LodOptions::default()
            };
            if let Some(n) = lod.integer("sectors", 1..=i64::from(MAX_SECTORS))? {
                options.sectors = n as u32;
            }
            if let Some(atlas) = lod.boolean("atlas")? {
                options.atlas = atlas;
            }
            lod.finish()?;
            Ok(Some(options))
        }
        other => Err(o.wrong_type(
            "lod",
            "a table {sectors = n, atlas = bool} or a boolean",
            &other,
        )),
    }
}

/// `pge.lod.budget{ distances = {...}, leaves = n, roots = r, total = T, near = d, far = d }`:
/// for each distance, how many of the species' `leaves` to draw (see [`assign`]); `roots` is
/// the coarsest level's leaf count (`extras.pge.lod.roots`, default 1).
fn budget_from_options(o: &Options) -> mlua::Result<Vec<u32>> {
    let count = |key: &str, max: i64| -> mlua::Result<i64> {
        o.integer(key, 0..=max)?
            .ok_or_else(|| o.missing(key, format!("an integer between 0 and {max}")))
    };
    let distance = |key: &str| -> mlua::Result<f32> {
        o.number_f32(key, Bounds::AtLeast(0.0))?
            .ok_or_else(|| o.missing(key, Bounds::AtLeast(0.0)))
    };
    let leaves = count("leaves", i64::from(u32::MAX))? as u32;
    let total = count("total", 1 << 53)? as u64;
    let roots = o
        .integer("roots", 1..=i64::from(u32::MAX))?
        .map_or(1, |r| r as u32);
    let near = distance("near")?;
    let far = distance("far")?;
    let list = match o.value("distances")? {
        Value::Table(list) => list,
        other => return Err(o.wrong_type("distances", "an array of numbers", &other)),
    };
    o.finish()?;
    let mut distances = Vec::with_capacity(list.raw_len());
    for i in 1..=list.raw_len() {
        let key = format!("distances[{i}]");
        let d = match list.raw_get::<Value>(i)? {
            Value::Integer(d) => d as f64,
            Value::Number(d) => d,
            other => return Err(o.wrong_type(&key, Bounds::AtLeast(0.0), &other)),
        };
        if !Bounds::AtLeast(0.0).contains(d) || d > f64::from(f32::MAX) {
            return Err(o.invalid(&key, Bounds::AtLeast(0.0), d));
        }
        distances.push(d as f32);
    }
    let budget = Budget { near, far, total };
    assign(&distances, leaves, roots, &budget).map_err(|e| o.error(e))
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
        let call =
            |args: &str| eval(&format!("return pge.lod.budget{{ {args} }}")).expect_err("an error");
        let e = call("distances = {1, 0/0}, leaves = 10, total = 5, near = 1, far = 2");
        assert!(
            e.contains("eval:1: pge.lod.budget: distances[2] must be a number >= 0, got NaN"),
            "{e}"
        );
        let e = call("distances = {}, leaves = 10, total = 5, near = 3, far = 2");
        assert!(
            e.contains("pge.lod.budget: near must be at most far, got near = 3 and far = 2"),
            "{e}"
        );
        let e = call("distances = {}, leaves = 10, total = 5, near = -1, far = 2");
        assert!(
            e.contains("pge.lod.budget: near must be a number >= 0, got -1"),
            "{e}"
        );
        let e = call("distance = {}, leaves = 10, total = 5, near = 1, far = 2");
        assert!(
            e.contains("pge.lod.budget: distances must be an array of numbers"),
            "{e}"
        );
        let e = call("distances = {}, distance = 3, leaves = 10, total = 5, near = 1, far = 2");
        assert!(e.contains("unknown option 'distance'"), "{e}");
        let e = call("distances = {}, leaves = 10, near = 1, far = 2");
        assert!(e.contains("total is required"), "{e}");
    }

    /// Runs `source` with a global `lod(t)` that reads `t.lod` and describes the result.
    fn read(source: &str) -> Result<String, String> {
        let engine = Engine::builder().build().expect("engine");
        let session = engine.session(SessionOptions::default()).expect("session");
        let f = session
            .lua()
            .create_function(|lua, t: Value| {
                let o = Options::new(lua, t, "tree")?;
                let lod = lod_options(&o)?;
                o.finish()?;
                Ok(format!("{:?}", lod.map(|l| (l.sectors, l.atlas, l.source))))
            })
            .expect("function");
        session.lua().globals().set("lod", f).expect("global");
        session.eval::<String>(source).map_err(|e| e.to_string())
    }

    #[test]
    fn lod_options_are_read_and_checked() {
        assert_eq!(read("return lod{}").as_deref(), Ok("None"));
        assert_eq!(
            read("return lod{ lod = true }").as_deref(),
            Ok("Some((1, false, \"eval:1\"))")
        );
        assert_eq!(
            read("return lod{ lod = { sectors = 8, atlas = true } }").as_deref(),
            Ok("Some((8, true, \"eval:1\"))")
        );
        let e = read("return lod{ lod = { sectors = 65 } }").expect_err("range");
        assert!(
            e.contains("tree: lod.sectors must be an integer between 1 and 64, got 65"),
            "{e}"
        );
        let e = read("return lod{ lod = { sectors = 0 } }").expect_err("range");
        assert!(
            e.contains("lod.sectors must be an integer between 1 and 64, got 0"),
            "{e}"
        );
        let e = read("return lod{ lod = { sector = 2 } }").expect_err("unknown");
        assert!(e.contains("unknown option 'lod.sector'"), "{e}");
        assert!(e.contains("(known: sectors, atlas)"), "{e}");
        let e = read("return lod{ lod = 3 }").expect_err("type");
        assert!(e.contains("tree: lod must be a table"), "{e}");
    }
}
