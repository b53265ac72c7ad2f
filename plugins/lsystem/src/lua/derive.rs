//! `pge derive`: the string an L-system derives, without building a model.

use std::fmt::Write as _;
use std::io::{self, Write};

use mlua::{Lua, Value};
use pge_engine::{Error, Location, RunContext};

use super::algorithm::LSystemAlgorithm;
use super::object::LuaLSystem;
use crate::{ModuleString, SymbolTable};

/// The parameters of a module whose parameter table is not a plain array of numbers.
#[derive(Clone, Debug, PartialEq)]
struct External {
    /// The leading positional numbers (written by the `text` format).
    positional: Vec<f64>,
    /// The whole table as JSON (written by the `json` format).
    json: serde_json::Value,
}

/// The result of a derivation: the final string with its symbol names and parameters.
#[derive(Clone, Debug)]
pub struct Derivation {
    string: ModuleString,
    symbols: SymbolTable,
    externals: Vec<External>,
    /// Derivation steps taken.
    pub steps: u32,
}

fn number(out: &mut String, v: f64) {
    if v.is_finite() {
        let _ = write!(out, "{v}");
    } else {
        out.push_str("null");
    }
}

fn to_json(v: &Value, depth: u32) -> serde_json::Value {
    use serde_json::Value as J;
    match v {
        Value::Nil => J::Null,
        Value::Boolean(b) => J::Bool(*b),
        Value::Integer(i) => J::from(*i),
        Value::Number(n) => serde_json::Number::from_f64(*n).map_or(J::Null, J::Number),
        Value::String(s) => J::String(s.to_string_lossy()),
        Value::Table(t) if depth < 16 => {
            let n = t.raw_len();
            let mut count = 0;
            let mut map = serde_json::Map::new();
            // Keys in a defined order: serde_json keeps insertion order.
            for pair in pge_engine::lua::sorted_pairs(t).unwrap_or_default() {
                count += 1;
                let key = match &pair.0 {
                    Value::String(s) => s.to_string_lossy(),
                    Value::Integer(i) => i.to_string(),
                    Value::Number(x) => x.to_string(),
                    other => other.type_name().to_string(),
                };
                map.insert(key, to_json(&pair.1, depth + 1));
            }
            if count == n {
                J::Array(
                    (1..=n)
                        .map(|i| to_json(&t.raw_get(i).unwrap_or(Value::Nil), depth + 1))
                        .collect(),
                )
            } else {
                J::Object(map)
            }
        }
        other => J::String(other.type_name().to_string()),
    }
}

impl Derivation {
    /// Number of modules, brackets included.
    #[must_use]
    pub fn len(&self) -> usize {
        self.string.len()
    }

    /// Whether the string is empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.string.is_empty()
    }

    /// Module `i` as `Name` or `Name(p1,p2,...)` (positional numeric parameters, shortest
    /// round-trip form).
    #[must_use]
    pub fn module_text(&self, i: usize) -> String {
        let mut out = String::new();
        self.write_module(i, &mut out);
        out
    }

    fn write_module(&self, i: usize, out: &mut String) {
        match self.string.external(i) {
            None => self.string.write_module(i, &self.symbols, out),
            Some(slot) => {
                out.push_str(self.symbols.name(self.string.sym(i)));
                let p = &self.externals[slot as usize].positional;
                if !p.is_empty() {
                    out.push('(');
                    for (k, v) in p.iter().enumerate() {
                        if k > 0 {
                            out.push(',');
                        }
                        crate::module_string::write_param(out, *v);
                    }
                    out.push(')');
                }
            }
        }
    }

    /// Writes the `text` format: modules separated by one space, then a newline.
    pub fn write_text(&self, w: &mut dyn Write) -> io::Result<()> {
        let mut buf = String::with_capacity(1 << 16);
        for i in 0..self.string.len() {
            if i > 0 {
                buf.push(' ');
            }
            self.write_module(i, &mut buf);
            if buf.len() > 60_000 {
                w.write_all(buf.as_bytes())?;
                buf.clear();
            }
        }
        buf.push('\n');
        w.write_all(buf.as_bytes())
    }

    /// Writes the `json` format: an array of `{"name": ..., "params": ...}` (params is an
    /// array of numbers, or the parameter table as JSON when it is not one).
    pub fn write_json(&self, w: &mut dyn Write) -> io::Result<()> {
        let mut buf = String::with_capacity(1 << 16);
        buf.push('[');
        for i in 0..self.string.len() {
            if i > 0 {
                buf.push(',');
            }
            buf.push_str("{\"name\":");
            buf.push_str(
                &serde_json::Value::from(self.symbols.name(self.string.sym(i))).to_string(),
            );
            buf.push_str(",\"params\":");
            match self.string.external(i) {
                Some(slot) => buf.push_str(&self.externals[slot as usize].json.to_string()),
                None => {
                    buf.push('[');
                    for (k, v) in self.string.params(i).iter().enumerate() {
                        if k > 0 {
                            buf.push(',');
                        }
                        number(&mut buf, *v);
                    }
                    buf.push(']');
                }
            }
            buf.push('}');
            if buf.len() > 60_000 {
                w.write_all(buf.as_bytes())?;
                buf.clear();
            }
        }
        buf.push_str("]\n");
        w.write_all(buf.as_bytes())
    }
}

/// Derives the L-system a script returned (`value`), taking `ctx.steps` steps or the
/// system's own `iterations`. A system without IRules and rule functions is not interpreted
/// (interpretation could not change its string).
pub fn derive_value(
    lua: &Lua,
    value: &Value,
    ctx: &RunContext,
    location: &Location,
) -> pge_engine::Result<Derivation> {
    let cfg = match value {
        Value::UserData(ud) => match ud.borrow::<LuaLSystem>() {
            Ok(l) => l.0.clone(),
            Err(_) => return Err(not_an_lsystem(value, location)),
        },
        _ => return Err(not_an_lsystem(value, location)),
    };
    let skip = cfg.irules.is_empty() && cfg.rrules.is_empty();
    let mut algorithm = LSystemAlgorithm::new(lua, cfg, skip);
    pge_engine::algorithm::grow(&mut algorithm, ctx)?;
    let string = algorithm.string().clone();
    let mut externals = Vec::new();
    let mut slotted = string.clone();
    for i in 0..string.len() {
        if let Some(v) = algorithm.external_params(i) {
            let mut positional = Vec::new();
            if let Value::Table(t) = v {
                for k in 1..=t.raw_len() {
                    match t.raw_get::<Value>(k) {
                        Ok(Value::Integer(x)) => positional.push(x as f64),
                        Ok(Value::Number(x)) => positional.push(x),
                        _ => break,
                    }
                }
            }
            externals.push(External {
                positional,
                json: to_json(v, 0),
            });
            slotted.set_external_slot(i, externals.len() as u32 - 1);
        }
    }
    let symbols = algorithm.symbols().clone();
    Ok(Derivation {
        string: slotted,
        symbols,
        externals,
        steps: algorithm.steps_taken(),
    })
}

fn not_an_lsystem(value: &Value, location: &Location) -> Error {
    Error::script(
        location.clone(),
        format!(
            "pge derive needs a script that returns an L-system (pge.LSystem), not {}",
            value.type_name()
        ),
    )
}
