//! Interpretation: each module of the derived string is handed to the IRules that match
//! it (leftmost-first left contexts, bracket-aware), then to the default interpreters of the
//! instance (a turtle).

use mlua::{MultiValue, Value};
use pge_engine::Location;

use super::config::LuaIRule;
use super::host::{HostError, LuaHost, positional_numbers, truthy};
use crate::{ModuleString, Sym};

impl LuaHost<'_> {
    /// Interprets module `i` of `s`.
    pub(crate) fn interpret_module(&mut self, s: &ModuleString, i: usize) -> Result<(), HostError> {
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
                    let found = self.prepared.match_left_context(
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

    /// Interprets every module of `s` (checking the deadline now and then).
    pub(crate) fn interpret_all(
        &mut self,
        s: &ModuleString,
        location: &Location,
    ) -> Result<(), HostError> {
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
