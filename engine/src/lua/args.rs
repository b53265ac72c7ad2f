//! Arguments of methods (`image:set(x, y, c)`, `meta:calc(p)`): numbers and vectors, with
//! errors that name the method and say what was wrong. Option tables are read with
//! [`Options`](super::Options) instead.

use glam::Vec3;
use mlua::{FromLua, Lua, Value};

use super::errors::script_error;
use super::math::LuaVec3;

/// A finite number from a script value, or a `FILE:LINE:` error that names `what` (the
/// method and argument) and says what was wrong.
pub fn finite_number(lua: &Lua, v: &Value, what: &str) -> mlua::Result<f64> {
    let x = match v {
        Value::Integer(i) => *i as f64,
        Value::Number(n) => *n,
        other => {
            return Err(script_error(
                lua,
                format!("{what}: expected a number, got {}", other.type_name()),
            ));
        }
    };
    if x.is_finite() {
        Ok(x)
    } else {
        Err(script_error(
            lua,
            format!("{what}: the number is NaN or infinite"),
        ))
    }
}

/// [`finite_number`] as an `f32`.
pub fn finite_f32(lua: &Lua, v: &Value, what: &str) -> mlua::Result<f32> {
    finite_number(lua, v, what).map(|x| x as f32)
}

/// A vector (a `pge.vec3` or `{x, y, z}`) from a script value, or a `FILE:LINE:` error
/// `WHAT: why`.
pub fn vec3_arg(lua: &Lua, v: Value, what: &str) -> mlua::Result<Vec3> {
    LuaVec3::from_lua(v, lua)
        .map(|v| v.0)
        .map_err(|e| script_error(lua, format!("{what}: {}", conversion_message(&e))))
}

/// The message of a conversion error (`expected a pge.vec3 or {x, y, z}`) without mlua's
/// framing.
#[must_use]
pub fn conversion_message(e: &mlua::Error) -> String {
    match e {
        mlua::Error::FromLuaConversionError {
            message: Some(m), ..
        } => m.clone(),
        other => other.to_string(),
    }
}

/// Makes assigning a field of a userdata type that has none (`this.size = 2` on a turtle) a
/// script error naming the field and the type, instead of Lua's "attempt to index a userdata
/// value". Call it from the type's `add_methods`; `what` names the type (`turtle`).
pub fn no_new_fields<T, M: mlua::UserDataMethods<T>>(m: &mut M, what: &'static str) {
    m.add_meta_method(
        mlua::MetaMethod::NewIndex,
        move |lua, _, (key, _): (Value, Value)| -> mlua::Result<()> {
            let key = match &key {
                Value::String(s) => format!("'{}'", s.to_string_lossy()),
                other => format!("a {} key", other.type_name()),
            };
            Err(script_error(
                lua,
                format!(
                    "cannot set {key} on a {what}: it has no fields to set (call its methods, \
                     or keep your own values in a Lua table)"
                ),
            ))
        },
    );
}
