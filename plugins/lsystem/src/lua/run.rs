//! Runs of rule calls: one protected call from Rust runs a Lua loop that applies an RRule to
//! many modules of a step, instead of one protected call per module.
//!
//! Developer note: which modules take this path is invisible to scripts except for speed.
//! A run is the modules of one symbol whose first rule is a Lua RRule without context, with
//! the modules without rules between them (copied), within one step. It is taken only
//! where nothing can see that the rule of a module runs before the successors of the
//! modules before it are interpreted: the step interprets nothing (`interpretEveryStep(false)`,
//! `pge derive` of a system that needs no interpretation) or its interpretation does
//! nothing (no IRule, and an instance the default interpreters do not drive, such as a Lua
//! table from `createInstance`). Everything else keeps the module-by-module path.
//!
//! The loop stops and hands back to Rust, in order, wherever Rust must act before the next
//! rule runs: a successor that is not a symbol or a flat array of symbols (a string may draw
//! random numbers while parsed; anything else may be an error), a rule that does not apply
//! when other rules of the symbol follow it (they are tried by the rewriting loop), and the
//! module cap (counted in the loop as the modules go by). The rules run in module order,
//! with `this` read-only as always, so random draws, errors and limits are those of the
//! module-by-module path; only the instruction count differs (the loop's own instructions),
//! and an instruction-limit or time-limit error raised in the loop names the rule.

use mlua::{Function, Lua, Table, Value};
use pge_engine::Error;
use pge_engine::lua::to_engine_error;

use super::host::{HostError, LuaHost, lua_number};
use crate::{ModuleString, RunEnd};

/// The name of the Lua chunks of this plugin (the run loop, the rule callers).
pub(crate) const CHUNK: &str = "pge.lsystem";

/// The loop: `loop(f, fmt, data, X, jobs, budget, R, more)` calls rule `f` for each job. The
/// jobs are read from `data`, unpacked with `string.unpack(fmt, data)` in one call: for
/// each job a header `copies * 8 + kind`, where `copies` counts the modules of the run
/// copied before the job, and kind 0 to 3: that many numbers follow (the job's parameters);
/// 4: an index into `X`, the job's parameter table, follows. Each result goes to `R`
/// (`false`: the rule did not apply). Returns the jobs done and why it stopped: 0 all done
/// or the budget passed after the last, 1 the copies before the next job would pass the
/// budget, 2 the last job's rule did not apply and more rules follow, 3 the last job's
/// result is for Rust to read first (not a symbol or an array of symbols).
const LOOP: &str = r#"
local getmetatable, type, unpack, marks = ...
return function(f, fmt, data, X, jobs, budget, R, more)
  local P = {unpack(fmt, data)}
  local made, j = 0, 1
  for k = 1, jobs do
    local h = P[j]
    local kind = h % 8
    local copies = h // 8
    if made + copies > budget then return k - 1, 1 end
    local a
    if kind == 1 then a = {P[j + 1]}; j = j + 2
    elseif kind == 0 then a = {}; j = j + 1
    elseif kind == 2 then a = {P[j + 1], P[j + 2]}; j = j + 3
    elseif kind == 3 then a = {P[j + 1], P[j + 2], P[j + 3]}; j = j + 4
    else a = X[P[j + 1]]; j = j + 2 end
    local r = f(a)
    if r == nil then
      if more then return k, 2 end
      R[k] = false
      made = made + 1
    elseif marks[getmetatable(r)] then
      R[k] = r
      made = made + 1
    elseif type(r) == "table" and getmetatable(r) == nil then
      R[k] = r
      local c = #r
      for q = 1, c do
        if not marks[getmetatable(r[q])] then return k, 3 end
      end
      made = made + c
    else
      R[k] = r
      return k, 3
    end
    if made + copies > budget then return k, 0 end
  end
  return jobs, 0
