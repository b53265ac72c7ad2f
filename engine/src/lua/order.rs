//! Table traversal in a defined order, so that output never depends on where Lua put keys.
//!
//! Lua visits the hash part of a table in the order of its hash slots. String hashes are
//! seeded from the clock and from addresses when a state is created, and tables, functions
//! and userdata hash by address: a script that builds geometry in `pairs` order would not
//! give the same bytes twice. The sandbox therefore replaces `next` and `pairs` with
//! functions that visit keys in [`key_order`]: numbers ascending, then strings by their
//! bytes, then `false` and `true`, then every other key. The order of keys of that last
//! group (tables, functions, userdata used as keys) is still Lua's own: no value-based order
//! exists for them. Rust code that turns a table into output iterates with
//! [`sorted_pairs`] for the same reason.

use std::cmp::Ordering;

use mlua::{Function, Lua, Table, Value};

use super::chunks::{ShippedChunk, engine_chunk, shipped_chunk};

/// The rank of a key's type in the traversal order.
fn rank(v: &Value) -> u8 {
    match v {
        Value::Integer(_) | Value::Number(_) => 0,
        Value::String(_) => 1,
        Value::Boolean(_) => 2,
        _ => 3,
    }
}

/// The order the sandbox's `pairs` and `next` visit keys in: numbers ascending (integers and
/// floats together), then strings by their bytes, then `false` before `true`; keys of any
/// other type compare equal to each other and come last.
#[must_use]
pub fn key_order(a: &Value, b: &Value) -> Ordering {
    match (a, b) {
        (Value::Integer(x), Value::Integer(y)) => x.cmp(y),
        (Value::Number(x), Value::Number(y)) => x.total_cmp(y),
        (Value::Integer(i), Value::Number(f)) => int_float(*i, *f),
        (Value::Number(f), Value::Integer(i)) => int_float(*i, *f).reverse(),
        (Value::String(x), Value::String(y)) => x.as_bytes().cmp(&y.as_bytes()),
        (Value::Boolean(x), Value::Boolean(y)) => x.cmp(y),
        _ => rank(a).cmp(&rank(b)),
    }
}

/// An integer key against a float key. A float key with an integral value in the range of
/// integers is stored as an integer by Lua, so equal values only occur at +-2^63.
fn int_float(i: i64, f: f64) -> Ordering {
    match (i as f64).total_cmp(&f) {
        Ordering::Equal if f > 0.0 => Ordering::Less,
        Ordering::Equal => Ordering::Greater,
        o => o,
    }
}

/// The keys of `t` (not its metatable's) in [`key_order`].
pub fn sorted_keys(t: &Table) -> mlua::Result<Vec<Value>> {
    let mut keys = Vec::new();
    t.for_each(|k: Value, _: Value| {
        keys.push(k);
        Ok(())
    })?;
    // Stable: keys without a defined order keep Lua's.
    keys.sort_by(key_order);
    Ok(keys)
}

/// The pairs of `t` in [`key_order`] (raw access, no metamethods).
pub fn sorted_pairs(t: &Table) -> mlua::Result<Vec<(Value, Value)>> {
    let mut pairs = Vec::new();
    t.for_each(|k: Value, v: Value| {
        pairs.push((k, v));
        Ok(())
    })?;
    pairs.sort_by(|a, b| key_order(&a.0, &b.0));
    Ok(pairs)
}

/// `next` and `pairs` over a snapshot of the sorted keys, cached per table (weakly) so that
/// each step of a traversal costs a table lookup. A traversal starts with `next(t, nil)`,
/// which takes a new snapshot; assigning to a field that did not exist during a traversal is
/// undefined in Lua and here sees the snapshot. Values are read at each step, so fields
/// cleared during the traversal are skipped.
const ORDERED: &str = r#"
local sorted, pairs_metamethod, rawnext, global_next = ...
local rawget, rawequal, type, error, setmetatable = rawget, rawequal, type, error, setmetatable
local cache = setmetatable({}, { __mode = "k" })

local function index_of(c, k)
  local map = c[3]
  if map == nil then
    map = {}
    local keys = c[1]
    for i = 1, #keys do map[keys[i]] = i end
    c[3] = map
  end
  return map[k]
