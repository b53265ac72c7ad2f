//! `pge derive`: the string an L-system derives, without building a model.

use std::fmt::Write as _;
use std::io::{self, Write};

use mlua::{Lua, Value};
use pge_engine::{Error, Location, RunContext};

use super::algorithm::LSystemAlgorithm;
use super::host::HostError;
use super::object::LuaLSystem;
use super::stream::{LastStep, StreamHost};
use crate::{ModuleString, Output, SymbolTable};

/// The result of a derivation: the final string with its symbol names and parameters. The
/// last steps of a system without Lua are not kept: they are derived again, piece by piece,
/// while the string is written, so a derivation holds the axiom (for rules that let every
/// step be taken depth first: see [`Prepared::derives_in_pieces`]) or the string before the
/// last step.
#[derive(Clone, Debug)]
pub struct Derivation {
    /// The final string, or the one before the streamed steps when `last` is set.
    string: ModuleString,
    last: Option<LastStep>,
    symbols: SymbolTable,
    /// Lua parameter tables of the external modules (read only when written).
    side: Vec<Value>,
    /// Keeps the Lua state of `side` alive as long as the derivation.
    _lua: Option<Lua>,
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

/// The leading positional numbers of an external module's parameter table (written by the
/// `text` format).
fn positional(v: &Value, out: &mut String) {
    let Value::Table(t) = v else { return };
    let mut k = 0;
    for i in 1..=t.raw_len() {
        let x = match t.raw_get::<Value>(i) {
            Ok(Value::Integer(x)) => x as f64,
            Ok(Value::Number(x)) => x,
            _ => break,
        };
        out.push(if k == 0 { '(' } else { ',' });
        // Text parses back: non-finite values as (1/0), (-1/0), (0/0).
        crate::module_string::write_param(out, x);
        k += 1;
    }
    if k > 0 {
        out.push(')');
    }
}

/// JSON written before flushing to the output.
const FLUSH_AT: usize = 60_000;
/// Text written before flushing to the output.
const TEXT_CHUNK: usize = 1 << 20;

/// The text format on its way out: every module is written with the space before it, and
/// the first module's is dropped.
struct TextOut<'w> {
    w: &'w mut dyn Write,
    buf: Vec<u8>,
    /// Some text was written.
    started: bool,
}

impl TextOut<'_> {
    /// Writes the buffer once it holds a chunk.
    #[inline]
    fn flush_full(&mut self) -> io::Result<()> {
        if self.buf.len() >= TEXT_CHUNK {
            self.flush()?;
        }
        Ok(())
    }

    fn flush(&mut self) -> io::Result<()> {
        let skip = usize::from(!self.started && self.buf.first() == Some(&b' '));
        self.w.write_all(&self.buf[skip..])?;
        self.started |= !self.buf.is_empty();
        self.buf.clear();
        Ok(())
    }
}

impl Derivation {
    /// Number of modules, brackets included.
    #[must_use]
    pub fn len(&self) -> usize {
        match &self.last {
            Some(last) => last.len as usize,
            None => self.string.len(),
        }
    }

    /// Whether the string is empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Hands every piece of the final string to `f` in order (the whole string, or the
    /// streamed last steps piece by piece).
    fn for_each_piece(&self, f: &mut dyn FnMut(&ModuleString) -> io::Result<()>) -> io::Result<()> {
        let Some(last) = &self.last else {
            return f(&self.string);
        };
        let mut rng = last.rng.clone();
        let mut host = StreamHost {
            rng: &mut rng,
            limits: None,
        };
        let mut failed = None;
        let mut sink = |piece: &ModuleString| {
            f(piece).map_err(|e| {
                failed = Some(e);
                HostError::Engine(Error::Cancelled {
                    location: Location::default(),
                })
            })
        };
        let result = last.prepared.derive(
            &self.string,
            &last.opts,
            &mut host,
            Output::Pieces(&mut sink),
        );
        match (result, failed) {
            (_, Some(e)) => Err(e),
            (Ok(_), None) => Ok(()),
            (Err(e), None) => Err(io::Error::other(match e {
                HostError::Engine(e) => e.to_string(),
                HostError::Ls(e) => e.to_string(),
                HostError::Lua(e) => e.to_string(),
            })),
        }
    }

    /// Module `i` as `Name` or `Name(p1,p2,...)` (positional numeric parameters, shortest
    /// round-trip form). Reading a module of streamed last steps derives them up to it.
    #[must_use]
    pub fn module_text(&self, i: usize) -> String {
        let mut out = String::new();
        let mut skip = i;
        let _ = self.for_each_piece(&mut |piece| {
            if skip < piece.len() {
                self.write_module(piece, skip, &mut out);
                return Err(io::Error::other("found"));
            }
            skip -= piece.len();
            Ok(())
        });
        out
    }

