//! `pge.mesh` and `pge.model`: geometry built in scripts.

use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3, Vec4};
use mlua::{
    AnyUserData, FromLua, IntoLua, Lua, ObjectLike, Table, UserData, UserDataMethods, Value,
};

use super::errors::script_error;
use super::held;
use super::math::LuaMat4;
use super::sandbox::{read_file, resolve_path};
use crate::RunContext;
use crate::geometry::{AlphaMode, Material, Mesh, Model, Primitive, Texture};

/// A mesh made by `pge.mesh` (or a plugin), shared by the models it is added to. Given to a
/// script (converted to a Lua value), its buffers are charged to the run's memory budget for
/// as long as they live.
#[derive(Clone, Debug)]
pub struct LuaMesh(pub Arc<Mesh>);

/// A model made by `pge.model()` or returned by a generator's `:model()`. Given to a script
/// (converted to a Lua value), its meshes, textures and placements are charged to the run's
/// memory budget for as long as they live: a buffer shared by several values once.
#[derive(Clone, Debug, Default)]
pub struct LuaModel(pub Model);

/// The Lua value of a [`LuaMesh`].
struct MeshValue(Arc<Mesh>);

/// The Lua value of a [`LuaModel`].
struct ModelValue(Model);

impl IntoLua for LuaMesh {
    fn into_lua(self, lua: &Lua) -> mlua::Result<Value> {
        held::charge_mesh(lua, &self.0)?;
        lua.create_userdata(MeshValue(self.0)).map(Value::UserData)
    }
}

impl IntoLua for LuaModel {
    fn into_lua(self, lua: &Lua) -> mlua::Result<Value> {
        held::charge_model(lua, &self.0)?;
        let placements = placement_bytes(&self.0);
        let value = lua.create_userdata(ModelValue(self.0))?;
        super::charge(lua, &value, placements, "the placements of a model")?;
        Ok(Value::UserData(value))
    }
}

/// The bytes of a model's own placements (its instances and its groups' transforms), which
/// no other value shares.
fn placement_bytes(model: &Model) -> usize {
    std::mem::size_of_val(model.instances.as_slice())
        + model
            .groups
            .iter()
            .map(|g| std::mem::size_of_val(g.transforms.as_slice()))
            .sum::<usize>()
}

/// Whether a script value is a model or a mesh (`pge.model()`, `pge.mesh{...}`, a
/// generator's `:model()`).
#[must_use]
pub fn is_model_or_mesh(value: &AnyUserData) -> bool {
    value.is::<ModelValue>() || value.is::<MeshValue>()
}

impl UserData for MeshValue {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method("vertexCount", |_, me, ()| Ok(me.0.vertex_count()));
        m.add_method("triangleCount", |_, me, ()| Ok(me.0.triangle_count()));
        m.add_method("model", |_, me, ()| {
            Ok(LuaModel(Model::from_mesh(me.0.clone())))
        });
    }
}

impl UserData for ModelValue {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_function(
            "add",
            |lua, (ud, thing, transform): (AnyUserData, Value, Option<LuaMat4>)| {
                let other = to_model(&thing).map_err(|e| match e {
                    mlua::Error::RuntimeError(_) => e,
                    // Already located where it happened (a modeller's own :model()).
                    e if super::errors::engine_error_of(&e).is_some() => e,
                    other => script_error(lua, format!("model:add: {other}")),
                })?;
                let placements = {
                    let mut me = ud.borrow_mut::<ModelValue>()?;
                    me.0.add_model(&other, transform.map_or(Mat4::IDENTITY, |t| t.0));
                    placement_bytes(&me.0)
                };
                super::recharge(lua, &ud, placements, "the placements of a model")
            },
        );
        m.add_method("vertexCount", |_, me, ()| Ok(me.0.vertex_count()));
        m.add_method("triangleCount", |_, me, ()| Ok(me.0.triangle_count()));
        m.add_method("meshCount", |_, me, ()| Ok(me.0.meshes.len()));
        m.add_method_mut("setEnvironment", |lua, me, image: Value| {
            let mut tex = texture_from_value(lua, &image, "model:setEnvironment")?;
            if tex.name == "texture" {
                Arc::make_mut(&mut tex).name = "environment".into();
            }
            me.0.environment = Some(tex);
            held::charge_model(lua, &me.0)
        });
        m.add_method("instanceCount", |_, me, ()| Ok(me.0.instances.len()));
        m.add_function("model", |_, me: AnyUserData| Ok(me));
    }
}