end

local function next(t, k)
  if type(t) ~= "table" then
    error("bad argument #1 to 'next' (table expected, got " .. type(t) .. ")", 2)
  end
  local c
  if k == nil then
    if rawnext(t) == nil then
      cache[t] = nil
      return nil
    end
    c = { sorted(t), 0 }
    cache[t] = c
  else
    c = cache[t]
    if c == nil or not rawequal(c[1][c[2]], k) then
      local i = c and index_of(c, k)
      if i == nil then
        c = { sorted(t), 0 }
        i = index_of(c, k)
        if i == nil then error("invalid key to 'next'", 2) end
        cache[t] = c
      end
      c[2] = i
    end
  end
  local keys, i = c[1], c[2]
  while true do
    i = i + 1
    local key = keys[i]
    if key == nil then
      cache[t] = nil
      return nil
    end
    local v = rawget(t, key)
    if v ~= nil then
      c[2] = i
      return key, v
    end
  end
end

local function pairs(t)
  local mm = pairs_metamethod(t)
  if mm ~= nil then
    local f, s, c = mm(t)
    return f, s, c
  end
  if type(t) ~= "table" then
    error("bad argument #1 to 'pairs' (table expected, got " .. type(t) .. ")", 2)
  end
  return global_next, t, nil
end

return next, pairs
"#;

/// The global `next` and `pairs`: they load [`ORDERED`] at their first call (most scripts
/// never call them, and compiling it was a tenth of a session's setup), then hand over to
/// it with a tail call, so its errors still point at the script's line. `pairs` returns
/// the global `next`, as Lua's own does.
pub(crate) static ON_FIRST_CALL: ShippedChunk = ShippedChunk {
    name: "=pge",
    source: r#"
local load_ordered = ...
local ordered_next, ordered_pairs
local next
next = function(t, k)
  if ordered_next == nil then ordered_next, ordered_pairs = load_ordered(next) end
  return ordered_next(t, k)
end
local function pairs(t)
  if ordered_pairs == nil then ordered_next, ordered_pairs = load_ordered(next) end
  return ordered_pairs(t)
end
return next, pairs
"#,
    compiled: include_bytes!("compiled/on_first_call.luac"),
    file: "on_first_call.luac",
};

/// The `__pairs` metamethod of a table or userdata (read from the real metatable, as Lua's
/// `pairs` does), or nil.
fn pairs_metamethod(_: &Lua, v: Value) -> mlua::Result<Value> {
    match &v {
        Value::Table(t) => match t.metatable() {
            Some(mt) => mt.raw_get("__pairs"),
            None => Ok(Value::Nil),
        },
        Value::UserData(ud) => match ud.metatable() {
            Ok(mt) => mt.get("__pairs"),
            Err(_) => Ok(Value::Nil),
        },
        _ => Ok(Value::Nil),
    }
}

