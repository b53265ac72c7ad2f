//! The L-system's host calls: the [`Host`] the rewriting engine calls back for rule
//! functions (RRules), their successors and the random numbers, over the algorithm's state.

use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;

use mlua::{AnyUserData, Function, Lua, MultiValue, Table, Value};
use pge_engine::lua::{DefaultInterpreter, ReadOnlyPhase, current_uniform};
use pge_engine::{Error, RunContext};
use rand_mt::Mt;

use super::config::{Config, LuaRule};
use super::symbols::SymbolTags;
use crate::{Host, LsError, ModuleString, Prepared, Sym, SymbolTable, System};
use pge_engine::random::uniform;

/// How deeply a successor's arrays may nest (each level is a branch).
const MAX_SUCCESSOR_NESTING: u32 = 100;

/// Why a step stopped: a Lua error, an engine error, or a rewriting error.
#[derive(Debug)]
pub(crate) enum HostError {
    Lua(mlua::Error),
    Engine(Error),
    Ls(LsError),
}

impl From<LsError> for HostError {
    fn from(e: LsError) -> Self {
        HostError::Ls(e)
    }
}

impl From<mlua::Error> for HostError {
    fn from(e: mlua::Error) -> Self {
        HostError::Lua(e)
    }
}

/// A parameter as Lua sees it: integral values as integers (as the script wrote them).
pub(crate) fn lua_number(v: f64) -> Value {
    if v.fract() == 0.0 && v.abs() < 9_007_199_254_740_992.0 {
        Value::Integer(v as i64)
    } else {
        Value::Number(v)
    }
}

pub(crate) fn truthy(v: &Value) -> bool {
    !matches!(v, Value::Nil | Value::Boolean(false))
}

/// Reads the numbers of a parameter table that is a plain array of numbers: its keys are
/// exactly `1..=n` and every value is a number. One pass over the table's pairs, which for
/// keys present in the table calls into Lua unprotected (no `pcall` per module).
pub(crate) fn numeric_params(t: &Table, out: &mut Vec<f64>) -> mlua::Result<bool> {
    out.clear();
    let n = t.raw_len();
    if n == 0 {
        return Ok(t.is_empty());
    }
    out.resize(n, 0.0);
    let mut count = 0usize;
    for pair in t.pairs::<Value, Value>() {
        let (k, v) = pair?;
        count += 1;
        let slot = match k {
            Value::Integer(i) if i >= 1 && i as u64 <= n as u64 => i as usize - 1,
            _ => return Ok(false),
        };
        match v {
            Value::Integer(x) => out[slot] = x as f64,
            Value::Number(x) => out[slot] = x,
            _ => return Ok(false),
        }
    }
    // Distinct keys, all in 1..=n: n of them are exactly 1..=n.
    Ok(count == n)
}

/// The positional numbers of a parameter table (for the default interpretation).
pub(crate) fn positional_numbers(v: &Value, out: &mut Vec<f64>) -> mlua::Result<()> {
    out.clear();
    if let Value::Table(t) = v {
        for i in 1..=t.raw_len() {
            match t.raw_get::<Value>(i)? {
                Value::Integer(x) => out.push(x as f64),
                Value::Number(x) => out.push(x),
                _ => break,
            }
        }
    }
    Ok(())
}