end, function(f, fmt, data, n, R, more)
  local P = {unpack(fmt, data)}
  local marks, getmetatable = marks, getmetatable
  for k = 1, n do
    local r = f({P[k]})
    if marks[getmetatable(r)] then
      R[k] = r
    elseif r == nil and not more then
      R[k] = false
    elseif r == nil then
      return k, 2
    else
      R[k] = r
      return k, 3
    end
  end
  return n, 0
end
"#;

/// Makes the run loop over the session's symbol metatables `marks`, with the base library's
/// functions as they are before any script runs.
pub(crate) fn run_loop(lua: &Lua, marks: &Table) -> mlua::Result<(Function, Function)> {
    let globals = lua.globals();
    let string: Table = globals.get("string")?;
    lua.load(LOOP).set_name(format!("={CHUNK}")).call((
        globals.get::<Function>("getmetatable")?,
        globals.get::<Function>("type")?,
        string.get::<Function>("unpack")?,
        marks.clone(),
    ))
}

impl LuaHost<'_> {
    /// Whether this step may hand runs to [`LuaHost::apply_run_lua`]: its interpretation, if
    /// any, does nothing (no IRule, no instance the default interpreters drive).
    pub(crate) fn runs_allowed(&self) -> bool {
        self.run_loop.is_some()
            && (!self.interpret || (self.cfg.irules.is_empty() && self.instance_ud.is_none()))
    }

    /// [`crate::Host::apply_run`] with one call of the run loop.
    pub(crate) fn apply_run_lua(
        &mut self,
        rule: u32,
        jobs: &[usize],
        more: bool,
        src: &ModuleString,
        out: &mut ModuleString,
        budget: u64,
    ) -> Result<RunEnd, HostError> {
        let Some((run_loop, dense)) = self.run_loop.clone() else {
            return Err(HostError::Engine(Error::script(
                self.cfg.location.clone(),
                "the run loop of L-system rules is missing",
            )));
        };
        let first = jobs[0];
        if jobs.len() == jobs[jobs.len() - 1] - first + 1
            && jobs
                .iter()
                .all(|&m| src.external(m).is_none() && src.params(m).len() == 1)
        {
            let n = jobs
                .len()
                .min(budget.saturating_add(1).min(usize::MAX as u64) as usize);
            let (mut fmt, mut data) = std::mem::take(&mut self.run_packed);
            fmt.clear();
            data.clear();
            fmt.push(b'<');
            for &m in &jobs[..n] {
                pack(&mut fmt, &mut data, lua_number(src.params(m)[0]));
            }
            let packed = (
                self.lua.create_string(&fmt)?,
                self.lua.create_string(&data)?,
            );
            self.run_packed = (fmt, data);
            let results = self.lua.create_table_with_capacity(n, 0)?;
            let r = &self.cfg.rrules[rule as usize];
            let (func, origin, text) = (r.func.clone(), r.origin, r.text.clone());
            self.set_this(true)?;
            self.read_only.enter(text.clone());
            let called = dense.call::<(usize, u8)>((func, packed.0, packed.1, n, &results, more));
            self.read_only.leave();
            let (done, why) = called.map_err(|e| self.locate(e, origin))?;
            let what = super::host::SuccessorOf(&text);
            let plain = if why == 0 { done } else { done - 1 };
            for (k, &m) in jobs[..plain].iter().enumerate() {
                match results.raw_get::<Value>(k + 1)? {
                    Value::Boolean(false) => out.push_from(src, m),
                    v => self.push_value(&v, out, origin, &what, 0)?,
                }
            }
            let next = first + plain;
            return match why {
                2 => Ok(RunEnd {
                    next,
                    fell_through: true,
                }),
                3 => {
                    let v = results.raw_get::<Value>(done)?;
                    self.push_value(&v, out, origin, &what, 0)?;
                    Ok(RunEnd {
                        next: next + 1,
                        fell_through: false,
                    })
                }
                _ => Ok(RunEnd {
                    next,
                    fell_through: false,
                }),
            };
        }
        // The jobs packed for one `string.unpack`: integers as `j`, other numbers as `n`
        // (a rule sees integral parameters as Lua integers, as module by module).
        let (mut fmt, mut data) = std::mem::take(&mut self.run_packed);
        fmt.clear();
        data.clear();
        fmt.push(b'<');
        let mut tables = Vec::new();
        for (k, &m) in jobs.iter().enumerate() {
            let copies = ((m - first - k) as i64) << 3;
            let params = src.params(m);
            if src.external(m).is_none() && params.len() <= 3 {
                pack(
                    &mut fmt,
                    &mut data,
                    Value::Integer(copies | params.len() as i64),
                );
                for &p in params {
                    pack(&mut fmt, &mut data, lua_number(p));
                }
            } else {
                tables.push(self.param_value(src, m)?);
                pack(&mut fmt, &mut data, Value::Integer(copies | 4));
                pack(&mut fmt, &mut data, Value::Integer(tables.len() as i64));
            }
        }
        let packed = (
            self.lua.create_string(&fmt)?,
            self.lua.create_string(&data)?,
        );
        self.run_packed = (fmt, data);
        let tables = self.lua.create_sequence_from(tables)?;
        let results = self.lua.create_table_with_capacity(jobs.len(), 0)?;
        let r = &self.cfg.rrules[rule as usize];
        let (func, origin, text) = (r.func.clone(), r.origin, r.text.clone());
        self.set_this(true)?;
        self.read_only.enter(text.clone());
        let called = run_loop.call::<(usize, u8)>((
            func,
            packed.0,
            packed.1,
            tables,
            jobs.len(),
            budget.min(i64::MAX as u64) as i64,
            &results,
            more,
        ));
        self.read_only.leave();
        let (done, why) = called.map_err(|e| self.locate(e, origin))?;
        let what = super::host::SuccessorOf(&text);
        // The jobs whose results are plain (symbols, flat arrays of symbols, not applied).
        let plain = match why {
            0 | 1 => done,
            _ => done - 1,
        };
        let mut next = first;
        for (k, &m) in jobs[..plain].iter().enumerate() {
            out.extend_from(src, next..m);
            match results.raw_get::<Value>(k + 1)? {
                Value::Boolean(false) => out.push_from(src, m),
                v => self.push_value(&v, out, origin, &what, 0)?,
            }
            next = m + 1;
        }
        match why {
            2 => {
                let m = jobs[done - 1];
                out.extend_from(src, next..m);
                Ok(RunEnd {
                    next: m,
                    fell_through: true,
                })
            }
            3 => {
                let m = jobs[done - 1];
                out.extend_from(src, next..m);
                let v = results.raw_get::<Value>(done)?;
                self.push_value(&v, out, origin, &what, 0)?;
                Ok(RunEnd {
                    next: m + 1,
                    fell_through: false,
                })
            }
            _ => Ok(RunEnd {
                next,
                fell_through: false,
            }),
        }
    }

    /// A Lua error of a rule call: a limit the count hook raised in this plugin's own
    /// chunks (the loop, the callers) names the rule's line instead.
    pub(crate) fn locate(&self, e: mlua::Error, origin: u32) -> HostError {
        let located = to_engine_error(self.lua, e.clone());
        match located.location() {
            Some(l) if l.file == CHUNK => {
                let at = self
                    .cfg
                    .locations
                    .get(origin as usize)
                    .cloned()
                    .unwrap_or_default();
                HostError::Engine(located.at(at))
            }
            _ => HostError::Lua(e),
        }
    }
}

/// Appends a number to a `string.pack` format and its data: `j` for an integer, `n` for a
/// float.
fn pack(fmt: &mut Vec<u8>, data: &mut Vec<u8>, v: Value) {
    match v {
        Value::Integer(i) => {
            fmt.push(b'j');
            data.extend_from_slice(&i.to_le_bytes());
        }
        Value::Number(x) => {
            fmt.push(b'n');
            data.extend_from_slice(&x.to_le_bytes());
        }
        _ => {}
    }
}