/// The model of a script value: a [`LuaModel`], a [`LuaMesh`], or anything with a `:model()`
/// method (a modeller, a turtle) whose result is one of those.
pub fn to_model(value: &Value) -> mlua::Result<Model> {
    to_model_depth(value, None, 0)
}

/// The model of a script value as [`to_model`] makes it, for code that runs with a
/// [`RunContext`] (an algorithm's `finish`): a host object whose type registered a model
/// maker ([`register_model_maker`](super::services::register_model_maker)) is modelled with
/// `ctx` (its seed, its deadline) rather than through its Lua `:model()` method.
pub fn to_model_in(lua: &Lua, value: &Value, ctx: &RunContext) -> mlua::Result<Model> {
    to_model_depth(value, Some((lua, ctx)), 0)
}

fn to_model_depth(
    value: &Value,
    ctx: Option<(&Lua, &RunContext)>,
    depth: usize,
) -> mlua::Result<Model> {
    let not_a_model = || {
        mlua::Error::RuntimeError(format!(
            "expected a model, a mesh or an object with a :model() method, got {}",
            value.type_name()
        ))
    };
    if depth > 4 {
        return Err(not_a_model());
    }
    let produced: Value = match value {
        Value::UserData(ud) => {
            if let Ok(m) = ud.borrow::<ModelValue>() {
                return Ok(m.0.clone());
            }
            if let Ok(m) = ud.borrow::<MeshValue>() {
                return Ok(Model::from_mesh(m.0.clone()));
            }
            if let Some((lua, ctx)) = ctx
                && let Some(model) = super::services::make_model(lua, ud, ctx)?
            {
                return Ok(model);
            }
            match ud.get::<Value>("model") {
                Ok(Value::Function(_)) => ud.call_method("model", ())?,
                _ => return Err(not_a_model()),
            }
        }
        Value::Table(t) => match t.get::<Value>("model")? {
            Value::Function(_) => t.call_method("model", ())?,
            _ => return Err(not_a_model()),
        },
        _ => return Err(not_a_model()),
    };
    to_model_depth(&produced, ctx, depth + 1)
}

fn floats(lua: &Lua, t: &Table, key: &str, per: usize) -> mlua::Result<Option<Vec<f32>>> {
    let v: Value = t.raw_get(key)?;
    let Value::Table(arr) = v else {
        return match v {
            Value::Nil => Ok(None),
            other => Err(script_error(
                lua,
                format!(
                    "pge.mesh: {key} must be an array of numbers, not {}",
                    other.type_name()
                ),
            )),
        };
    };
    let n = arr.raw_len();
    let mut out = Vec::with_capacity(n);
    for i in 1..=n {
        let x = match arr.raw_get::<Value>(i)? {
            Value::Integer(k) => k as f64,
            Value::Number(x) => x,
            other => {
                return Err(script_error(
                    lua,
                    format!(
                        "pge.mesh: {key}[{i}] is a {}, not a number",
                        other.type_name()
                    ),
                ));
            }
        };
        if !x.is_finite() {
            return Err(script_error(
                lua,
                format!("pge.mesh: {key}[{i}] is NaN or infinite"),
            ));
        }
        out.push(x as f32);
    }
    if n % per != 0 {
        return Err(script_error(
            lua,
            format!("pge.mesh: {key} has {n} numbers, not a multiple of {per}"),
        ));
    }
    Ok(Some(out))
}

