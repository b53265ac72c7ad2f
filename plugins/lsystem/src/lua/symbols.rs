//! Symbols in Lua: `A{...}`, `pge.sym(name, params)`.
//!
//! A symbol is its own parameter table tagged with the symbol's metatable, so that `A{}` in a
//! hot rule costs one table and one call of a Rust function (no Lua instructions), and a rule
//! reads `a.v` or `a[1]` directly.
//! Rust recognises a symbol by its metatable (see [`SymbolTags`]).

use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;

use mlua::{Function, Lua, Table, Value};
use pge_engine::lua::{engine_chunk, script_error};
use rustc_hash::FxHashMap;

use super::{session_symbols, with_shared};
use crate::Sym;

/// The metatables that mark symbols, by address (hashed by rustc's fast hasher: the map is
/// only probed, never iterated), and the constructors already made.
#[derive(Default)]
pub(crate) struct SymbolTags {
    by_meta: FxHashMap<usize, Sym>,
    constructors: HashMap<Sym, (Table, Function)>,
}

impl SymbolTags {
    /// The symbol a table stands for, if it is one.
    pub fn symbol_of(&self, t: &Table) -> Option<Sym> {
        let meta = t.metatable()?;
        self.by_meta.get(&(meta.to_pointer() as usize)).copied()
    }
}

pub(crate) fn tags(lua: &Lua) -> Rc<RefCell<SymbolTags>> {
    with_shared(lua, |s| s.tags.clone())
}

/// The constructor of `name`, a Rust function: `A{...}` tags the table it is given with the
/// symbol's metatable and returns it (`A()` tags a new empty table). Running no Lua
/// instructions, it costs a rule nothing under the session's instruction-count hook.
pub(crate) fn constructor(lua: &Lua, name: &str) -> mlua::Result<Function> {
    let sym = session_symbols(lua).borrow_mut().intern(name);
    let tags = tags(lua);
    if let Some((_, f)) = tags.borrow().constructors.get(&sym) {
        return Ok(f.clone());
    }
    let meta = lua.create_table()?;
    let fields = lua.create_table()?;
    fields.raw_set("name", name)?;
    meta.raw_set("__index", fields)?;
    meta.raw_set("__name", format!("symbol {name}"))?;
    // A table that is already a symbol (`Floor(b), Roof(b)`), or has any metatable, is
    // copied (with the global `next`, in its order) so that one table never stands for two
    // symbols. Rare, so written in Lua.
    let copy: Function = engine_chunk(
        lua,
        "=pge.sym",
        r#"local next = next
            return function(p)
                local c = {}
                for k, v in next, p do c[k] = v end
                return c
            end"#,
    )?
    .call(())?;
    let tag = meta.clone();
    let symbol = name.to_string();
    let f = lua.create_function(move |lua, p: Value| -> mlua::Result<Table> {
        let t = match p {
            Value::Nil => lua.create_table()?,
            Value::Table(t) if !t.has_metatable() => t,
            Value::Table(t) => copy.call::<Table>(t)?,
            other => {
                return Err(script_error(
                    lua,
                    format!(
                        "the parameters of symbol '{symbol}' must be one table ({symbol}{{...}}), \
                         not {}",
                        lua_type_name(&other)
                    ),
                ));
            }
        };
        t.set_metatable(Some(tag.clone()))?;
        Ok(t)
    })?;
    let mut t = tags.borrow_mut();
    t.by_meta.insert(meta.to_pointer() as usize, sym);
    t.constructors.insert(sym, (meta, f.clone()));
    Ok(f)
}

/// What Lua's `type` says of a value.
fn lua_type_name(v: &Value) -> &'static str {
    match v {
        Value::Integer(_) | Value::Number(_) => "number",
        Value::LightUserData(_) | Value::UserData(_) => "userdata",
        other => other.type_name(),
    }
}

pub(crate) fn register(lua: &Lua, pge: &mlua::Table) -> mlua::Result<()> {
    pge.set(
        "sym",
        lua.create_function(|lua, (name, params): (String, Value)| {
            if name.is_empty() || name.chars().any(char::is_whitespace) {
                return Err(script_error(
                    lua,
                    format!("pge.sym: '{name}' is not a symbol name (no spaces, not empty)"),
                ));
            }
            match params {
                Value::Nil | Value::Table(_) => {}
                other => {
                    return Err(script_error(
                        lua,
                        format!(
                            "pge.sym: the parameters of '{name}' must be one table, not {}",
                            other.type_name()
                        ),
                    ));
                }
            }
            constructor(lua, &name)?.call::<Value>(params)
        })?,
    )?;
    // Undefined globals starting with an uppercase ASCII letter are symbol constructors,
    // found by the globals' `__index` (after any `__index` already there) and then stored
    // as plain globals: later reads of the name cost one table read. A name the script
    // cleared reads its constructor again. A Rust function, so that a session compiles no
    // Lua for it.
    let globals = lua.globals();
    let meta = match globals.metatable() {
        Some(meta) => meta,
        None => lua.create_table()?,
    };
    let previous: Value = meta.raw_get("__index")?;
    let made = lua.create_table()?;
    let index = lua.create_function(move |lua, (t, k): (Table, Value)| {
        let cached: Value = made.raw_get(&k)?;
        if !cached.is_nil() {
            return Ok(cached);
        }
        let v = match &previous {
            Value::Function(f) => f.call::<Value>((&t, &k))?,
            Value::Table(p) => p.get::<Value>(&k)?,
            _ => Value::Nil,
        };
        if !v.is_nil() {
            return Ok(v);
        }
        let Value::String(name) = &k else {
            return Ok(Value::Nil);
        };
        if !name.as_bytes().first().is_some_and(u8::is_ascii_uppercase) {
            return Ok(Value::Nil);
        }
        let c = Value::Function(constructor(lua, &name.to_str()?)?);
        made.raw_set(&k, &c)?;
        t.raw_set(k, &c)?;
        Ok(c)
    })?;
    meta.raw_set("__index", index)?;
    globals.set_metatable(Some(meta))
}
