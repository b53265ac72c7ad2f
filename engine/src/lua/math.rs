//! `pge.vec3`, `pge.quat`, `pge.mat4`: glam types as Lua values.

use glam::{Mat4, Quat, Vec3};
use mlua::{FromLua, Lua, MetaMethod, Table, UserData, UserDataFields, UserDataMethods, Value};

use super::errors::script_error;

/// A 3D vector. From Lua it also accepts `{x, y, z}` and `{x =, y =, z =}`; NaN and
/// infinite components are refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LuaVec3(pub Vec3);

/// A rotation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LuaQuat(pub Quat);

/// A 4x4 affine transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LuaMat4(pub Mat4);

fn conversion(from: &Value, to: &'static str, message: String) -> mlua::Error {
    mlua::Error::FromLuaConversionError {
        from: from.type_name(),
        to: to.into(),
        message: Some(message),
    }
}

fn number(v: Value) -> Option<f64> {
    match v {
        Value::Integer(i) => Some(i as f64),
        Value::Number(n) => Some(n),
        _ => None,
    }
}

impl FromLua for LuaVec3 {
    fn from_lua(value: Value, _: &Lua) -> mlua::Result<Self> {
        let v = match &value {
            Value::UserData(ud) => *ud.borrow::<LuaVec3>().map_err(|_| {
                conversion(&value, "vec3", "expected a pge.vec3 or {x, y, z}".into())
            })?,
            Value::Table(t) => {
                let get = |i: usize, k: &str| -> mlua::Result<Option<f64>> {
                    match t.raw_get::<Value>(i)? {
                        Value::Nil => Ok(number(t.raw_get::<Value>(k)?)),
                        v => Ok(number(v)),
                    }
                };
                match (get(1, "x")?, get(2, "y")?, get(3, "z")?) {
                    (Some(x), Some(y), Some(z)) => LuaVec3(Vec3::new(x as f32, y as f32, z as f32)),
                    _ => {
                        return Err(conversion(
                            &value,
                            "vec3",
                            "a vector table needs three numbers {x, y, z}".into(),
                        ));
                    }
                }
            }
            _ => {
                return Err(conversion(
                    &value,
                    "vec3",
                    "expected a pge.vec3 or {x, y, z}".into(),
                ));
            }
        };
        if !v.0.is_finite() {
            return Err(conversion(
                &value,
                "vec3",
                format!(
                    "vector ({}, {}, {}) has a NaN or infinite component",
                    v.0.x, v.0.y, v.0.z
                ),
            ));
        }
        Ok(v)
    }
}

impl FromLua for LuaQuat {
    fn from_lua(value: Value, _: &Lua) -> mlua::Result<Self> {
        match &value {
            Value::UserData(ud) => ud
                .borrow::<LuaQuat>()
                .map(|q| *q)
                .map_err(|_| conversion(&value, "quat", "expected a pge.quat".into())),
            _ => Err(conversion(&value, "quat", "expected a pge.quat".into())),
        }
    }
}

impl FromLua for LuaMat4 {
    fn from_lua(value: Value, _: &Lua) -> mlua::Result<Self> {
        match &value {
            Value::UserData(ud) => ud
                .borrow::<LuaMat4>()
                .map(|m| *m)
                .map_err(|_| conversion(&value, "mat4", "expected a pge.mat4".into())),
            _ => Err(conversion(&value, "mat4", "expected a pge.mat4".into())),
        }
    }
}

fn finite(lua: &Lua, v: Vec3, what: &str) -> mlua::Result<LuaVec3> {
    if v.is_finite() {
        Ok(LuaVec3(v))
    } else {
        Err(script_error(
            lua,
            format!("{what} gives a NaN or infinite vector"),
        ))
    }
}

fn scalar(lua: &Lua, v: &Value, what: &str) -> mlua::Result<f32> {
    match number(v.clone()) {
        Some(n) if n.is_finite() => Ok(n as f32),
        Some(_) => Err(script_error(
            lua,
            format!("{what}: the number is NaN or infinite"),
        )),
        None => Err(script_error(
            lua,
            format!("{what}: expected a number, got {}", v.type_name()),
        )),
    }
}

fn is_vector(v: &Value) -> bool {
    matches!(v, Value::UserData(ud) if ud.is::<LuaVec3>()) || matches!(v, Value::Table(_))
}