/// An image given by a script: a PNG path relative to the script, or an object that makes one
/// (anything with a `pngBytes()` method: `pge.Image`, `img:texture()`). `what` starts errors.
pub fn texture_from_value(lua: &Lua, value: &Value, what: &str) -> mlua::Result<Arc<Texture>> {
    let tex = match value {
        Value::String(path) => {
            let path = path.to_string_lossy();
            let file = resolve_path(lua, &path)?;
            let bytes = read_file(lua, &file)
                .map_err(|e| script_error(lua, format!("{what} '{path}': {e}")))?;
            Texture::from_image_bytes(path.clone(), &bytes)
                .map_err(|e| script_error(lua, format!("{what} '{path}': {e}")))?
        }
        Value::UserData(_) | Value::Table(_) => {
            let bytes: mlua::LuaString = match value {
                Value::UserData(ud) => ud.call_method("pngBytes", ()),
                Value::Table(tb) => tb.call_method("pngBytes", ()),
                _ => unreachable!("matched above"),
            }
            .map_err(|e| {
                script_error(
                    lua,
                    format!("{what}: expected a PNG path or an object with pngBytes() ({e})"),
                )
            })?;
            Texture::from_image_bytes("texture", &bytes.as_bytes())
                .map_err(|e| script_error(lua, format!("{what}: {e}")))?
        }
        other => {
            return Err(script_error(
                lua,
                format!(
                    "{what} must be a PNG path or an image, not {}",
                    other.type_name()
                ),
            ));
        }
    };
    Ok(Arc::new(tex))
}

/// A material from a script table: `color = "#rrggbb"`, `doubleSided`, `roughness`,
/// `metallic`, `alpha = "opaque"|"mask"|"blend"`, `alphaCutoff`, `texture = "file.png"`,
/// `name`.
pub fn material_from_table(lua: &Lua, t: &Table) -> mlua::Result<Material> {
    let mut m = Material::default();
    if let Some(name) = t.raw_get::<Option<String>>("name")? {
        m.name = name;
    }
    if let Some(c) = t.raw_get::<Option<String>>("color")? {
        m.base_color = crate::geometry::Material::from_hex("", &c)
            .map_err(|e| script_error(lua, format!("material color: {e}")))?
            .base_color;
    }
    m.double_sided = t.raw_get::<Option<bool>>("doubleSided")?.unwrap_or(false);
    let unit = |k: &str, d: f32| -> mlua::Result<f32> {
        match t.raw_get::<Option<f64>>(k)? {
            None => Ok(d),
            Some(x) if (0.0..=1.0).contains(&x) => Ok(x as f32),
            Some(x) => Err(script_error(
                lua,
                format!("material {k} = {x} must be in [0, 1]"),
            )),
        }
    };
    m.roughness = unit("roughness", m.roughness)?;
    m.metallic = unit("metallic", m.metallic)?;
    let cutoff = unit("alphaCutoff", 0.5)?;
    m.alpha = match t.raw_get::<Option<String>>("alpha")?.as_deref() {
        None | Some("opaque") => AlphaMode::Opaque,
        Some("mask") => AlphaMode::Mask(cutoff),
        Some("blend") => AlphaMode::Blend,
        Some(other) => {
            return Err(script_error(
                lua,
                format!("material alpha = '{other}': expected \"opaque\", \"mask\" or \"blend\""),
            ));
        }
    };
    m.texture = match t.raw_get::<Value>("texture")? {
        Value::Nil => None,
        v => Some(texture_from_value(lua, &v, "material texture")?),
    };
    Ok(m)
}

