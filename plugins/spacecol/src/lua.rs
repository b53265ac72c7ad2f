//! The Lua side: `pge.SpaceColonization{...}` and the `pge.shape.*` constructors. A thin
//! adapter: it reads and checks options (errors at the calling line name the option and the
//! range it needs) and hands plain Rust values to [`SpaceColonization`] and [`Shape`].

use std::rc::Rc;

use glam::{Vec2, Vec3};
use mlua::{FromLua, Function, Lua, Table, UserData, UserDataMethods, Value};
use pge_engine::Plugin;
use pge_engine::lua::{
    AlgorithmHandle, LuaMat4, LuaVec3, caller_location, resolve_path, script_error,
    to_engine_error, to_model,
};

use crate::colonize::{Params, SpaceColonization};
use crate::points::Mode;
use crate::shape::Shape;
use crate::trimesh::TriMesh;

/// Adds `pge.SpaceColonization` and `pge.shape` (sphere, ellipsoid, box, capsule, cone,
/// cylinder, revolve, mesh, union, difference, predicate) to every session.
#[derive(Clone, Copy, Debug, Default)]
pub struct SpaceColonizationPlugin;

impl Plugin for SpaceColonizationPlugin {
    fn name(&self) -> &str {
        "spacecol"
    }

    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        pge.set(
            "SpaceColonization",
            lua.create_function(|lua, v: Value| new_colonization(lua, v))?,
        )?;
        let shape = lua.create_table()?;
        shape.set(
            "sphere",
            lua.create_function(|lua, v: Value| sphere(lua, &args(lua, "sphere", v)?))?,
        )?;
        shape.set(
            "ellipsoid",
            lua.create_function(|lua, v: Value| ellipsoid(lua, &args(lua, "ellipsoid", v)?))?,
        )?;
        shape.set(
            "box",
            lua.create_function(|lua, v: Value| boxed(lua, &args(lua, "box", v)?))?,
        )?;
        shape.set(
            "capsule",
            lua.create_function(|lua, v: Value| axial(lua, "capsule", &args(lua, "capsule", v)?))?,
        )?;
        shape.set(
            "cylinder",
            lua.create_function(|lua, v: Value| {
                axial(lua, "cylinder", &args(lua, "cylinder", v)?)
            })?,
        )?;
        shape.set(
            "cone",
            lua.create_function(|lua, v: Value| cone(lua, &args(lua, "cone", v)?))?,
        )?;
        shape.set(
            "revolve",
            lua.create_function(|lua, v: Value| revolve(lua, &args(lua, "revolve", v)?))?,
        )?;
        shape.set("mesh", lua.create_function(|lua, v: Value| mesh(lua, v))?)?;
        shape.set(
            "union",
            lua.create_function(|lua, v: Value| union(lua, &args(lua, "union", v)?))?,
        )?;
        shape.set(
            "difference",
            lua.create_function(|lua, v: Value| difference(lua, &args(lua, "difference", v)?))?,
        )?;
        shape.set(
            "predicate",
            lua.create_function(|lua, (f, b): (Value, Value)| predicate(lua, f, b))?,
        )?;
        pge.set("shape", shape)
    }
}

/// An envelope in Lua (`pge.shape.*`); `:contains(p)` tests a point, `:bounds()` returns
/// the two corners.
#[derive(Clone, Debug)]
pub struct LuaShape(pub Shape);

impl UserData for LuaShape {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method("contains", |lua, me, p: LuaVec3| {
            me.0.contains(p.0).map_err(|e| script_error(lua, e))
        });
        m.add_method("bounds", |_, me, ()| {
            let (lo, hi) = me.0.bounds();
            Ok((LuaVec3(lo), LuaVec3(hi)))
        });
        m.add_method("kind", |_, me, ()| Ok(me.0.kind()));
    }
}

impl FromLua for LuaShape {
    fn from_lua(value: Value, _: &Lua) -> mlua::Result<Self> {
        match &value {
            Value::UserData(ud) => ud
                .borrow::<LuaShape>()
                .map(|s| s.clone())
                .map_err(|_| not_a_shape(&value)),
            _ => Err(not_a_shape(&value)),
        }
    }
}

fn not_a_shape(v: &Value) -> mlua::Error {
    mlua::Error::FromLuaConversionError {
        from: v.type_name(),
        to: "shape".into(),
        message: Some("expected a pge.shape".into()),
    }
}