/// Replaces the global `next` and `pairs` with the ordered ones.
pub(crate) fn register(lua: &Lua) -> mlua::Result<()> {
    let globals = lua.globals();
    let rawnext: Function = globals.get("next")?;
    let load_ordered = lua.create_function(move |lua, global_next: Function| {
        let sorted =
            lua.create_function(|lua, t: Table| lua.create_sequence_from(sorted_keys(&t)?))?;
        engine_chunk(lua, "=pge", ORDERED)?.call::<(Function, Function)>((
            sorted,
            lua.create_function(pairs_metamethod)?,
            rawnext.clone(),
            global_next,
        ))
    })?;
    let (next, pairs): (Function, Function) =
        shipped_chunk(lua, &ON_FIRST_CALL)?.call(load_ordered)?;
    globals.set("next", next)?;
    globals.set("pairs", pairs)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lua() -> Lua {
        let lua = Lua::new();
        register(&lua).expect("registers");
        lua
    }

    #[test]
    fn pairs_visits_numbers_then_strings_then_booleans() {
        let lua = lua();
        let order: String = lua
            .load(
                r#"
                local t = { "a", "b", zeta = 1, alpha = 2, [2.5] = 3, [-1] = 4, [true] = 5,
                            [false] = 6, [10] = 7, beta = 8 }
                local s = {}
                for k in pairs(t) do s[#s + 1] = tostring(k) end
                return table.concat(s, ",")
                "#,
            )
            .eval()
            .expect("runs");
        assert_eq!(order, "-1,1,2,2.5,10,alpha,beta,zeta,false,true");
    }

    #[test]
    fn next_walks_the_same_order_and_detects_empty_tables() {
        let lua = lua();
        let (order, empty): (String, bool) = lua
            .load(
                r#"
                local t = { c = 1, a = 2, b = 3 }
                local s, k = {}, next(t)
                while k ~= nil do s[#s + 1] = k; k = next(t, k) end
                return table.concat(s), next({}) == nil
                "#,
            )
            .eval()
            .expect("runs");
        assert_eq!(order, "abc");
        assert!(empty);
    }

    #[test]
    fn fields_cleared_during_a_traversal_are_skipped_and_nesting_works() {
        let lua = lua();
        let (seen, pairs_count): (String, i64) = lua
            .load(
                r#"
                local t = { a = 1, b = 2, c = 3, d = 4 }
                local s = {}
                for k in pairs(t) do
                  s[#s + 1] = k
                  if k == "a" then t.a = nil; t.c = nil end
                end
                local u, n = { x = 1, y = 2, z = 3 }, 0
                for _ in pairs(u) do for _ in pairs(u) do n = n + 1 end end
                return table.concat(s), n
                "#,
            )
            .eval()
            .expect("runs");
        assert_eq!(seen, "abd");
        assert_eq!(pairs_count, 9);
    }

    #[test]
    fn pairs_honours_the_pairs_metamethod_and_rejects_non_tables() {
        let lua = lua();
        let n: i64 = lua
            .load(
                r#"
                local t = setmetatable({}, { __metatable = false,
                  __pairs = function(t) return function(_, k) if not k then return 1, 1 end end, t, nil end })
                local n = 0
                for k in pairs(t) do n = n + k end
                return n
                "#,
            )
            .eval()
            .expect("runs");
        assert_eq!(n, 1);
        let e = lua
            .load("for k in pairs(3) do end")
            .exec()
            .expect_err("a number");
        assert!(e.to_string().contains("table expected, got number"), "{e}");
        let e = lua
            .load("next({a = 1}, 'b')")
            .exec()
            .expect_err("no such key");
        assert!(e.to_string().contains("invalid key to 'next'"), "{e}");
    }

    #[test]
    fn next_and_pairs_made_at_first_call_keep_positions_and_identity() {
        // `next` first in one state, `pairs` first in another.
        for first in ["next({})", "pairs({})"] {
            let lua = lua();
            lua.load(first).exec().expect("runs");
            let same: bool = lua
                .load(
                    "local f, t, k = pairs({ b = 1, a = 2 })\nreturn f == next and f(t, k) == 'a'",
                )
                .eval()
                .expect("runs");
            assert!(same, "pairs returns the global next ({first} first)");
            let e = lua
                .load("local x = 1\nfor k in pairs(3) do end")
                .set_name("=s")
                .exec()
                .expect_err("a number");
            assert!(
                e.to_string().contains("s:2: bad argument #1 to 'pairs'"),
                "{e}"
            );
            let e = lua
                .load("local x = 1\n\nnext({a = 1}, 'b')")
                .set_name("=s")
                .exec()
                .expect_err("no such key");
            assert!(e.to_string().contains("s:3: invalid key to 'next'"), "{e}");
        }
    }

    #[test]
    fn sorted_pairs_orders_rust_side_traversals() {
        let lua = Lua::new();
        let t: Table = lua
            .load("return { b = 1, a = 2, [3] = 3, [1] = 4 }")
            .eval()
            .expect("table");
        let keys: Vec<String> = sorted_pairs(&t)
            .expect("pairs")
            .iter()
            .map(|(k, _)| k.to_string().expect("printable"))
            .collect();
        assert_eq!(keys, ["1", "3", "a", "b"]);
    }
}