impl UserData for LuaVec3 {
    fn add_fields<F: UserDataFields<Self>>(f: &mut F) {
        f.add_field_method_get("x", |_, v| Ok(v.0.x));
        f.add_field_method_get("y", |_, v| Ok(v.0.y));
        f.add_field_method_get("z", |_, v| Ok(v.0.z));
    }

    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method("dot", |_, a, b: LuaVec3| Ok(a.0.dot(b.0)));
        m.add_method("cross", |_, a, b: LuaVec3| Ok(LuaVec3(a.0.cross(b.0))));
        m.add_method("length", |_, a, ()| Ok(a.0.length()));
        m.add_method("distance", |_, a, b: LuaVec3| Ok(a.0.distance(b.0)));
        m.add_method("normalize", |lua, a, ()| match a.0.try_normalize() {
            Some(n) => Ok(LuaVec3(n)),
            None => Err(script_error(lua, "cannot normalize a zero-length vector")),
        });
        m.add_method("lerp", |_, a, (b, t): (LuaVec3, f32)| {
            Ok(LuaVec3(a.0.lerp(b.0, t)))
        });
        m.add_method("unpack", |_, a, ()| Ok((a.0.x, a.0.y, a.0.z)));
        m.add_meta_function(MetaMethod::Add, |lua, (a, b): (LuaVec3, LuaVec3)| {
            finite(lua, a.0 + b.0, "vec3 + vec3")
        });
        m.add_meta_function(MetaMethod::Sub, |lua, (a, b): (LuaVec3, LuaVec3)| {
            finite(lua, a.0 - b.0, "vec3 - vec3")
        });
        m.add_meta_function(MetaMethod::Mul, |lua, (a, b): (Value, Value)| {
            let v = match (is_vector(&a), is_vector(&b)) {
                (true, true) => LuaVec3::from_lua(a, lua)?.0 * LuaVec3::from_lua(b, lua)?.0,
                (true, false) => LuaVec3::from_lua(a, lua)?.0 * scalar(lua, &b, "vec3 * number")?,
                (false, true) => LuaVec3::from_lua(b, lua)?.0 * scalar(lua, &a, "number * vec3")?,
                (false, false) => {
                    return Err(script_error(lua, "vec3 multiplication needs a vector"));
                }
            };
            finite(lua, v, "vec3 *")
        });
        m.add_meta_function(MetaMethod::Div, |lua, (a, b): (LuaVec3, Value)| {
            let s = scalar(lua, &b, "vec3 / number")?;
            finite(lua, a.0 / s, "vec3 / number")
        });
        m.add_meta_method(MetaMethod::Unm, |_, a, ()| Ok(LuaVec3(-a.0)));
        m.add_meta_function(MetaMethod::Eq, |_, (a, b): (LuaVec3, LuaVec3)| {
            Ok(a.0 == b.0)
        });
        m.add_meta_method(MetaMethod::ToString, |_, a, ()| {
            Ok(format!("vec3({}, {}, {})", a.0.x, a.0.y, a.0.z))
        });
    }
}

impl UserData for LuaQuat {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method("inverse", |_, q, ()| Ok(LuaQuat(q.0.inverse())));
        m.add_method("normalize", |_, q, ()| Ok(LuaQuat(q.0.normalize())));
        m.add_meta_function(MetaMethod::Mul, |lua, (a, b): (LuaQuat, Value)| match &b {
            Value::UserData(ud) if ud.is::<LuaQuat>() => Ok(Value::UserData(
                lua.create_userdata(LuaQuat(a.0 * LuaQuat::from_lua(b, lua)?.0))?,
            )),
            _ => {
                let v = LuaVec3::from_lua(b, lua)?;
                Ok(Value::UserData(lua.create_userdata(LuaVec3(a.0 * v.0))?))
            }
        });
        m.add_meta_method(MetaMethod::ToString, |_, q, ()| {
            Ok(format!("quat({}, {}, {}, {})", q.0.x, q.0.y, q.0.z, q.0.w))
        });
    }
}

impl UserData for LuaMat4 {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method("transformPoint", |_, a, p: LuaVec3| {
            Ok(LuaVec3(a.0.transform_point3(p.0)))
        });
        m.add_method("transformVector", |_, a, p: LuaVec3| {
            Ok(LuaVec3(a.0.transform_vector3(p.0)))
        });
        m.add_method("inverse", |lua, a, ()| {
            let inv = a.0.inverse();
            if inv.is_finite() {
                Ok(LuaMat4(inv))
            } else {
                Err(script_error(lua, "mat4:inverse(): the matrix is singular"))
            }
        });
        m.add_method("translate", |_, a, v: LuaVec3| {
            Ok(LuaMat4(a.0 * Mat4::from_translation(v.0)))
        });
        m.add_method("rotate", |lua, a, (r, deg): (Value, Option<f32>)| {
            Ok(LuaMat4(a.0 * rotation(lua, r, deg)?))
        });
        m.add_method("scale", |lua, a, s: Value| {
            Ok(LuaMat4(a.0 * scaling(lua, s)?))
        });
        m.add_method("position", |_, a, ()| Ok(LuaVec3(a.0.w_axis.truncate())));
        m.add_meta_function(MetaMethod::Mul, |lua, (a, b): (LuaMat4, Value)| match &b {
            Value::UserData(ud) if ud.is::<LuaMat4>() => Ok(Value::UserData(
                lua.create_userdata(LuaMat4(a.0 * LuaMat4::from_lua(b, lua)?.0))?,
            )),
            _ => {
                let v = LuaVec3::from_lua(b, lua)?;
                Ok(Value::UserData(
                    lua.create_userdata(LuaVec3(a.0.transform_point3(v.0)))?,
                ))
            }
        });
        m.add_meta_method(MetaMethod::ToString, |_, a, ()| {
            Ok(format!("mat4({:?})", a.0.to_cols_array()))
        });
    }
}