/// The argument table of `pge.shape.NAME{...}`.
fn args(lua: &Lua, name: &str, v: Value) -> mlua::Result<Table> {
    match v {
        Value::Table(t) => Ok(t),
        other => Err(script_error(
            lua,
            format!(
                "pge.shape.{name} takes a table of options, got {}",
                other.type_name()
            ),
        )),
    }
}

/// Reads option `key` (or positional `index`) of `t`.
fn field(t: &Table, key: &str, index: usize) -> mlua::Result<Value> {
    match t.get::<Value>(key)? {
        Value::Nil => t.raw_get::<Value>(index),
        v => Ok(v),
    }
}

fn vec3_opt(lua: &Lua, what: &str, key: &str, v: Value) -> mlua::Result<Option<Vec3>> {
    if v.is_nil() {
        return Ok(None);
    }
    LuaVec3::from_lua(v, lua).map(|v| Some(v.0)).map_err(|e| {
        let why = match &e {
            mlua::Error::FromLuaConversionError {
                message: Some(m), ..
            } => m.clone(),
            other => other.to_string(),
        };
        script_error(
            lua,
            format!("{what}: {key} must be a vector {{x, y, z}}: {why}"),
        )
    })
}

fn vec3(lua: &Lua, what: &str, key: &str, v: Value) -> mlua::Result<Vec3> {
    vec3_opt(lua, what, key, v)?.ok_or_else(|| {
        script_error(
            lua,
            format!("{what}: {key} is required (a vector {{x, y, z}})"),
        )
    })
}

/// A finite number > 0 (`positive`) or >= 0.
fn number_opt(
    lua: &Lua,
    what: &str,
    key: &str,
    v: Value,
    positive: bool,
) -> mlua::Result<Option<f32>> {
    let range = if positive {
        "a number > 0"
    } else {
        "a number >= 0"
    };
    let x = match v {
        Value::Nil => return Ok(None),
        Value::Integer(i) => i as f64,
        Value::Number(n) => n,
        other => {
            return Err(script_error(
                lua,
                format!("{what}: {key} must be {range}, got {}", other.type_name()),
            ));
        }
    };
    if !x.is_finite() || x < 0.0 || (positive && x == 0.0) || x > f32::MAX as f64 {
        return Err(script_error(
            lua,
            format!("{what}: {key} must be {range}, got {x}"),
        ));
    }
    Ok(Some(x as f32))
}

fn number(lua: &Lua, what: &str, key: &str, v: Value) -> mlua::Result<f32> {
    number_opt(lua, what, key, v, true)?
        .ok_or_else(|| script_error(lua, format!("{what}: {key} is required (a number > 0)")))
}

fn integer_opt(
    lua: &Lua,
    what: &str,
    key: &str,
    v: Value,
    lo: i64,
    hi: i64,
) -> mlua::Result<Option<u32>> {
    let bad = |got: String| {
        script_error(
            lua,
            format!("{what}: {key} must be an integer between {lo} and {hi}, got {got}"),
        )
    };
    let i = match v {
        Value::Nil => return Ok(None),
        Value::Integer(i) => i,
        Value::Number(n) if n.fract() == 0.0 && n.abs() < 1e15 => n as i64,
        Value::Number(n) => return Err(bad(n.to_string())),
        other => return Err(bad(other.type_name().to_string())),
    };
    if i < lo || i > hi {
        return Err(bad(i.to_string()));
    }
    Ok(Some(i as u32))
}

fn shape_of(lua: &Lua, what: &str, key: &str, v: Value) -> mlua::Result<Shape> {
    let type_name = v.type_name();
    let hint = if matches!(v, Value::UserData(_)) {
        " (a mesh or model becomes a shape with pge.shape.mesh{model = m})"
    } else {
        ""
    };
    LuaShape::from_lua(v, lua).map(|s| s.0).map_err(|_| {
        script_error(
            lua,
            format!("{what}: {key} must be a shape (pge.shape.*), got {type_name}{hint}"),
        )
    })
}

fn sphere(lua: &Lua, t: &Table) -> mlua::Result<LuaShape> {
    let w = "pge.shape.sphere";
    let center = vec3_opt(lua, w, "center", field(t, "center", 1)?)?.unwrap_or(Vec3::ZERO);
    let radius = number(lua, w, "radius", field(t, "radius", 2)?)?;
    Ok(LuaShape(Shape::Sphere { center, radius }))
}

