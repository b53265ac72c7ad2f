//! The Lua side: `pge.Growth{...}` (docs/lua-api.md). A thin adapter: it reads the options through
//! the engine's one reader and hands plain Rust values to [`Growth`].

use std::sync::Arc;

use mlua::{Lua, Table, Value};
use pge_engine::Plugin;
use pge_engine::lua::{AlgorithmHandle, Bounds, Options, caller_location, skeleton_from_value};

use crate::growth::{Growth, GrowthParams, MAX_STEPS};

/// Adds `pge.Growth` to every session.
#[derive(Clone, Copy, Debug, Default)]
pub struct GrowthPlugin;

impl Plugin for GrowthPlugin {
    fn name(&self) -> &str {
        "growth"
    }

    fn lazy_names(&self) -> &'static [&'static str] {
        &["Growth"]
    }

    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        pge.set(
            "Growth",
            lua.create_function(|lua, v: Value| new_growth(lua, v))?,
        )
    }
}

fn new_growth(lua: &Lua, v: Value) -> mlua::Result<AlgorithmHandle> {
    let w = "pge.Growth";
    let o = Options::new(lua, v, w)?;
    let mut p = GrowthParams::default();
    let t = &mut p.transport;
    if let Some(x) = o.number("ratio", Bounds::Finite)? {
        if !(x > 0.0 && x < 1.0) {
            return Err(o.invalid("ratio", "a number between 0 and 1 (exclusive)", x));
        }
        t.ratio = x;
    }
    if let Some(x) = o.number("spread", Bounds::AtLeast(0.0))? {
        t.spread = x;
    }
    if let Some(x) = o.number("splitsize", Bounds::Above(0.0))? {
        t.splitsize = x;
    }
    if let Some(x) = o.number("splitdecay", Bounds::AtLeast(0.0))? {
        t.splitdecay = x;
    }
    if let Some(x) = o.number("directedness", Bounds::Between(0.0, 1.0))? {
        t.directedness = x;
    }
    if let Some(x) = o.integer("localdepth", 0..=1000)? {
        t.localdepth = x as u32;
    }
    if let Some(x) = o.number("feed", Bounds::Above(0.0))? {
        t.feed = x;
    }
    if let Some(x) = o.integer("steps", 0..=i64::from(MAX_STEPS))? {
        p.steps = x as u32;
    }
    if let Some(v) = o.vec3("root")? {
        p.root = v;
    }
    if let Some(v) = o.vec3("direction")? {
        if v.length_squared() == 0.0 {
            return Err(o.invalid("direction", "a non-zero vector", "{0, 0, 0}"));
        }
        p.direction = v;
    }
    match o.value("start")? {
        Value::Nil => {}
        v => match skeleton_from_value(&v) {
            Some(s) if s.is_empty() => {
                return Err(o.problem("start", "must be a skeleton with nodes, got an empty one"));
            }
            Some(s) => p.start = Some(Arc::new(s)),
            None => {
                return Err(o.wrong_type(
                    "start",
                    "a skeleton (pge.Skeleton, e.g. from handle:skeleton())",
                    &v,
                ));
            }
        },
    }
    if let Some(x) = o.positive("scale")? {
        p.scale = x;
    }
    if let Some(x) = o.positive("girth")? {
        p.girth = x;
    }
    if let Some(x) = o.integer("maxBranches", 1..=50_000_000)? {
        p.max_branches = x as usize;
    }
    if let Some(x) = o.integer("seed", 0..=i64::MAX)? {
        p.seed = x as u64;
    }
    p.tree = pge_tree::lua::tree_options_keeping_radii(&o)?;
    o.finish()?;
    let growth = Growth::new(p, caller_location(lua)).map_err(|e| match e {
        pge_engine::Error::Script { message, .. } => o.error(message),
        other => mlua::Error::external(other),
    })?;
    Ok(AlgorithmHandle::new(Box::new(growth)))
}
