//! `pge.shape.*`: the envelopes of space colonization in Lua, read with the engine's
//! options reader (`pge.shape.sphere{ center = {0, 4, 0}, radius = 2 }`, or positionally
//! `pge.shape.sphere{ {0, 4, 0}, 2 }`).

use std::rc::Rc;

use glam::{Vec2, Vec3};
use mlua::{FromLua, Function, Lua, Table, UserData, UserDataMethods, Value};
use pge_engine::lua::{
    LuaMat4, LuaVec3, Options, caller_location, error_message, read_file, resolve_path,
    script_error, to_engine_error, to_model,
};

use crate::shape::Shape;
use crate::trimesh::TriMesh;

/// The `pge.shape` table.
pub(super) fn shape_table(lua: &Lua) -> mlua::Result<Table> {
    let shape = lua.create_table()?;
    type Make = fn(&Options) -> mlua::Result<LuaShape>;
    let makers: [(&str, &[&'static str], Make); 9] = [
        ("sphere", &["center", "radius"], sphere),
        ("ellipsoid", &["center", "radii"], ellipsoid),
        ("box", &["min", "max"], boxed),
        ("capsule", &["a", "b", "radius"], capsule),
        ("cylinder", &["a", "b", "radius"], cylinder),
        ("cone", &["base", "apex", "radius"], cone),
        ("revolve", &["profile"], revolve),
        ("union", &[], union),
        ("difference", &["a", "b"], difference),
    ];
    for (name, positional, make) in makers {
        shape.set(
            name,
            lua.create_function(move |lua, v: Value| {
                let what = format!("pge.shape.{name}");
                let o = Options::table_required(lua, v, &what)?.positional(positional);
                make(&o)
            })?,
        )?;
    }
    shape.set("mesh", lua.create_function(|lua, v: Value| mesh(lua, v))?)?;
    shape.set(
        "predicate",
        lua.create_function(|lua, (f, b): (Value, Value)| predicate(lua, f, b))?,
    )?;
    Ok(shape)
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

/// A required vector option.
fn vec3(o: &Options, key: &str) -> mlua::Result<Vec3> {
    o.vec3(key)?
        .ok_or_else(|| o.missing(key, "a vector {x, y, z}"))
}

/// A required option > 0.
fn positive(o: &Options, key: &str) -> mlua::Result<f32> {
    o.positive(key)?
        .ok_or_else(|| o.missing(key, "a number > 0"))
}

/// Option `key` as a shape, with a hint when a model was given instead.
pub(super) fn shape_of(o: &Options, key: &str, v: Value) -> mlua::Result<Shape> {
    let type_name = v.type_name();
    let hint = if matches!(v, Value::UserData(_)) {
        " (a mesh or model becomes a shape with pge.shape.mesh{model = m})"
    } else {
        ""
    };
    LuaShape::from_lua(v, o.lua()).map(|s| s.0).map_err(|_| {
        o.problem(
            key,
            format!("must be a shape (pge.shape.*), got {type_name}{hint}"),
        )
    })
}

fn sphere(o: &Options) -> mlua::Result<LuaShape> {
    let center = o.vec3("center")?.unwrap_or(Vec3::ZERO);
    let radius = positive(o, "radius")?;
    o.finish()?;
    Ok(LuaShape(Shape::Sphere { center, radius }))
}

fn ellipsoid(o: &Options) -> mlua::Result<LuaShape> {
    let center = o.vec3("center")?.unwrap_or(Vec3::ZERO);
    let radii = vec3(o, "radii")?;
    o.finish()?;
    if radii.min_element() <= 0.0 {
        return Err(o.problem(
            "radii",
            format!(
                "must all be > 0, got ({}, {}, {})",
                radii.x, radii.y, radii.z
            ),
        ));
    }
    Ok(LuaShape(Shape::Ellipsoid { center, radii }))
}

fn boxed(o: &Options) -> mlua::Result<LuaShape> {
    let min = vec3(o, "min")?;
    let max = vec3(o, "max")?;
    o.finish()?;
    if min.cmpge(max).any() {
        return Err(o.problem("min", "must be below max on every axis (a box with volume)"));
    }
    Ok(LuaShape(Shape::Box { min, max }))
}

fn capsule(o: &Options) -> mlua::Result<LuaShape> {
    let a = vec3(o, "a")?;
    let b = vec3(o, "b")?;
    let radius = positive(o, "radius")?;
    o.finish()?;
    Ok(LuaShape(Shape::Capsule { a, b, radius }))
}

fn cylinder(o: &Options) -> mlua::Result<LuaShape> {
    let a = vec3(o, "a")?;
    let b = vec3(o, "b")?;
    let radius = positive(o, "radius")?;
    o.finish()?;
    if a == b {
        return Err(o.error("a and b must differ (the cylinder's axis)"));
    }
    Ok(LuaShape(Shape::Cylinder { a, b, radius }))
}

fn cone(o: &Options) -> mlua::Result<LuaShape> {
    let base = vec3(o, "base")?;
    let apex = vec3(o, "apex")?;
    let radius = positive(o, "radius")?;
    o.finish()?;
    if base == apex {
        return Err(o.error("base and apex must differ"));
    }
    Ok(LuaShape(Shape::Cone { base, apex, radius }))
}

fn revolve(o: &Options) -> mlua::Result<LuaShape> {
    let profile = match o.value("profile")? {
        Value::Table(p) => p,
        other => return Err(o.wrong_type("profile", "a list of {r, y} points", &other)),
    };
    let mut points = Vec::new();
    for (k, item) in profile.sequence_values::<Value>().enumerate() {
        let key = format!("profile[{}]", k + 1);
        let Value::Table(pt) = item? else {
            return Err(o.problem(&key, "must be a point {r, y}"));
        };
        let get = |i: usize, name: &str| -> mlua::Result<Option<f64>> {
            Ok(match field(&pt, name, i)? {
                Value::Integer(v) => Some(v as f64),
                Value::Number(v) => Some(v),
                _ => None,
            })
        };
        let (Some(r), Some(y)) = (get(1, "r")?, get(2, "y")?) else {
            return Err(o.problem(&key, "must be a point {r, y} of two numbers"));
        };
        if !r.is_finite() || !y.is_finite() || r < 0.0 {
            return Err(o.problem(
                &key,
                format!("must have a finite r >= 0 and a finite y, got {{{r}, {y}}}"),
            ));
        }
        points.push(Vec2::new(r as f32, y as f32));
    }
    if points.len() < 3 {
        return Err(o.problem(
            "profile",
            format!("needs at least 3 points {{r, y}}, got {}", points.len()),
        ));
    }
    let center = o.vec3("center")?.unwrap_or(Vec3::ZERO);
    o.finish()?;
    Ok(LuaShape(Shape::Revolve {
        profile: points.into(),
        center,
    }))
}

/// Entry `key` of `t`, or its positional entry `index` (a point `{r = 1, y = 2}` or `{1, 2}`;
/// a mesh's `{path = "x.obj"}` or `{"x.obj"}`).
fn field(t: &Table, key: &str, index: usize) -> mlua::Result<Value> {
    match t.get::<Value>(key)? {
        Value::Nil => t.raw_get::<Value>(index),
        v => Ok(v),
    }
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
                .map_err(|e| script_error(lua, format!("{w}: {}", error_message(lua, &e))))?;
            let bytes = read_file(lua, &file)
                .map_err(|e| script_error(lua, format!("{w}: cannot read '{path}': {e}")))?;
            let lower = path.to_ascii_lowercase();
            let parsed: Result<_, Box<dyn std::error::Error>> = if lower.ends_with(".obj") {
                let text = String::from_utf8_lossy(&bytes);
                TriMesh::parse_obj(&text).map_err(Into::into)
            } else if lower.ends_with(".glb") || lower.ends_with(".gltf") {
                pge_engine::import::scene_triangles(&bytes).map_err(Into::into)
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
            let model = to_model(&m).map_err(|e| {
                script_error(lua, format!("{w}: model: {}", error_message(lua, &e)))
            })?;
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

fn union(o: &Options) -> mlua::Result<LuaShape> {
    let mut parts = Vec::new();
    if let Some(t) = o.table() {
        for (k, v) in t.sequence_values::<Value>().enumerate() {
            parts.push(shape_of(o, &format!("[{}]", k + 1), v?)?);
        }
    }
    if parts.is_empty() {
        return Err(script_error(
            o.lua(),
            "pge.shape.union needs at least one shape: pge.shape.union{a, b, ...}",
        ));
    }
    checked(o, Shape::Union(parts.into()))
}

/// A union or difference, refused past the nesting and size limits.
fn checked(o: &Options, shape: Shape) -> mlua::Result<LuaShape> {
    shape.check_size().map_err(|e| o.error(e))?;
    Ok(LuaShape(shape))
}

fn difference(o: &Options) -> mlua::Result<LuaShape> {
    let a = shape_of(o, "a", o.value("a")?)?;
    let b = shape_of(o, "b", o.value("b")?)?;
    o.finish()?;
    checked(o, Shape::Difference(Rc::new(a), Rc::new(b)))
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
        Value::UserData(_) => {
            let o = Options::from_table(lua, lua.create_table()?, w);
            shape_of(&o, "bounds", bounds)?.bounds()
        }
        Value::Table(t) => {
            let o = Options::from_table(lua, lua.create_table()?, w);
            let o = o.child("bounds", t).positional(&["min", "max"]);
            let bounds = (vec3(&o, "min")?, vec3(&o, "max")?);
            o.finish()?;
            bounds
        }
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

#[cfg(test)]
mod tests {
    use pge_engine::{Engine, Session, SessionOptions};

    fn session() -> Session {
        let engine = Engine::builder()
            .plugin(crate::SpaceColonizationPlugin)
            .build()
            .expect("engine");
        engine.session(SessionOptions::default()).expect("session")
    }

    #[test]
    fn shapes_read_named_or_positional_options_and_refuse_unknown_ones() {
        let s = session();
        let kind: String = s
            .eval("return pge.shape.sphere{ {0, 1, 0}, 2 }:kind()")
            .expect("positional");
        assert_eq!(kind, "sphere");
        let inside: bool = s
            .eval("return pge.shape.box{ min = {0, 0, 0}, max = {1, 1, 1} }:contains({0.5, 0.5, 0.5})")
            .expect("named");
        assert!(inside);
        let cases = [
            (
                "pge.shape.sphere{ centre = {0, 0, 0}, radius = 1 }",
                "eval:1: pge.shape.sphere: unknown option 'centre': 'centre' is not an option \
                 (known: center, radius)",
            ),
            (
                "pge.shape.sphere{ center = {0, 0, 0} }",
                "eval:1: pge.shape.sphere: radius is required (a number > 0)",
            ),
            (
                "pge.shape.cone{ base = {0, 0, 0}, apex = {0, 0, 0}, radius = 1 }",
                "eval:1: pge.shape.cone: base and apex must differ",
            ),
            (
                "pge.shape.sphere(3)",
                "eval:1: pge.shape.sphere takes a table of options, got integer",
            ),
            (
                "pge.shape.difference{ 1, 2 }",
                "eval:1: pge.shape.difference: a must be a shape (pge.shape.*), got integer",
            ),
        ];
        for (code, want) in cases {
            let e = s
                .eval::<()>(&format!("local s = {code}"))
                .expect_err(code)
                .to_string();
            assert_eq!(e, want, "{code}");
        }
    }
}