fn ellipsoid(lua: &Lua, t: &Table) -> mlua::Result<LuaShape> {
    let w = "pge.shape.ellipsoid";
    let center = vec3_opt(lua, w, "center", field(t, "center", 1)?)?.unwrap_or(Vec3::ZERO);
    let radii = vec3(lua, w, "radii", field(t, "radii", 2)?)?;
    if radii.min_element() <= 0.0 {
        return Err(script_error(
            lua,
            format!(
                "{w}: radii must all be > 0, got ({}, {}, {})",
                radii.x, radii.y, radii.z
            ),
        ));
    }
    Ok(LuaShape(Shape::Ellipsoid { center, radii }))
}

fn boxed(lua: &Lua, t: &Table) -> mlua::Result<LuaShape> {
    let w = "pge.shape.box";
    let min = vec3(lua, w, "min", field(t, "min", 1)?)?;
    let max = vec3(lua, w, "max", field(t, "max", 2)?)?;
    if min.cmpge(max).any() {
        return Err(script_error(
            lua,
            format!("{w}: min must be below max on every axis (a box with volume)"),
        ));
    }
    Ok(LuaShape(Shape::Box { min, max }))
}

fn axial(lua: &Lua, name: &str, t: &Table) -> mlua::Result<LuaShape> {
    let w = format!("pge.shape.{name}");
    let a = vec3(lua, &w, "a", field(t, "a", 1)?)?;
    let b = vec3(lua, &w, "b", field(t, "b", 2)?)?;
    let radius = number(lua, &w, "radius", field(t, "radius", 3)?)?;
    if name == "cylinder" && a == b {
        return Err(script_error(
            lua,
            format!("{w}: a and b must differ (the cylinder's axis)"),
        ));
    }
    Ok(LuaShape(if name == "capsule" {
        Shape::Capsule { a, b, radius }
    } else {
        Shape::Cylinder { a, b, radius }
    }))
}

fn cone(lua: &Lua, t: &Table) -> mlua::Result<LuaShape> {
    let w = "pge.shape.cone";
    let base = vec3(lua, w, "base", field(t, "base", 1)?)?;
    let apex = vec3(lua, w, "apex", field(t, "apex", 2)?)?;
    let radius = number(lua, w, "radius", field(t, "radius", 3)?)?;
    if base == apex {
        return Err(script_error(lua, format!("{w}: base and apex must differ")));
    }
    Ok(LuaShape(Shape::Cone { base, apex, radius }))
}

fn revolve(lua: &Lua, t: &Table) -> mlua::Result<LuaShape> {
    let w = "pge.shape.revolve";
    let profile = match field(t, "profile", 1)? {
        Value::Table(p) => p,
        other => {
            return Err(script_error(
                lua,
                format!(
                    "{w}: profile must be a list of {{r, y}} points, got {}",
                    other.type_name()
                ),
            ));
        }
    };
    let mut points = Vec::new();
    for (k, item) in profile.sequence_values::<Value>().enumerate() {
        let bad = |why: &str| script_error(lua, format!("{w}: profile[{}] {why}", k + 1));
        let Value::Table(pt) = item? else {
            return Err(bad("must be a point {r, y}"));
        };
        let get = |i: usize, key: &str| -> mlua::Result<Option<f64>> {
            Ok(match field(&pt, key, i)? {
                Value::Integer(v) => Some(v as f64),
                Value::Number(v) => Some(v),
                _ => None,
            })
        };
        let (Some(r), Some(y)) = (get(1, "r")?, get(2, "y")?) else {
            return Err(bad("must be a point {r, y} of two numbers"));
        };
        if !r.is_finite() || !y.is_finite() || r < 0.0 {
            return Err(bad(&format!(
                "must have a finite r >= 0 and a finite y, got {{{r}, {y}}}"
            )));
        }
        points.push(Vec2::new(r as f32, y as f32));
    }
    if points.len() < 3 {
        return Err(script_error(
            lua,
            format!(
                "{w}: profile needs at least 3 points {{r, y}}, got {}",
                points.len()
            ),
        ));
    }
    let center = vec3_opt(lua, w, "center", t.get("center")?)?.unwrap_or(Vec3::ZERO);
    Ok(LuaShape(Shape::Revolve {
        profile: points.into(),
        center,
    }))
}