/// A host over one algorithm's state for one call of the rewriting engine (made by
/// `LSystemAlgorithm::with_host`).
pub(crate) struct LuaHost<'a> {
    pub(crate) lua: &'a Lua,
    pub(crate) ctx: &'a RunContext,
    pub(crate) cfg: &'a Config,
    pub(crate) system: &'a System,
    /// The rules compiled from `system`.
    pub(crate) prepared: &'a Prepared,
    pub(crate) symbols: &'a RefCell<SymbolTable>,
    pub(crate) side: &'a mut Vec<Value>,
    pub(crate) parse_cache: &'a mut HashMap<String, ModuleString>,
    pub(crate) rng: &'a mut Mt,
    pub(crate) rng_in_lua: bool,
    pub(crate) this_rw: &'a Value,
    pub(crate) this_ro: &'a Value,
    pub(crate) this_is_ro: Option<bool>,
    pub(crate) irules_by_sym: &'a [Vec<u32>],
    pub(crate) interpreters: &'a [DefaultInterpreter],
    pub(crate) instance_ud: Option<AnyUserData>,
    pub(crate) interpret: bool,
    pub(crate) numbers: Vec<f64>,
    pub(crate) tags: Rc<RefCell<SymbolTags>>,
    pub(crate) read_only: ReadOnlyPhase,
    /// `function(f, ...) return f({...}) end` for 0 to 3 numeric parameters.
    pub(crate) callers: &'a [Function],
    /// Bracket pairs of the string interpreted so far (for IRules with a left context).
    pub(crate) imatches: Vec<u32>,
    pub(crate) istack: Vec<u32>,
    pub(crate) track_brackets: bool,
    pub(crate) imatched: Vec<usize>,
    pub(crate) name: String,
}