/// A rotation from `(axis, degrees)` or a quaternion.
fn rotation(lua: &Lua, r: Value, degrees: Option<f32>) -> mlua::Result<Mat4> {
    if let Value::UserData(ud) = &r
        && let Ok(q) = ud.borrow::<LuaQuat>()
    {
        return Ok(Mat4::from_quat(q.0));
    }
    let axis = LuaVec3::from_lua(r, lua)?.0;
    let axis = axis
        .try_normalize()
        .ok_or_else(|| script_error(lua, "rotation axis has zero length"))?;
    let deg =
        degrees.ok_or_else(|| script_error(lua, "rotate(axis, degrees): the angle is missing"))?;
    Ok(Mat4::from_axis_angle(axis, deg.to_radians()))
}

fn scaling(lua: &Lua, s: Value) -> mlua::Result<Mat4> {
    match number(s.clone()) {
        Some(_) => Ok(Mat4::from_scale(Vec3::splat(scalar(lua, &s, "scale")?))),
        None => Ok(Mat4::from_scale(LuaVec3::from_lua(s, lua)?.0)),
    }
}

pub(crate) fn register(lua: &Lua, pge: &Table) -> mlua::Result<()> {
    pge.set(
        "vec3",
        lua.create_function(|lua, (x, y, z): (Value, Option<f64>, Option<f64>)| {
            if let (Value::Table(_) | Value::UserData(_), None) = (&x, y) {
                return LuaVec3::from_lua(x, lua);
            }
            let x = number(x).unwrap_or(0.0);
            let v = Vec3::new(x as f32, y.unwrap_or(0.0) as f32, z.unwrap_or(0.0) as f32);
            finite(lua, v, "pge.vec3")
        })?,
    )?;
    let quat = lua.create_table()?;
    quat.set(
        "axisAngle",
        lua.create_function(|lua, (axis, deg): (LuaVec3, f32)| {
            let a = axis
                .0
                .try_normalize()
                .ok_or_else(|| script_error(lua, "pge.quat.axisAngle: the axis has zero length"))?;
            if !deg.is_finite() {
                return Err(script_error(
                    lua,
                    "pge.quat.axisAngle: the angle is not finite",
                ));
            }
            Ok(LuaQuat(Quat::from_axis_angle(a, deg.to_radians())))
        })?,
    )?;
    quat.set(
        "identity",
        lua.create_function(|_, ()| Ok(LuaQuat(Quat::IDENTITY)))?,
    )?;
    quat.set(
        "between",
        lua.create_function(|lua, (a, b): (LuaVec3, LuaVec3)| {
            match (a.0.try_normalize(), b.0.try_normalize()) {
                (Some(a), Some(b)) => Ok(LuaQuat(Quat::from_rotation_arc(a, b))),
                _ => Err(script_error(lua, "pge.quat.between: zero-length vector")),
            }
        })?,
    )?;
    pge.set("quat", quat)?;
    let mat4 = lua.create_table()?;
    mat4.set(
        "identity",
        lua.create_function(|_, ()| Ok(LuaMat4(Mat4::IDENTITY)))?,
    )?;
    mat4.set(
        "translate",
        lua.create_function(|_, v: LuaVec3| Ok(LuaMat4(Mat4::from_translation(v.0))))?,
    )?;
    mat4.set(
        "rotate",
        lua.create_function(|lua, (r, deg): (Value, Option<f32>)| {
            Ok(LuaMat4(rotation(lua, r, deg)?))
        })?,
    )?;
    mat4.set(
        "scale",
        lua.create_function(|lua, s: Value| Ok(LuaMat4(scaling(lua, s)?)))?,
    )?;
    pge.set("mat4", mat4)?;
    Ok(())
}