fn mesh(lua: &Lua, v: Value) -> mlua::Result<LuaShape> {
    let w = "pge.shape.mesh";
    // `pge.shape.mesh{path = "x.obj"}`, `{"x.obj"}`, `{model = m}`, or a model/mesh itself.
    let (path, model) = match &v {
        Value::String(s) => (Some(s.to_string_lossy()), None),
        Value::Table(t) => {
            let path = match field(t, "path", 1)? {
                Value::String(s) => Some(s.to_string_lossy()),
                Value::Nil | Value::UserData(_) | Value::Table(_) => None,
                other => {
                    return Err(script_error(
                        lua,
                        format!("{w}: path must be a file name, got {}", other.type_name()),
                    ));
                }
            };
            let model = match t.get::<Value>("model")? {
                Value::Nil => match t.raw_get::<Value>(1)? {
                    m @ (Value::UserData(_) | Value::Table(_)) => Some(m),
                    _ => None,
                },
                m => Some(m),
            };
            (path, model)
        }
        Value::UserData(_) => (None, Some(v.clone())),
        other => {
            return Err(script_error(
                lua,
                format!(
                    "{w} takes {{path = \"file.obj\"}} or {{model = m}}, got {}",
                    other.type_name()
                ),
            ));
        }
    };
    let (name, (positions, triangles)) = match (path, model) {
        (Some(path), None) => {
            let file = resolve_path(lua, &path)
                .map_err(|e| script_error(lua, format!("{w}: {}", unlocated(lua, &e))))?;
            let bytes = std::fs::read(&file)
                .map_err(|e| script_error(lua, format!("{w}: cannot read '{path}': {e}")))?;
            let lower = path.to_ascii_lowercase();
            let parsed = if lower.ends_with(".obj") {
                let text = String::from_utf8_lossy(&bytes);
                TriMesh::parse_obj(&text)
            } else if lower.ends_with(".glb") || lower.ends_with(".gltf") {
                TriMesh::parse_gltf(&bytes)
            } else {
                return Err(script_error(
                    lua,
                    format!("{w}: '{path}' must be an .obj, .glb or .gltf file"),
                ));
            };
            (
                path.clone(),
                parsed.map_err(|e| script_error(lua, format!("{w}: '{path}': {e}")))?,
            )
        }
        (None, Some(m)) => {
            let model = to_model(&m)
                .map_err(|e| script_error(lua, format!("{w}: model: {}", unlocated(lua, &e))))?;
            ("model".to_string(), TriMesh::model_triangles(&model))
        }
        (Some(_), Some(_)) => {
            return Err(script_error(
                lua,
                format!("{w}: give either path or model, not both"),
            ));
        }
        (None, None) => {
            return Err(script_error(
                lua,
                format!("{w}: needs path = \"file.obj\" (or .glb) or model = a model"),
            ));
        }
    };
    // `transform = pge.mat4...` places the mesh (a unit crown scaled to the tree's size).
    let transform = match &v {
        Value::Table(t) => match t.get::<Value>("transform")? {
            Value::Nil => None,
            m => Some(
                LuaMat4::from_lua(m, lua)
                    .map_err(|_| script_error(lua, format!("{w}: transform must be a pge.mat4")))?
                    .0,
            ),
        },
        _ => None,
    };
    let positions: Vec<Vec3> = match transform {
        Some(m) => positions.iter().map(|p| m.transform_point3(*p)).collect(),
        None => positions,
    };
    let mesh = TriMesh::new(name.clone(), &positions, &triangles)
        .map_err(|e| script_error(lua, format!("{w}: '{name}' {e}")))?;
    Ok(LuaShape(Shape::Mesh(Rc::new(mesh))))
}

fn union(lua: &Lua, t: &Table) -> mlua::Result<LuaShape> {
    let mut parts = Vec::new();
    for (k, v) in t.sequence_values::<Value>().enumerate() {
        parts.push(shape_of(
            lua,
            "pge.shape.union",
            &format!("[{}]", k + 1),
            v?,
        )?);
    }
    if parts.is_empty() {
        return Err(script_error(
            lua,
            "pge.shape.union needs at least one shape: pge.shape.union{a, b, ...}",
        ));
    }
    Ok(LuaShape(Shape::Union(parts.into())))
}

fn difference(lua: &Lua, t: &Table) -> mlua::Result<LuaShape> {
    let w = "pge.shape.difference";
    let a = shape_of(lua, w, "a", field(t, "a", 1)?)?;
    let b = shape_of(lua, w, "b", field(t, "b", 2)?)?;
    Ok(LuaShape(Shape::Difference(Rc::new(a), Rc::new(b))))
}