/// `pge.mesh{ positions =, indices = [, normals =, uvs =, colors =, material =, primitive =] }`.
fn make_mesh(lua: &Lua, t: Table) -> mlua::Result<LuaMesh> {
    let positions = floats(lua, &t, "positions", 3)?
        .ok_or_else(|| script_error(lua, "pge.mesh: positions are missing"))?;
    let positions: Vec<Vec3> = positions
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    let primitive = match t.raw_get::<Option<String>>("primitive")?.as_deref() {
        None | Some("triangles") => Primitive::Triangles,
        Some("lines") => Primitive::Lines,
        Some(other) => {
            return Err(script_error(
                lua,
                format!("pge.mesh: primitive '{other}': expected \"triangles\" or \"lines\""),
            ));
        }
    };
    let idx = floats(lua, &t, "indices", primitive.arity())?
        .ok_or_else(|| script_error(lua, "pge.mesh: indices are missing"))?;
    let mut indices = Vec::with_capacity(idx.len());
    for (i, x) in idx.iter().enumerate() {
        if *x < 0.0 || x.fract() != 0.0 || *x as usize >= positions.len() {
            return Err(script_error(
                lua,
                format!(
                    "pge.mesh: indices[{}] = {x} is out of range: indices are 0-based and there are {} vertices",
                    i + 1,
                    positions.len()
                ),
            ));
        }
        indices.push(*x as u32);
    }
    let n = positions.len();
    let per_vertex = |key: &str, got: usize| -> mlua::Result<()> {
        if got != n {
            Err(script_error(
                lua,
                format!("pge.mesh: {key} has {got} entries but there are {n} vertices"),
            ))
        } else {
            Ok(())
        }
    };
    let normals: Vec<Vec3> = match floats(lua, &t, "normals", 3)? {
        Some(v) => {
            per_vertex("normals", v.len() / 3)?;
            v.chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]).normalize_or(Vec3::Y))
                .collect()
        }
        None => Vec::new(),
    };
    let uvs: Vec<Vec2> = match floats(lua, &t, "uvs", 2)? {
        Some(v) => {
            per_vertex("uvs", v.len() / 2)?;
            v.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect()
        }
        None => Vec::new(),
    };
    let colors: Vec<Vec4> = match floats(lua, &t, "colors", 1)? {
        Some(v) if v.len() == 4 * n => v
            .chunks_exact(4)
            .map(|c| Vec4::new(c[0], c[1], c[2], c[3]))
            .collect(),
        Some(v) if v.len() == 3 * n => v
            .chunks_exact(3)
            .map(|c| Vec4::new(c[0], c[1], c[2], 1.0))
            .collect(),
        Some(v) => {
            return Err(script_error(
                lua,
                format!(
                    "pge.mesh: colors has {} numbers; expected 3 or 4 per vertex ({n} vertices)",
                    v.len()
                ),
            ));
        }
        None => Vec::new(),
    };
    let material = match t.raw_get::<Option<Table>>("material")? {
        Some(mt) => material_from_table(lua, &mt)?,
        None => Material::default(),
    };
    let mut mesh = Mesh {
        name: t
            .raw_get::<Option<String>>("name")?
            .unwrap_or_else(|| "mesh".into()),
        primitive,
        positions,
        normals,
        uvs,
        colors,
        indices,
        material: Arc::new(material),
        ..Mesh::default()
    };
    if mesh.normals.is_empty() && primitive == Primitive::Triangles {
        mesh.compute_normals();
    }
    mesh.validate()
        .map_err(|e| script_error(lua, format!("pge.mesh: {e}")))?;
    Ok(LuaMesh(Arc::new(mesh)))
}

impl FromLua for LuaModel {
    fn from_lua(value: Value, _: &Lua) -> mlua::Result<Self> {
        to_model(&value).map(LuaModel)
    }
}

pub(crate) fn register(lua: &Lua, pge: &Table) -> mlua::Result<()> {
    pge.set("mesh", lua.create_function(make_mesh)?)?;
    pge.set(
        "model",
        lua.create_function(|_, ()| Ok(LuaModel::default()))?,
    )?;
    Ok(())
}
