//! The L-system as an [`Algorithm`]: one step is one derivation step, with the rule
//! functions called through the [`Host`] trait and interpretation streamed after each module.

use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;

use mlua::{AnyUserData, Function, Lua, MultiValue, ObjectLike, Table, Value, WeakLua};
use pge_engine::geometry::Model;
use pge_engine::lua::{script_error, swap_rng, to_engine_error, to_model_in};
use pge_engine::{Algorithm, Error, Location, RunContext, Step};
use rand_mt::Mt;

use super::object::{Axiom, Config, LuaIRule, LuaRule};
use super::session_symbols;
use super::symbols::{SymbolTags, tags};
use crate::system::uniform;
use crate::{Host, LsError, ModuleString, StepOptions, Sym, SymbolTable, System};
use pge_engine::lua::{
    DefaultInterpreter, ReadOnlyPhase, check_mutable, current_uniform, default_instance,
    interpreters, read_only_phase,
};

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

/// A derivation in progress: the string, the instance (`this`), the generator.
pub struct LSystemAlgorithm {
    lua: WeakLua,
    cfg: Config,
    symbols: Rc<RefCell<SymbolTable>>,
    string: ModuleString,
    scratch: ModuleString,
    /// Lua parameter tables of the string's external modules.
    side: Vec<Value>,
    rng: Mt,
    this_rw: Value,
    this_ro: Value,
    done: u32,
    /// The step whose string the instance last interpreted.
    interpreted: Option<u32>,
    /// `pge derive` without rules that could change the string: no interpretation at all.
    skip_interpretation: bool,
    irules_by_sym: Vec<Vec<u32>>,
    parse_cache: HashMap<String, ModuleString>,
    lua_involved: bool,
    max_modules: usize,
    interpreters: Vec<DefaultInterpreter>,
    callers: Vec<Function>,
}

/// `genrand` key of an instance: the run's seed and the object's index.
fn instance_rng(seed: u64, index: u32) -> Mt {
    Mt::new_with_key([seed as u32, (seed >> 32) as u32, index, 0x4c53_5953])
}

/// A parameter as Lua sees it: integral values as integers (as the script wrote them).
fn lua_number(v: f64) -> Value {
    if v.fract() == 0.0 && v.abs() < 9_007_199_254_740_992.0 {
        Value::Integer(v as i64)
    } else {
        Value::Number(v)
    }
}

fn truthy(v: &Value) -> bool {
    !matches!(v, Value::Nil | Value::Boolean(false))
}

/// Reads the numbers of a parameter table that is a plain array of numbers.
fn numeric_params(t: &Table, out: &mut Vec<f64>) -> mlua::Result<bool> {
    out.clear();
    let n = t.raw_len();
    if n == 0 {
        return Ok(t.is_empty());
    }
    for i in 1..=n {
        match t.raw_get::<Value>(i)? {
            Value::Integer(x) => out.push(x as f64),
            Value::Number(x) => out.push(x),
            _ => return Ok(false),
        }
    }
    let mut count = 0usize;
    for pair in t.pairs::<Value, Value>() {
        pair?;
        count += 1;
        if count > n {
            return Ok(false);
        }
    }
    Ok(true)
}

/// The positional numbers of a parameter table (for the default interpretation).
fn positional_numbers(v: &Value, out: &mut Vec<f64>) -> mlua::Result<()> {
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

struct LuaHost<'a> {
    lua: &'a Lua,
    ctx: &'a RunContext,
    cfg: &'a Config,
    system: &'a System,
    symbols: &'a RefCell<SymbolTable>,
    side: &'a mut Vec<Value>,
    parse_cache: &'a mut HashMap<String, ModuleString>,
    rng: &'a mut Mt,
    rng_in_lua: bool,
    this_rw: &'a Value,
    this_ro: &'a Value,
    this_is_ro: Option<bool>,
    irules_by_sym: &'a [Vec<u32>],
    interpreters: &'a [DefaultInterpreter],
    instance_ud: Option<AnyUserData>,
    interpret: bool,
    numbers: Vec<f64>,
    tags: Rc<RefCell<SymbolTags>>,
    read_only: ReadOnlyPhase,
    /// `function(f, ...) return f({...}) end` for 0 to 3 numeric parameters.
    callers: &'a [Function],
    /// Bracket pairs of the string interpreted so far (for IRules with a left context).
    imatches: Vec<u32>,
    istack: Vec<u32>,
    track_brackets: bool,
    imatched: Vec<usize>,
    name: String,
}