fn predicate(lua: &Lua, f: Value, bounds: Value) -> mlua::Result<LuaShape> {
    let w = "pge.shape.predicate";
    let Value::Function(f) = f else {
        return Err(script_error(
            lua,
            format!(
                "{w}(f, bounds): f must be a function(p) returning true inside, got {}",
                f.type_name()
            ),
        ));
    };
    let (min, max) = match bounds {
        Value::UserData(_) => shape_of(lua, w, "bounds", bounds)?.bounds(),
        Value::Table(t) => (
            vec3(lua, w, "bounds.min", field(&t, "min", 1)?)?,
            vec3(lua, w, "bounds.max", field(&t, "max", 2)?)?,
        ),
        other => {
            return Err(script_error(
                lua,
                format!(
                    "{w}(f, bounds): bounds must be {{min = v, max = v}} or a shape, got {}",
                    other.type_name()
                ),
            ));
        }
    };
    if min.cmpge(max).any() {
        return Err(script_error(
            lua,
            format!("{w}: bounds.min must be below bounds.max on every axis"),
        ));
    }
    let location = caller_location(lua);
    let test = move |p: Vec3| -> pge_engine::Result<bool> { call_predicate(&f, p, &location) };
    Ok(LuaShape(Shape::Predicate {
        test: Rc::new(test),
        min,
        max,
    }))
}

fn call_predicate(
    f: &Function,
    p: Vec3,
    location: &pge_engine::Location,
) -> pge_engine::Result<bool> {
    match f.call::<Value>(LuaVec3(p)) {
        Ok(v) => Ok(!matches!(v, Value::Nil | Value::Boolean(false))),
        Err(e) => Err(match f.weak_lua().try_upgrade() {
            Some(lua) => to_engine_error(&lua, e),
            None => pge_engine::Error::script(location.clone(), format!("predicate failed: {e}")),
        }),
    }
}

/// The first line of an error's message without a leading `FILE:LINE: ` of the calling
/// code (errors from the engine's helpers are already located; ours add the location again).
fn unlocated(lua: &Lua, e: &mlua::Error) -> String {
    let line = first_line(e);
    let prefix = format!("{}: ", caller_location(lua));
    line.strip_prefix(&prefix)
        .map(str::to_string)
        .unwrap_or(line)
}

fn first_line(e: &mlua::Error) -> String {
    let s = match e {
        mlua::Error::RuntimeError(m) => m.clone(),
        mlua::Error::CallbackError { cause, .. } => return first_line(cause),
        other => other.to_string(),
    };
    s.lines().next().unwrap_or("").to_string()
}

const OPTIONS: &[&str] = &[
    "envelope",
    "points",
    "mode",
    "thickness",
    "influence",
    "kill",
    "step",
    "tropism",
    "root",
    "roots",
    "trunk",
    "maxIterations",
    "seed",
    "radius",
    "smoothing",
    "sides",
    "leaves",
    "mesh",
    "start",
];

