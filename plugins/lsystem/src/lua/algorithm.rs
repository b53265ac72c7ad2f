//! The L-system as an [`Algorithm`]: one step is one derivation step, with the rule
//! functions called through the host ([`super::host`]) and interpretation
//! ([`super::interpret`]) streamed after each module.

use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;

use mlua::{Function, Lua, ObjectLike, Value, WeakLua};
use pge_engine::geometry::Model;
use pge_engine::lua::{
    DefaultInterpreter, check_mutable, default_instance, engine_chunk, interpreters,
    read_only_phase, script_error, swap_rng, to_engine_error, to_model_in,
};
use pge_engine::{Algorithm, Error, RunContext, Step};
use rand_mt::Mt;

use super::config::{Axiom, Config};
use super::host::{HostError, LuaHost};
use super::session_symbols;
use super::stream::{LastStep, StreamHost};
use super::symbols::tags;
use crate::{DeriveOptions, Host, LsError, ModuleString, Output, Prepared, SymbolTable, System};

/// A derivation in progress: the string, the instance (`this`), the generator.
pub struct LSystemAlgorithm {
    lua: WeakLua,
    cfg: Config,
    /// The rules compiled by `init` (and again when a global changes).
    prepared: Option<Prepared>,
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

impl LSystemAlgorithm {
    /// An algorithm running a copy of `cfg`. With `skip_interpretation` nothing interprets
    /// the string (for `pge derive` on systems whose rules cannot observe it).
    pub(crate) fn new(lua: &Lua, cfg: Config, skip_interpretation: bool) -> LSystemAlgorithm {
        LSystemAlgorithm {
            lua: lua.weak(),
            symbols: session_symbols(lua),
            cfg,
            prepared: None,
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

    /// Moves the current string and the Lua parameter tables of its external modules out.
    pub(crate) fn take_string(&mut self) -> (ModuleString, Vec<Value>) {
        self.scratch = ModuleString::new();
        (
            std::mem::take(&mut self.string),
            std::mem::take(&mut self.side),
        )
    }

    /// Derives like [`pge_engine::algorithm::grow`] for `pge derive`. When nothing of Lua
    /// takes part in the last steps (no interpretation, rule functions or callbacks), those
    /// steps are only counted, checking every limit, and returned to be streamed: the
    /// current string is then the one before them (the axiom, when the rules let every step
    /// be taken depth first: see [`Prepared::derives_in_pieces`]; else the string before
    /// the last step).
    pub(crate) fn grow_for_output(
        &mut self,
        ctx: &RunContext,
    ) -> pge_engine::Result<Option<LastStep>> {
        self.init(ctx)?;
        let target = ctx.steps.unwrap_or(self.cfg.iterations);
        let stream = target > 0
            && self.skip_interpretation
            && !self.lua_involved
            && !self.cfg.system.has_external();
        let before = match &self.prepared {
            Some(p) if stream && p.derives_in_pieces() => 0,
            _ if stream => target - 1,
            _ => target,
        };
        while self.done < before {
            if self.step(ctx)? == Step::Done {
                break;
            }
        }
        if !stream || self.done != before {
            return Ok(None);
        }
        // The previous step's buffer is not needed any more.
        self.scratch = ModuleString::new();
        self.guarded(ctx, |me, _, ctx| {
            let prepared = me.prepared()?.clone();
            let opts = DeriveOptions::new(me.done + 1, target - me.done, me.max_modules);
            let rng = me.rng.clone();
            let location = me.cfg.location.clone();
            let mut host = StreamHost {
                rng: &mut me.rng,
                limits: Some((ctx, &location)),
            };
            let len = prepared.derive(&me.string, &opts, &mut host, Output::Count)?;
            me.done = target;
            Ok(Some(LastStep {
                prepared,
                rng,
                opts,
                len,
            }))
        })
    }

    /// The compiled rules (`init` compiles them).
    fn prepared(&self) -> Result<&Prepared, HostError> {
        self.prepared.as_ref().ok_or_else(|| self.not_initialised())
    }

    #[cold]
    fn not_initialised(&self) -> HostError {
        HostError::Engine(Error::script(
            self.cfg.location.clone(),
            format!("L-system '{}' derived before its init", self.cfg.name),
        ))
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
        let prepared = match &self.prepared {
            Some(p) => p,
            None => return Err(self.not_initialised()),
        };
        let instance_ud = match &self.this_rw {
            Value::UserData(ud) if !self.interpreters.is_empty() => Some(ud.clone()),
            _ => None,
        };
        let mut host = LuaHost {
            lua,
            ctx,
            cfg: &self.cfg,
            system: &self.cfg.system,
            prepared,
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
        // Functions with fixed parameters: a vararg chunk would copy its arguments on
        // every call.
        self.callers = [
            "return function(f) return f({}) end",
            "return function(f, a) return f({a}) end",
            "return function(f, a, b) return f({a, b}) end",
            "return function(f, a, b, c) return f({a, b, c}) end",
        ]
        .iter()
        .map(|code| engine_chunk(lua, "=pge.lsystem", code)?.call::<Function>(()))
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
        self.prepared = Some(self.cfg.system.prepare(&self.symbols.borrow())?);
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
        let opts = DeriveOptions {
            interpret: stream,
            ..DeriveOptions::new(self.done + 1, 1, self.max_modules)
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
            me.with_host(lua, ctx, lua_involved, stream, |host, _, string, out| {
                let prepared = host.prepared;
                prepared.derive(string, &opts, host, Output::Keep(out))
            })?;
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
            self.prepared = Some(
                self.cfg
                    .system
                    .prepare(&self.symbols.borrow())
                    .map_err(|e| mlua::Error::RuntimeError(e.to_string()))?,
            );
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
                    || pge_engine::lua::is_model_or_mesh(ud)
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