    fn write_module(&self, string: &ModuleString, i: usize, out: &mut String) {
        match string.external(i) {
            None => string.write_module(i, &self.symbols, out),
            Some(slot) => {
                out.push_str(self.symbols.name(string.sym(i)));
                if let Some(v) = self.side.get(slot as usize) {
                    positional(v, out);
                }
            }
        }
    }

    /// Writes the `text` format: modules separated by one space, then a newline, in chunks
    /// of a mebibyte. Modules without parameters are written from a table of
    /// their names, each with the space before it (one byte for every one-letter name).
    pub fn write_text(&self, w: &mut dyn Write) -> io::Result<()> {
        let names: Vec<&str> = (0..self.symbols.len())
            .map(|i| self.symbols.name(crate::Sym(i as u32)))
            .collect();
        let letters: Option<Vec<u8>> = names
            .iter()
            .map(|n| match n.as_bytes() {
                [b] => Some(*b),
                _ => None,
            })
            .collect();
        let spaced: Vec<Vec<u8>> = names.iter().map(|n| format!(" {n}").into_bytes()).collect();
        let mut out = TextOut {
            w,
            buf: Vec::with_capacity(TEXT_CHUNK + (1 << 16)),
            started: false,
        };
        let mut module = String::new();
        self.for_each_piece(&mut |piece| {
            if !piece.is_flat() {
                for i in 0..piece.len() {
                    module.clear();
                    self.write_module(piece, i, &mut module);
                    out.buf.push(b' ');
                    out.buf.extend_from_slice(module.as_bytes());
                    out.flush_full()?;
                }
                return Ok(());
            }
            for syms in piece.raw_syms().chunks(1 << 14) {
                match &letters {
                    Some(letters) => {
                        let start = out.buf.len();
                        out.buf.resize(start + 2 * syms.len(), b' ');
                        for (pair, &s) in out.buf[start..].chunks_exact_mut(2).zip(syms) {
                            pair[1] = letters[s as usize];
                        }
                    }
                    None => {
                        for &s in syms {
                            out.buf.extend_from_slice(&spaced[s as usize]);
                        }
                    }
                }
                out.flush_full()?;
            }
            Ok(())
        })?;
        out.buf.push(b'\n');
        out.flush()
    }

    /// Writes the `json` format: an array of `{"name": ..., "params": ...}` (params is an
    /// array of numbers, or the parameter table as JSON when it is not one).
    pub fn write_json(&self, w: &mut dyn Write) -> io::Result<()> {
        let mut buf = String::with_capacity(FLUSH_AT + 4096);
        buf.push('[');
        let mut first = true;
        self.for_each_piece(&mut |piece| {
            for i in 0..piece.len() {
                if !first {
                    buf.push(',');
                }
                first = false;
                buf.push_str("{\"name\":");
                buf.push_str(&serde_json::Value::from(self.symbols.name(piece.sym(i))).to_string());
                buf.push_str(",\"params\":");
                match piece.external(i) {
                    Some(slot) => buf.push_str(
                        &to_json(self.side.get(slot as usize).unwrap_or(&Value::Nil), 0)
                            .to_string(),
                    ),
                    None => {
                        buf.push('[');
                        for (k, v) in piece.params(i).iter().enumerate() {
                            if k > 0 {
                                buf.push(',');
                            }
                            number(&mut buf, *v);
                        }
                        buf.push(']');
                    }
                }
                buf.push('}');
                if buf.len() > FLUSH_AT {
                    w.write_all(buf.as_bytes())?;
                    buf.clear();
                }
            }
            Ok(())
        })?;
        buf.push_str("]\n");
        w.write_all(buf.as_bytes())
    }
}

/// Derives the L-system a script returned (`value`), taking `ctx.steps` steps or the
/// system's own `iterations`. A system without IRules and rule functions is not interpreted
/// (interpretation could not change its string); when no Lua takes part in its last steps
/// either, those steps are only counted here (checking every limit) and streamed when
/// written.
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
    let last = algorithm.grow_for_output(ctx)?;
    let (string, side) = algorithm.take_string();
    let symbols = algorithm.symbols().clone();
    Ok(Derivation {
        string,
        last,
        symbols,
        _lua: (!side.is_empty()).then(|| lua.clone()),
        side,
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