fn new_colonization(lua: &Lua, v: Value) -> mlua::Result<AlgorithmHandle> {
    let w = "pge.SpaceColonization";
    let Value::Table(t) = v else {
        return Err(script_error(
            lua,
            format!("{w} takes a table of options, got {}", v.type_name()),
        ));
    };
    for pair in t.pairs::<Value, Value>() {
        let (k, _) = pair?;
        if let Value::String(s) = &k {
            let name = s.to_string_lossy();
            if !OPTIONS.contains(&name.as_str()) {
                return Err(script_error(
                    lua,
                    format!(
                        "{w}: '{name}' is not an option (known: {})",
                        OPTIONS.join(", ")
                    ),
                ));
            }
        }
    }
    let envelope = match t.get::<Value>("envelope")? {
        Value::Nil => {
            return Err(script_error(
                lua,
                format!("{w}: envelope is required (a pge.shape.*)"),
            ));
        }
        v => shape_of(lua, w, "envelope", v)?,
    };
    let mut p = Params::new(envelope);
    p.points = integer_opt(lua, w, "points", t.get("points")?, 1, 10_000_000)?;
    let thickness = number_opt(lua, w, "thickness", t.get("thickness")?, true)?;
    p.mode = match t.get::<Value>("mode")? {
        Value::Nil => Mode::Fill,
        Value::String(s) => match s.to_string_lossy().as_str() {
            "fill" => Mode::Fill,
            "vertices" => Mode::Vertices,
            "surround" => {
                let (lo, hi) = p.envelope.bounds();
                Mode::Surround {
                    thickness: thickness.unwrap_or(0.15 * (hi - lo).min_element().max(0.0)),
                }
            }
            other => {
                return Err(script_error(
                    lua,
                    format!(
                        "{w}: mode must be \"fill\", \"surround\" or \"vertices\", got \"{other}\""
                    ),
                ));
            }
        },
        other => {
            return Err(script_error(
                lua,
                format!(
                    "{w}: mode must be \"fill\", \"surround\" or \"vertices\", got {}",
                    other.type_name()
                ),
            ));
        }
    };
    if let Some(step) = number_opt(lua, w, "step", t.get("step")?, true)? {
        // Influence and kill defaults follow the step.
        p.influence = 8.0 * step;
        p.kill = 2.0 * step;
        p.step = step;
    }
    let influence = number_opt(lua, w, "influence", t.get("influence")?, true)?;
    let kill = number_opt(lua, w, "kill", t.get("kill")?, true)?;
    // A default never contradicts a value the script gave: an unset kill stays below a
    // given influence, an unset influence above a given kill.
    match (influence, kill) {
        (Some(i), Some(k)) => (p.influence, p.kill) = (i, k),
        (Some(i), None) => (p.influence, p.kill) = (i, p.kill.min(0.25 * i)),
        (None, Some(k)) => (p.influence, p.kill) = (p.influence.max(4.0 * k), k),
        (None, None) => {}
    }
    if let Some(v) = vec3_opt(lua, w, "tropism", t.get("tropism")?)? {
        p.tropism = v;
    }
    if let Some(v) = vec3_opt(lua, w, "root", t.get("root")?)? {
        p.roots = vec![v];
    }
    match t.get::<Value>("roots")? {
        Value::Nil => {}
        Value::Table(list) => {
            let mut roots = Vec::new();
            for (k, r) in list.sequence_values::<Value>().enumerate() {
                roots.push(vec3(lua, w, &format!("roots[{}]", k + 1), r?)?);
            }
            if roots.is_empty() {
                return Err(script_error(
                    lua,
                    format!("{w}: roots must be a non-empty list of vectors"),
                ));
            }
            p.roots = roots;
        }
        other => {
            return Err(script_error(
                lua,
                format!(
                    "{w}: roots must be a list of vectors, got {}",
                    other.type_name()
                ),
            ));
        }
    }
    if let Some(v) = number_opt(lua, w, "trunk", t.get("trunk")?, false)? {
        p.trunk = v;
    }
    if let Some(n) = integer_opt(
        lua,
        w,
        "maxIterations",
        t.get("maxIterations")?,
        1,
        1_000_000,
    )? {
        p.max_iterations = n;
    }
    match t.get::<Value>("seed")? {
        Value::Nil => {}
        Value::Integer(i) if i >= 0 => p.seed = i as u64,
        Value::Number(n) if n >= 0.0 && n.fract() == 0.0 && n < 9.0e15 => p.seed = n as u64,
        other => {
            let shown = match other {
                Value::Integer(i) => i.to_string(),
                Value::Number(n) => n.to_string(),
                v => v.type_name().to_string(),
            };
            return Err(script_error(
                lua,
                format!("{w}: seed must be an integer >= 0, got {shown}"),
            ));
        }
    }
    match t.get::<Value>("start")? {
        Value::Nil => {}
        v => match pge_engine::lua::skeleton_from_value(&v) {
            Some(s) => p.start = Some(std::sync::Arc::new(s)),
            None => {
                return Err(script_error(
                    lua,
                    format!(
                        "{w}: start must be a skeleton (pge.Skeleton, e.g. from handle:skeleton()), got {}",
                        v.type_name()
                    ),
                ));
            }
        },
    }
    p.tree = pge_tree::lua::options_from_lua(lua, w, &t)?;
    let location = caller_location(lua);
    let sc = SpaceColonization::new(p, location).map_err(|e| match e {
        pge_engine::Error::Script { message, .. } => script_error(lua, format!("{w}: {message}")),
        other => script_error(lua, other),
    })?;
    Ok(AlgorithmHandle::new(Box::new(sc)))
}