impl LuaHost<'_> {
    fn set_this(&mut self, read_only: bool) -> mlua::Result<()> {
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

    fn param_value(&self, s: &ModuleString, i: usize) -> mlua::Result<Value> {
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

    fn rule_error(&self, origin: u32, message: String) -> HostError {
        let location = self
            .cfg
            .locations
            .get(origin as usize)
            .cloned()
            .unwrap_or_default();
        HostError::Engine(Error::script(location, message))
    }

    fn push_symbol(&mut self, sym: Sym, t: &Table, out: &mut ModuleString) -> mlua::Result<()> {
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
    fn push_value(
        &mut self,
        v: &Value,
        out: &mut ModuleString,
        origin: u32,
        what: &dyn std::fmt::Display,
        depth: u32,
    ) -> Result<(), HostError> {
        if depth > 100 {
            return Err(self.rule_error(origin, format!("{what} nests arrays too deeply")));
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

    fn interpret_module(&mut self, s: &ModuleString, i: usize) -> Result<(), HostError> {
        let sym = s.sym(i);
        if self.track_brackets {
            if self.imatches.len() <= i {
                self.imatches.resize(i + 1, u32::MAX);
            }
            if sym == Sym::PUSH {
                self.istack.push(i as u32);
            } else if sym == Sym::POP
                && let Some(open) = self.istack.pop()
            {
                self.imatches[i] = open;
                self.imatches[open as usize] = i as u32;
            }
        }
        if let Some(list) = self.irules_by_sym.get(sym.index())
            && !list.is_empty()
        {
            let arg = self.param_value(s, i)?;
            self.set_this(false)?;
            for &k in list {
                let rule: &LuaIRule = &self.cfg.irules[k as usize];
                let v: Value = if rule.left.is_empty() {
                    rule.func.call(arg.clone())?
                } else {
                    let mut matched = std::mem::take(&mut self.imatched);
                    matched.clear();
                    let found = self.system.match_left_context(
                        &rule.left,
                        s,
                        &self.imatches,
                        i,
                        &mut matched,
                    );
                    let mut args = Vec::with_capacity(matched.len() + 1);
                    if found {
                        for &m in &matched {
                            args.push(self.param_value(s, m)?);
                        }
                        args.push(arg.clone());
                    }
                    self.imatched = matched;
                    if !found {
                        continue;
                    }
                    rule.func.call(MultiValue::from_vec(args))?
                };
                if truthy(&v) {
                    return Ok(());
                }
            }
        }
        if let Some(ud) = &self.instance_ud {
            let params: &[f64] = match s.external(i) {
                Some(slot) => {
                    positional_numbers(&self.side[slot as usize], &mut self.numbers)?;
                    &self.numbers
                }
                None => s.params(i),
            };
            // The name is copied so an interpreter may run Lua code that makes symbols.
            self.name.clear();
            self.name.push_str(self.symbols.borrow().name(sym));
            for f in self.interpreters {
                if f(self.lua, ud, &self.name, params)? {
                    break;
                }
            }
        }
        Ok(())
    }

    fn interpret_all(&mut self, s: &ModuleString, location: &Location) -> Result<(), HostError> {
        for i in 0..s.len() {
            if i & 0xFFFF == 0 {
                self.ctx
                    .check_deadline(location)
                    .map_err(HostError::Engine)?;
            }
            self.interpret_module(s, i)?;
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

impl LSystemAlgorithm {
    /// An algorithm running a copy of `cfg`. With `skip_interpretation` nothing interprets
    /// the string (for `pge derive` on systems whose rules cannot observe it).
    pub(crate) fn new(lua: &Lua, cfg: Config, skip_interpretation: bool) -> LSystemAlgorithm {
        LSystemAlgorithm {
            lua: lua.weak(),
            symbols: session_symbols(lua),
            cfg,
            string: ModuleString::new(),
            scratch: ModuleString::new(),
            side: Vec::new(),
            rng: Mt::new(1),
            this_rw: Value::Nil,
            this_ro: Value::Nil,
            done: 0,
            interpreted: None,
            skip_interpretation,
            irules_by_sym: Vec::new(),
            parse_cache: HashMap::new(),
            lua_involved: false,
            max_modules: 10_000_000,
            interpreters: Vec::new(),
            callers: Vec::new(),
        }
    }

    /// The current string.
    #[must_use]
    pub fn string(&self) -> &ModuleString {
        &self.string
    }

    /// The Lua parameter table of external module `i` of the current string.
    #[must_use]
    pub fn external_params(&self, i: usize) -> Option<&Value> {
        self.string
            .external(i)
            .and_then(|slot| self.side.get(slot as usize))
    }

    /// The symbol table the string's symbols refer to.
    #[must_use]
    pub fn symbols(&self) -> std::cell::Ref<'_, SymbolTable> {
        self.symbols.borrow()
    }

    /// Derivation steps taken.
    #[must_use]
    pub fn steps_taken(&self) -> u32 {
        self.done
    }

    fn upgrade(&self) -> pge_engine::Result<Lua> {
        self.lua.try_upgrade().ok_or_else(|| {
            Error::script(
                self.cfg.location.clone(),
                "the Lua session of this L-system is gone",
            )
        })
    }

    fn engine_error(&self, lua: &Lua, e: HostError) -> Error {
        match e {
            // Errors raised while no Lua code runs (the default interpretation of a
            // module) carry no place: they belong to this L-system.
            HostError::Lua(e) => match to_engine_error(lua, e) {
                Error::Script {
                    location,
                    message,
                    traceback,
                } if location.file == "?" => Error::Script {
                    location: self.cfg.location.clone(),
                    message: format!("L-system '{}': {message}", self.cfg.name),
                    traceback,
                },
                other => other,
            },
            HostError::Engine(e) => e,
            HostError::Ls(e @ LsError::Rule { origin, .. }) => Error::script(
                self.cfg
                    .locations
                    .get(origin as usize)
                    .cloned()
                    .unwrap_or_default(),
                e.to_string(),
            ),
            HostError::Ls(LsError::TooManyModules { step, count, max }) => Error::ModuleLimit {
                location: self.cfg.location.clone(),
                system: self.cfg.name.clone(),
                step,
                count,
                max,
            },
            HostError::Ls(e) => Error::script(
                self.cfg.location.clone(),
                format!("L-system '{}': {e}", self.cfg.name),
            ),
        }
    }

    /// Makes a host over this algorithm's state and runs `f` with it and the current string.
    fn with_host<R>(
        &mut self,
        lua: &Lua,
        ctx: &RunContext,
        rng_in_lua: bool,
        interpret: bool,
        f: impl FnOnce(
            &mut LuaHost<'_>,
            &System,
            &ModuleString,
            &mut ModuleString,
        ) -> Result<R, HostError>,
    ) -> Result<R, HostError> {
        let instance_ud = match &self.this_rw {
            Value::UserData(ud) if !self.interpreters.is_empty() => Some(ud.clone()),
            _ => None,
        };
        let mut host = LuaHost {
            lua,
            ctx,
            cfg: &self.cfg,
            system: &self.cfg.system,
            symbols: &self.symbols,
            side: &mut self.side,
            parse_cache: &mut self.parse_cache,
            rng: &mut self.rng,
            rng_in_lua,
            this_rw: &self.this_rw,
            this_ro: &self.this_ro,
            this_is_ro: None,
            irules_by_sym: &self.irules_by_sym,
            interpreters: &self.interpreters,
            instance_ud,
            interpret,
            numbers: Vec::new(),
            tags: tags(lua),
            read_only: read_only_phase(lua),
            callers: &self.callers,
            imatches: Vec::new(),
            istack: Vec::new(),
            track_brackets: self.cfg.irules.iter().any(|r| !r.left.is_empty()),
            imatched: Vec::new(),
            name: String::new(),
        };
        f(&mut host, &self.cfg.system, &self.string, &mut self.scratch)
    }

    /// Runs `f` with the instance's generator behind `pge.random()`.
    fn with_rng<R>(&mut self, lua: &Lua, f: impl FnOnce(&mut Self) -> R) -> R {
        let mine = std::mem::replace(&mut self.rng, Mt::new(0));
        let old = swap_rng(lua, mine);
        let r = f(self);
        self.rng = swap_rng(lua, old);
        r
    }

    fn call_reset(&self) -> mlua::Result<()> {
        let has_reset = match &self.this_rw {
            Value::UserData(ud) => matches!(ud.get::<Value>("reset"), Ok(Value::Function(_))),
            Value::Table(t) => matches!(t.get::<Value>("reset"), Ok(Value::Function(_))),
            _ => false,
        };
        if has_reset {
            match &self.this_rw {
                Value::UserData(ud) => ud.call_method::<()>("reset", ())?,
                Value::Table(t) => t.call_method::<()>("reset", ())?,
                _ => {}
            }
        }
        Ok(())
    }

    fn set_instance(&mut self, lua: &Lua, v: Value) -> mlua::Result<()> {
        self.this_ro = match &v {
            Value::Table(t) => {
                let fail =
                    lua.create_function(|lua, (_, k): (Value, Value)| -> mlua::Result<()> {
                        let key = k.to_string().unwrap_or_else(|_| "?".into());
                        check_mutable(lua, &format!("writing this.{key}"))?;
                        Err(script_error(lua, format!("this.{key} is read-only here")))
                    })?;
                let meta = lua.create_table()?;
                meta.raw_set("__index", t.clone())?;
                meta.raw_set("__newindex", fail)?;
                let proxy = lua.create_table()?;
                proxy.set_metatable(Some(meta))?;
                Value::Table(proxy)
            }
            other => other.clone(),
        };
        self.this_rw = v;
        lua.globals().raw_set("this", self.this_rw.clone())
    }

    /// Interprets the whole current string from a reset instance.
    fn interpret_now(&mut self, lua: &Lua, ctx: &RunContext) -> Result<(), HostError> {
        let location = self.cfg.location.clone();
        let rng_in_lua = self.lua_involved;
        let run = |me: &mut Self| -> Result<(), HostError> {
            me.call_reset()?;
            me.with_host(lua, ctx, rng_in_lua, true, |host, _, string, _| {
                host.interpret_all(string, &location)
            })
        };
        if rng_in_lua {
            self.with_rng(lua, run)
        } else {
            run(self)
        }?;
        self.interpreted = Some(self.done);
        Ok(())
    }

    fn init_inner(&mut self, lua: &Lua, ctx: &RunContext) -> Result<(), HostError> {
        self.interpreters = interpreters(lua);
        self.callers = [
            "local f = ... return f({})",
            "local f, a = ... return f({a})",
            "local f, a, b = ... return f({a, b})",
            "local f, a, b, c = ... return f({a, b, c})",
        ]
        .iter()
        .map(|code| lua.load(*code).set_name("=pge.lsystem").into_function())
        .collect::<mlua::Result<_>>()?;
        // Numeric globals become names classic expressions can read.
        for pair in self.cfg.globals.pairs::<Value, Value>() {
            let (k, v) = pair?;
            if let (Value::String(k), Some(v)) =
                (&k, v.as_number().or(v.as_integer().map(|i| i as f64)))
            {
                self.cfg.system.set_global(&k.to_str()?, v);
            }
        }
        self.cfg.system.prepare(&self.symbols.borrow())?;
        self.max_modules = self.cfg.max_modules.unwrap_or(ctx.max_modules);
        self.rng = instance_rng(ctx.seed, self.cfg.index);
        self.lua_involved = !self.cfg.rrules.is_empty()
            || !self.cfg.irules.is_empty()
            || self.cfg.before.is_some()
            || self.cfg.after.is_some();
        let n = self.symbols.borrow().len();
        self.irules_by_sym = vec![Vec::new(); n];
        for (k, r) in self.cfg.irules.iter().enumerate() {
            self.irules_by_sym[r.sym.index()].push(k as u32);
        }
        self.done = 0;
        self.interpreted = None;
        self.side.clear();
        self.parse_cache.clear();
        // The instance.
        let create = self.cfg.create.clone();
        let instance = self.with_rng(lua, |_| -> mlua::Result<Value> {
            match &create {
                Some(f) => f.call::<Value>(()),
                // The default instance a plugin registered with the engine (the turtle).
                None => match default_instance(lua)? {
                    Some(instance) => Ok(instance),
                    None => Ok(Value::Table(lua.create_table()?)),
                },
            }
        })?;
        self.set_instance(lua, instance)?;
        // The axiom.
        let Some((axiom, location)) = self.cfg.axiom.clone() else {
            return Err(HostError::Engine(Error::script(
                self.cfg.location.clone(),
                format!(
                    "L-system '{}' has no axiom (call obj:axiom(...))",
                    self.cfg.name
                ),
            )));
        };
        let mut string = ModuleString::new();
        let parsed = self.with_host(lua, ctx, false, false, |host, system, _, _| {
            match &axiom {
                Axiom::Text(text) => {
                    let symbols = host.symbols;
                    let mut table = symbols.borrow_mut();
                    let mut rand = || host.random();
                    string = system.parse_string(text, &mut table, &mut rand)?;
                }
                Axiom::Lua(t) => {
                    host.push_value(
                        &Value::Table(t.clone()),
                        &mut string,
                        u32::MAX,
                        &"the axiom",
                        0,
                    )?;
                }
            }
            Ok(())
        });
        match parsed {
            Ok(()) => {}
            Err(HostError::Ls(e)) => {
                return Err(HostError::Engine(Error::script(
                    location,
                    format!("axiom: {e}"),
                )));
            }
            Err(HostError::Engine(Error::Script { message, .. })) => {
                return Err(HostError::Engine(Error::script(location, message)));
            }
            Err(e) => return Err(e),
        }
        if string.len() > self.max_modules {
            return Err(LsError::TooManyModules {
                step: 0,
                count: string.len() as u64,
                max: self.max_modules,
            }
            .into());
        }
        self.string = string;
        if self.cfg.every_step && self.lua_involved && !self.skip_interpretation {
            self.interpret_now(lua, ctx)?;
        }
        Ok(())
    }

    fn step_inner(&mut self, lua: &Lua, ctx: &RunContext) -> Result<Step, HostError> {
        let target = ctx.steps.unwrap_or(self.cfg.iterations);
        if self.done >= target {
            return Ok(Step::Done);
        }
        let stream = self.cfg.every_step && self.lua_involved && !self.skip_interpretation;
        let lua_involved = self.lua_involved;
        let opts = StepOptions {
            step: self.done + 1,
            max_modules: self.max_modules,
            stream,
        };
        let body = |me: &mut Self| -> Result<(), HostError> {
            if stream {
                me.call_reset()?;
            }
            lua.globals().raw_set("this", me.this_rw.clone())?;
            if let Some(f) = me.cfg.before.clone() {
                let v: Value = f.call(())?;
                if !v.is_nil() {
                    me.set_instance(lua, v)?;
                }
                me.sync_globals()?;
            }
            me.with_host(
                lua,
                ctx,
                lua_involved,
                stream,
                |host, system, string, out| system.step(string, out, host, &opts),
            )?;
            std::mem::swap(&mut me.string, &mut me.scratch);
            me.compact_side();
            me.done += 1;
            if stream {
                me.interpreted = Some(me.done);
            }
            lua.globals().raw_set("this", me.this_rw.clone())?;
            if let Some(f) = me.cfg.after.clone() {
                f.call::<()>(())?;
            }
            me.sync_globals()?;
            Ok(())
        };
        if lua_involved {
            self.with_rng(lua, body)
        } else {
            body(self)
        }?;
        Ok(if self.done >= target {
            Step::Done
        } else {
            Step::Continue
        })
    }

    /// Numeric globals changed by IRules and callbacks reach classic expressions.
    fn sync_globals(&mut self) -> mlua::Result<()> {
        let mut changed = false;
        for pair in self.cfg.globals.pairs::<Value, Value>() {
            let (k, v) = pair?;
            if let (Value::String(k), Some(v)) =
                (&k, v.as_number().or(v.as_integer().map(|i| i as f64)))
            {
                let k = k.to_str()?;
                if self.cfg.system.global(&k) != Some(v) {
                    self.cfg.system.set_global(&k, v);
                    changed = true;
                }
            }
        }
        if changed {
            self.cfg
                .system
                .prepare(&self.symbols.borrow())
                .map_err(|e| mlua::Error::RuntimeError(e.to_string()))?;
        }
        Ok(())
    }

    fn compact_side(&mut self) {
        if self.side.is_empty() {
            return;
        }
        let mut kept = Vec::new();
        for i in 0..self.string.len() {
            if let Some(slot) = self.string.external(i) {
                kept.push(self.side[slot as usize].clone());
                self.string.set_external_slot(i, kept.len() as u32 - 1);
            }
        }
        self.side = kept;
    }

    fn finish_inner(&mut self, lua: &Lua, ctx: &RunContext) -> Result<Model, HostError> {
        if !self.skip_interpretation && self.interpreted != Some(self.done) {
            self.interpret_now(lua, ctx)?;
        }
        let has_model = match &self.this_rw {
            Value::UserData(ud) => {
                matches!(ud.get::<Value>("model"), Ok(Value::Function(_)))
                    || ud.is::<pge_engine::lua::LuaModel>()
                    || ud.is::<pge_engine::lua::LuaMesh>()
            }
            Value::Table(t) => matches!(t.get::<Value>("model"), Ok(Value::Function(_))),
            _ => false,
        };
        let mut model = if has_model {
            to_model_in(lua, &self.this_rw, ctx)?
        } else {
            Model::new()
        };
        model.stats.modules = self.string.len() as u64;
        Ok(model)
    }

    /// Runs `f`, turning its error into an engine error with a file and line.
    fn guarded<R>(
        &mut self,
        ctx: &RunContext,
        f: impl FnOnce(&mut Self, &Lua, &RunContext) -> Result<R, HostError>,
    ) -> pge_engine::Result<R> {
        let lua = self.upgrade()?;
        // An L-system run inside another one's rule leaves the outer `this` as it found it.
        let outer_this: Value = lua.globals().raw_get("this").unwrap_or(Value::Nil);
        let result = f(self, &lua, ctx);
        let _ = lua.globals().raw_set("this", outer_this);
        read_only_phase(&lua).leave();
        result.map_err(|e| self.engine_error(&lua, e))
    }
}

impl Algorithm for LSystemAlgorithm {
    fn name(&self) -> &str {
        &self.cfg.name
    }

    fn init(&mut self, ctx: &RunContext) -> pge_engine::Result<()> {
        self.guarded(ctx, |me, lua, ctx| me.init_inner(lua, ctx))
    }

    fn step(&mut self, ctx: &RunContext) -> pge_engine::Result<Step> {
        self.guarded(ctx, |me, lua, ctx| me.step_inner(lua, ctx))
    }

    fn finish(&mut self, ctx: &RunContext) -> pge_engine::Result<Model> {
        self.guarded(ctx, |me, lua, ctx| me.finish_inner(lua, ctx))
    }

    fn planned_steps(&self) -> Option<u32> {
        Some(self.cfg.iterations)
    }
}
