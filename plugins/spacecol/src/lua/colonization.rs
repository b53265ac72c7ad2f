//! `pge.SpaceColonization{...}`: the options of a colonization, read with the engine's
//! options reader, and the algorithm handle the script returns.

use mlua::{Lua, Value};
use pge_engine::lua::{AlgorithmHandle, Bounds, Options, caller_location};

use super::shapes::shape_of;
use crate::colonize::{Params, SpaceColonization};
use crate::points::Mode;

pub(super) fn new_colonization(lua: &Lua, v: Value) -> mlua::Result<AlgorithmHandle> {
    let w = "pge.SpaceColonization";
    let o = Options::table_required(lua, v, w)?;
    let envelope = match o.value("envelope")? {
        Value::Nil => return Err(o.missing("envelope", "a pge.shape.*")),
        v => shape_of(&o, "envelope", v)?,
    };
    let mut p = Params::new(envelope);
    p.points = o.integer("points", 1..=10_000_000)?.map(|n| n as u32);
    let mode = o.choice("mode", &["fill", "surround", "vertices"])?;
    let thickness = o.positive("thickness")?;
    p.mode = match mode {
        None | Some("fill") => Mode::Fill,
        Some("vertices") => Mode::Vertices,
        Some(_) => {
            let (lo, hi) = p.envelope.bounds();
            Mode::Surround {
                thickness: thickness.unwrap_or(0.15 * (hi - lo).min_element().max(0.0)),
            }
        }
    };
    if let Some(step) = o.positive("step")? {
        // Influence and kill defaults follow the step.
        p.influence = 8.0 * step;
        p.kill = 2.0 * step;
        p.step = step;
    }
    let influence = o.positive("influence")?;
    let kill = o.positive("kill")?;
    // A default never contradicts a value the script gave: an unset kill stays below a
    // given influence, an unset influence above a given kill.
    match (influence, kill) {
        (Some(i), Some(k)) => (p.influence, p.kill) = (i, k),
        (Some(i), None) => (p.influence, p.kill) = (i, p.kill.min(0.25 * i)),
        (None, Some(k)) => (p.influence, p.kill) = (p.influence.max(4.0 * k), k),
        (None, None) => {}
    }
    if let Some(v) = o.vec3("tropism")? {
        p.tropism = v;
    }
    if let Some(v) = o.number_f32("persistence", Bounds::AtLeast(0.0))? {
        p.persistence = v;
    }
    if let Some(v) = o.number_f32("perception", Bounds::Between(0.0, 180.0))? {
        p.perception = v;
    }
    if let Some(v) = o.number_f32("maxTurn", Bounds::Between(0.0, 180.0))? {
        p.max_turn = v;
    }
    if let Some(v) = o.vec3("root")? {
        p.roots = vec![v];
    }
    match o.value("roots")? {
        Value::Nil => {}
        Value::Table(list) => {
            let mut roots = Vec::new();
            for (k, v) in list.sequence_values::<Value>().enumerate() {
                let key = format!("roots[{}]", k + 1);
                let root = o.vec3_of(&key, &v?)?;
                roots.push(root.ok_or_else(|| o.missing(&key, "a vector {x, y, z}"))?);
            }
            if roots.is_empty() {
                return Err(o.problem("roots", "must be a non-empty list of vectors"));
            }
            p.roots = roots;
        }
        other => return Err(o.wrong_type("roots", "a list of vectors", &other)),
    }
    if let Some(v) = o.number_f32("trunk", Bounds::AtLeast(0.0))? {
        p.trunk = v;
    }
    if let Some(n) = o.integer("maxIterations", 1..=1_000_000)? {
        p.max_iterations = n as u32;
    }
    if let Some(seed) = o.integer("seed", 0..=i64::MAX)? {
        p.seed = seed as u64;
    }
    match o.value("start")? {
        Value::Nil => {}
        v => match pge_engine::lua::skeleton_from_value(&v) {
            Some(s) => p.start = Some(std::sync::Arc::new(s)),
            None => {
                return Err(o.wrong_type(
                    "start",
                    "a skeleton (pge.Skeleton, e.g. from handle:skeleton())",
                    &v,
                ));
            }
        },
    }
    p.tree = pge_tree::lua::tree_options(&o)?;
    o.finish()?;
    let location = caller_location(lua);
    let sc = SpaceColonization::new(p, location).map_err(|e| match e {
        pge_engine::Error::Script { message, .. } => o.error(message),
        other => o.error(other),
    })?;
    Ok(AlgorithmHandle::new(Box::new(sc)))
}
