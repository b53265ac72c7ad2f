//! The Lua side: `pge.Conifer{...}`. A thin adapter: it reads the options through the
//! engine's one reader and hands plain Rust values to [`Conifer`].

use mlua::{Lua, Table, Value};
use pge_engine::Plugin;
use pge_engine::lua::{AlgorithmHandle, Bounds, Options, caller_location};

use crate::conifer::Conifer;
use crate::params::{
    ConiferParams, Crown, MAX_INTERWHORL, MAX_NODES, MAX_PER_WHORL, MAX_PROFILE, MAX_YEARS,
    SprayPattern,
};

/// Adds `pge.Conifer` to every session.
#[derive(Clone, Copy, Debug, Default)]
pub struct ConiferPlugin;

impl Plugin for ConiferPlugin {
    fn name(&self) -> &str {
        "conifer"
    }

    fn lazy_names(&self) -> &'static [&'static str] {
        &["Conifer"]
    }

    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        pge.set(
            "Conifer",
            lua.create_function(|lua, v: Value| new_conifer(lua, v))?,
        )
    }
}

/// `crown = "conic"` or `crown = {0, 0.7, 1, 0.9}`.
fn crown(o: &Options) -> mlua::Result<Option<Crown>> {
    const NEED: &str = "\"conic\", \"ogive\", \"columnar\" or a list of numbers >= 0";
    match o.value("crown")? {
        Value::Nil => Ok(None),
        Value::String(s) => {
            let name = s.to_string_lossy();
            Crown::from_name(&name)
                .map(Some)
                .ok_or_else(|| o.invalid("crown", NEED, format!("\"{name}\"")))
        }
        Value::Table(t) => {
            let n = t.raw_len();
            if !(2..=MAX_PROFILE).contains(&n) {
                return Err(o.problem(
                    "crown",
                    format!("must be a list of 2 to {MAX_PROFILE} numbers, got {n}"),
                ));
            }
            let mut values = Vec::with_capacity(n);
            for k in 1..=n {
                let v: Value = t.raw_get(k)?;
                let x = match v {
                    Value::Integer(i) => i as f64,
                    Value::Number(x) => x,
                    other => return Err(o.wrong_type(&format!("crown[{k}]"), NEED, &other)),
                };
                if !(x.is_finite() && x >= 0.0 && x <= f64::from(f32::MAX)) {
                    return Err(o.invalid(&format!("crown[{k}]"), "a number >= 0", x));
                }
                values.push(x as f32);
            }
            Ok(Some(Crown::Profile(values)))
        }
        other => Err(o.wrong_type("crown", NEED, &other)),
    }
}

fn new_conifer(lua: &Lua, v: Value) -> mlua::Result<AlgorithmHandle> {
    let o = Options::new(lua, v, "pge.Conifer")?;
    let mut p = ConiferParams::default();
    let angle = Bounds::Between(0.0, 180.0);
    if let Some(x) = o.integer("years", 1..=i64::from(MAX_YEARS))? {
        p.years = x as u32;
    }
    if let Some(x) = o.positive("height")? {
        p.height = x;
    }
    if let Some(x) = o.positive("crownRadius")? {
        p.crown_radius = x;
    }
    if let Some(c) = crown(&o)? {
        p.crown = c;
    }
    if let Some(x) = o.number_f32("crownBase", Bounds::Between(0.0, 0.95))? {
        p.crown_base = x;
    }
    if let Some((a, b)) = o.integer_range("perWhorl", 1..=i64::from(MAX_PER_WHORL))? {
        p.per_whorl = (a as u32, b as u32);
    }
    if let Some(x) = o.number_f32("twist", Bounds::Between(-360.0, 360.0))? {
        p.twist = x;
    }
    if let Some((a, b)) = o.range("angle", angle)? {
        // {apex, base}, apex <= base: lower branches leave the trunk flatter.
        p.angle = (a as f32, b as f32);
    }
    if let Some(x) = o.number_f32("droop", Bounds::Between(0.0, 90.0))? {
        p.droop = x;
    }
    if let Some(x) = o.number_f32("jitter", Bounds::Between(0.0, 1.0))? {
        p.jitter = x;
    }
    if let Some(x) = o.number_f32("waviness", Bounds::Between(0.0, 0.5))? {
        p.waviness = x;
    }
    if let Some(x) = o.positive("segment")? {
        p.segment = x;
    }
    if let Some(x) = o.integer("orders", 1..=3)? {
        p.orders = x as u32;
    }
    if let Some(x) = o.number_f32("sprayAngle", Bounds::Between(0.0, 90.0))? {
        p.spray_angle = x;
    }
    if let Some(x) = o.number_f32("sprayLength", Bounds::Between(0.0, 2.0))? {
        p.spray_length = x;
    }
    if let Some(x) = o.number_f32("sprayDroop", Bounds::Between(0.0, 90.0))? {
        p.spray_droop = x;
    }
    p.spray_pattern = match o.choice("sprayPattern", &SprayPattern::NAMES)? {
        Some("paired") => SprayPattern::Paired,
        _ => SprayPattern::Alternate,
    };
    if let Some(x) = o.number_f32("bare", Bounds::Between(0.0, 1.0))? {
        p.bare = x;
    }
    if let Some((a, b)) = o.integer_range("interwhorl", 0..=i64::from(MAX_INTERWHORL))? {
        p.interwhorl = (a as u32, b as u32);
    }
    if let Some(x) = o.number_f32("jointRatio", Bounds::AboveAtMost(0.0, 1.0))? {
        p.joint_ratio = x;
    }
    if let Some(v) = o.vec3("root")? {
        p.root = v;
    }
    if let Some(x) = o.integer("seed", 0..=i64::MAX)? {
        p.seed = x as u64;
    }
    if let Some(x) = o.integer("maxNodes", 1..=MAX_NODES as i64)? {
        p.max_nodes = x as usize;
    }
    p.tree = pge_tree::lua::tree_options_keeping_radii(&o)?;
    o.finish()?;
    let conifer = Conifer::new(p, caller_location(lua)).map_err(|e| match e {
        pge_engine::Error::Script { message, .. } => o.error(message),
        other => mlua::Error::external(other),
    })?;
    Ok(AlgorithmHandle::new(Box::new(conifer)))
}