impl LuaHost<'_> {
    pub(crate) fn set_this(&mut self, read_only: bool) -> mlua::Result<()> {
        if self.this_is_ro != Some(read_only) {
            let v = if read_only {
                self.this_ro
            } else {
                self.this_rw
            };
            self.lua.globals().raw_set("this", v.clone())?;
            self.this_is_ro = Some(read_only);
        }
        Ok(())
    }

    pub(crate) fn param_value(&self, s: &ModuleString, i: usize) -> mlua::Result<Value> {
        match s.external(i) {
            Some(slot) => Ok(self.side[slot as usize].clone()),
            None => {
                let params = s.params(i);
                let t = self.lua.create_table_with_capacity(params.len(), 0)?;
                for (k, p) in params.iter().enumerate() {
                    t.raw_set(k + 1, lua_number(*p))?;
                }
                Ok(Value::Table(t))
            }
        }
    }

    pub(crate) fn rule_error(&self, origin: u32, message: String) -> HostError {
        let location = self
            .cfg
            .locations
            .get(origin as usize)
            .cloned()
            .unwrap_or_default();
        HostError::Engine(Error::script(location, message))
    }

    pub(crate) fn push_symbol(
        &mut self,
        sym: Sym,
        t: &Table,
        out: &mut ModuleString,
    ) -> mlua::Result<()> {
        if sym == Sym::PUSH || sym == Sym::POP {
            out.push(sym, &[]);
        } else if numeric_params(t, &mut self.numbers)? {
            out.push(sym, &self.numbers);
        } else {
            let slot = self.side.len() as u32;
            self.side.push(Value::Table(t.clone()));
            out.push_external(sym, slot);
        }
        Ok(())
    }

    /// Appends a successor: a symbol, a classic string, or an array (nested arrays are
    /// branches).
    pub(crate) fn push_value(
        &mut self,
        v: &Value,
        out: &mut ModuleString,
        origin: u32,
        what: &dyn std::fmt::Display,
        depth: u32,
    ) -> Result<(), HostError> {
        if depth > MAX_SUCCESSOR_NESTING {
            return Err(self.rule_error(
                origin,
                format!(
                    "{what} nests arrays deeper than the limit of {MAX_SUCCESSOR_NESTING} levels"
                ),
            ));
        }
        match v {
            Value::Table(t) => {
                let sym = self.tags.borrow().symbol_of(t);
                match sym {
                    Some(sym) => self.push_symbol(sym, t, out)?,
                    None => {
                        // An array: its items; nested arrays are branches.
                        if depth > 0 {
                            out.push(Sym::PUSH, &[]);
                        }
                        for k in 1..=t.raw_len() {
                            let item: Value = t.raw_get(k)?;
                            self.push_value(&item, out, origin, what, depth + 1)?;
                        }
                        if depth > 0 {
                            out.push(Sym::POP, &[]);
                        }
                    }
                }
            }
            Value::String(s) => {
                let text = s.to_str()?.to_string();
                if let Some(ms) = self.parse_cache.get(&text) {
                    out.append(ms);
                } else {
                    let system = self.system;
                    let symbols = self.symbols;
                    let parsed = {
                        let mut table = symbols.borrow_mut();
                        let mut rand = || self.random();
                        system.parse_string_constness(&text, &mut table, &mut rand)
                    };
                    let (ms, constant) =
                        parsed.map_err(|e| self.rule_error(origin, format!("{what}: {e}")))?;
                    out.append(&ms);
                    // Only strings that evaluate the same every time may be reused.
                    if constant && self.parse_cache.len() < 4096 {
                        self.parse_cache.insert(text, ms);
                    }
                }
            }
            other => {
                return Err(self.rule_error(
                    origin,
                    format!(
                        "{what} is {}; a successor is a symbol, a string in classic notation \
                         or an array of them (nil: the rule does not apply, {{}}: delete)",
                        type_name(other)
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Names a rule's successor in error messages (formatted only when one is raised).
struct SuccessorOf<'a>(&'a str);

impl std::fmt::Display for SuccessorOf<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "the successor returned by RRule '{}'", self.0)
    }
}

fn type_name(v: &Value) -> String {
    match v {
        Value::UserData(ud) => match ud.type_name() {
            Ok(n) => n.to_string_lossy(),
            Err(_) => "userdata".to_string(),
        },
        other => other.type_name().to_string(),
    }
}

impl Host for LuaHost<'_> {
    type Error = HostError;

    fn random(&mut self) -> f64 {
        // Inside rule calls the instance's generator is the session's current one (see
        // `with_rng`); elsewhere it is ours.
        if self.rng_in_lua {
            current_uniform(self.lua)
        } else {
            uniform(self.rng)
        }
    }

    fn check(&mut self) -> Result<(), HostError> {
        self.ctx
            .check_deadline(&self.cfg.location)
            .map_err(HostError::Engine)
    }

    // Developer note: one protected call a module is the fastest path measured. A Lua loop
    // calling the rule for a whole run of modules in one protected call (commit 21100b6,
    // reverted) was 1.0-1.6x slower: its own Lua instructions, each trapped by the
    // instruction-count hook, cost more than the calls it saved (benches/README.md, "The
    // batched step").
    fn apply(
        &mut self,
        rule: u32,
        matched: &[usize],
        src: &ModuleString,
        out: &mut ModuleString,
    ) -> Result<bool, HostError> {
        let r: &LuaRule = &self.cfg.rrules[rule as usize];
        self.set_this(true)?;
        self.read_only.enter(r.text.clone());
        let m = matched[0];
        let result = if matched.len() == 1 && src.external(m).is_none() && src.params(m).len() <= 3
        {
            // The parameter table is built in Lua (cheaper than from Rust).
            let p = src.params(m);
            let f = &self.callers[p.len()];
            match *p {
                [] => f.call::<Value>(&r.func),
                [a] => f.call::<Value>((&r.func, lua_number(a))),
                [a, b] => f.call::<Value>((&r.func, lua_number(a), lua_number(b))),
                [a, b, c] => {
                    f.call::<Value>((&r.func, lua_number(a), lua_number(b), lua_number(c)))
                }
                _ => unreachable!("at most three parameters here"),
            }
        } else if matched.len() == 1 {
            let arg = self.param_value(src, m)?;
            r.func.call::<Value>(arg)
        } else {
            let mut args = Vec::with_capacity(matched.len());
            for &m in matched {
                args.push(self.param_value(src, m)?);
            }
            r.func.call::<Value>(MultiValue::from_vec(args))
        };
        self.read_only.leave();
        let v = result?;
        if v.is_nil() {
            return Ok(false);
        }
        self.push_value(&v, out, r.origin, &SuccessorOf(&r.text), 0)?;
        Ok(true)
    }

    fn interpret(&mut self, out: &ModuleString, from: usize) -> Result<(), HostError> {
        if !self.interpret {
            return Ok(());
        }
        for i in from..out.len() {
            self.interpret_module(out, i)?;
        }
        Ok(())
    }
}
