//! Symbols in Lua: `A{...}`, `pge.sym(name, params)`.

use mlua::{Lua, MetaMethod, Table, UserData, UserDataMethods, Value};
use pge_engine::lua::script_error;

use super::session_symbols;
use crate::Sym;

/// A symbol made in Lua: its interned id and its parameter table (any Lua values).
#[derive(Clone, Debug)]
pub struct LuaSymbol {
    /// The symbol.
    pub sym: Sym,
    /// Its parameters, `None` for `A()` / `pge.sym("A")`.
    pub params: Option<Table>,
}

impl UserData for LuaSymbol {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_meta_method(MetaMethod::Index, |lua, me, key: Value| {
            if let Value::String(s) = &key
                && s.as_bytes().as_ref() == b"name"
            {
                let name = session_symbols(lua).borrow().name(me.sym).to_string();
                return Ok(Value::String(lua.create_string(name)?));
            }
            match &me.params {
                Some(t) => t.get(key),
                None => Ok(Value::Nil),
            }
        });
        m.add_meta_method(MetaMethod::ToString, |lua, me, ()| {
            Ok(session_symbols(lua).borrow().name(me.sym).to_string())
        });
    }
}

fn params_arg(lua: &Lua, name: &str, v: Value) -> mlua::Result<Option<Table>> {
    match v {
        Value::Nil => Ok(None),
        Value::Table(t) => Ok(Some(t)),
        other => Err(script_error(
            lua,
            format!(
                "the parameters of symbol '{name}' must be one table ({name}{{...}}), not {}",
                other.type_name()
            ),
        )),
    }
}

fn constructor(lua: &Lua, name: String) -> mlua::Result<mlua::Function> {
    let sym = session_symbols(lua).borrow_mut().intern(&name);
    lua.create_function(move |lua, v: Value| {
        let params = params_arg(lua, &name, v)?;
        Ok(LuaSymbol { sym, params })
    })
}

pub(crate) fn register(lua: &Lua, pge: &Table) -> mlua::Result<()> {
    pge.set(
        "sym",
        lua.create_function(|lua, (name, params): (String, Value)| {
            if name.is_empty() || name.chars().any(char::is_whitespace) {
                return Err(script_error(
                    lua,
                    format!("pge.sym: '{name}' is not a symbol name (no spaces, not empty)"),
                ));
            }
            let params = params_arg(lua, &name, params)?;
            let sym = session_symbols(lua).borrow_mut().intern(&name);
            Ok(LuaSymbol { sym, params })
        })?,
    )?;
    let make = lua.create_function(|lua, name: String| constructor(lua, name))?;
    // Undefined globals starting with an uppercase letter are symbol constructors; the
    // lookup and cache live in Lua so that `A{}` in a hot rule costs one table read.
    lua.load(
        r#"
        local make = ...
        local cache = {}
        local meta = getmetatable(_G) or {}
        local previous = meta.__index
        meta.__index = function(t, k)
            local c = cache[k]
            if c then return c end
            if previous then
                local v
                if type(previous) == "function" then v = previous(t, k) else v = previous[k] end
                if v ~= nil then return v end
            end
            if type(k) == "string" and k:match("^[A-Z]") then
                c = make(k)
                cache[k] = c
                return c
            end
            return nil
        end
        setmetatable(_G, meta)
        "#,
    )
    .set_name("=pge.lsystem")
    .call::<()>(make)
}
