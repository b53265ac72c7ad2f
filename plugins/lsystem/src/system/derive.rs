//! The derivation step: every module of a string rewritten by the first rule that applies.

use super::compile::{CKind, Dispatch, Tables};
use super::context::{match_left, match_right};
use super::host::Host;
use super::rule::RuleDef;
use crate::error::LsError;
use crate::module_string::ModuleString;
use crate::symbol::Sym;

/// Options of one derivation step.
#[derive(Clone, Copy, Debug)]
pub struct StepOptions {
    /// The step's number (1-based), for error messages.
    pub step: u32,
    /// The module cap.
    pub max_modules: usize,
    /// Call [`Host::interpret`] after each module's successor.
    pub stream: bool,
}

/// A compiled system's rules, ready to derive.
pub(super) struct Deriver<'a> {
    /// The rules as added (left sides, origins and texts for errors).
    pub(super) defs: &'a [RuleDef],
    /// The values of the numeric globals.
    pub(super) globals: &'a [f64],
    /// The compiled rules and dispatch tables.
    pub(super) tables: &'a Tables,
}

impl Deriver<'_> {
    /// One derivation step: rewrites `src` into `out` (cleared first).
    pub(super) fn step<H: Host>(
        &self,
        src: &ModuleString,
        out: &mut ModuleString,
        host: &mut H,
        opts: &StepOptions,
    ) -> Result<(), H::Error> {
        out.clear();
        let too_many = |count: u64| LsError::TooManyModules {
            step: opts.step,
            count,
            max: opts.max_modules,
        };
        if self.tables.all_plain && src.is_flat() && !opts.stream {
            // Fast path: count first (fail before allocating), then copy slices.
            let syms = src.raw_syms();
            let mut total = 0u64;
            for &s in syms {
                total += match self.tables.dispatch.get(s as usize) {
                    Some(Dispatch::Plain { len, .. }) => u64::from(*len),
                    _ => 1,
                };
            }
            if total > opts.max_modules as u64 {
                return Err(too_many(total).into());
            }
            out.reserve(total as usize);
            for chunk in syms.chunks(1 << 16) {
                host.check()?;
                for &s in chunk {
                    match self.tables.dispatch.get(s as usize) {
                        Some(Dispatch::Plain { start, len }) => out.extend_plain(
                            &self.tables.plain_pool[*start as usize..(*start + *len) as usize],
                        ),
                        _ => out.extend_plain(&[s]),
                    }
                }
            }
            return Ok(());
        }
        let matches = if self.tables.uses_context {
            src.bracket_matches()
        } else {
            Vec::new()
        };
        let mut matched: Vec<usize> = Vec::with_capacity(16);
        let mut gathered: Vec<f64> = Vec::with_capacity(16);
        let max = opts.max_modules;
        for i in 0..src.len() {
            if i & 0xFFFF == 0 {
                host.check()?;
            }
            let from = out.len();
            let s = src.sym(i);
            match self.tables.dispatch.get(s.index()) {
                Some(Dispatch::Plain { start, len }) => out.extend_plain(
                    &self.tables.plain_pool[*start as usize..(*start + *len) as usize],
                ),
                Some(Dispatch::Rules { start, len }) => {
                    let list = &self.tables.rule_lists[*start as usize..(*start + *len) as usize];
                    let applied = self.apply_rules(
                        list,
                        src,
                        &matches,
                        i,
                        out,
                        host,
                        &mut matched,
                        &mut gathered,
                    )?;
                    if !applied {
                        out.push_from(src, i);
                    }
                }
                _ => out.push_from(src, i),
            }
            if out.len() > max {
                return Err(too_many(out.len() as u64).into());
            }
            if opts.stream {
                host.interpret(out, from)?;
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn apply_rules<H: Host>(
        &self,
        list: &[u32],
        src: &ModuleString,
        matches: &[u32],
        i: usize,
        out: &mut ModuleString,
        host: &mut H,
        matched: &mut Vec<usize>,
        gathered: &mut Vec<f64>,
    ) -> Result<bool, H::Error> {
        for &r in list {
            let r = r as usize;
            let def = &self.defs[r];
            let lhs = &def.lhs;
            matched.clear();
            if !lhs.left.is_empty()
                && !match_left(
                    &self.tables.ignored,
                    lhs.left.iter().map(|p| p.sym),
                    src,
                    matches,
                    i,
                    matched,
                )
            {
                continue;
            }
            matched.push(i);
            if !lhs.right.is_empty()
                && !match_right(&self.tables.ignored, &lhs.right, src, matches, i, matched)
            {
                continue;
            }
            match &self.tables.rules[r].kind {
                CKind::External(id) => {
                    if host.apply(*id, matched, src, out)? {
                        return Ok(true);
                    }
                }
                CKind::Classic {
                    condition,
                    successor,
                    choices,
                } => {
                    let params: &[f64] = if lhs.left.is_empty() && lhs.right.is_empty() {
                        match lhs.pred.arity {
                            None => &[],
                            Some(k) => {
                                self.check_arity(def, src, i, k)?;
                                src.params(i)
                            }
                        }
                    } else {
                        gathered.clear();
                        let items = lhs.left.iter().chain(std::iter::once(&lhs.pred)).chain(
                            lhs.right
                                .iter()
                                .filter(|p| p.sym != Sym::PUSH && p.sym != Sym::POP),
                        );
                        for (p, &m) in items.zip(matched.iter()) {
                            if let Some(k) = p.arity {
                                self.check_arity(def, src, m, k)?;
                                gathered.extend_from_slice(src.params(m));
                            }
                        }
                        gathered
                    };
                    let globals = self.globals;
                    if let Some(c) = condition
                        && c.eval(params, globals, &mut || host.random()) == 0.0
                    {
                        continue;
                    }
                    let (succ, def) = match choices {
                        Some(choices) => {
                            let x = host.random();
                            let pick = choices
                                .iter()
                                .find(|(cum, _)| x < *cum)
                                .map_or(choices[choices.len() - 1].1, |c| c.1);
                            match &self.tables.rules[pick].kind {
                                CKind::Classic { successor, .. } => (successor, &self.defs[pick]),
                                CKind::External(_) => (successor, def),
                            }
                        }
                        None => (successor, def),
                    };
                    for item in succ.iter() {
                        if item.args.is_empty() {
                            out.push(item.sym, &[]);
                            continue;
                        }
                        out.begin(item.sym);
                        for a in item.args.iter() {
                            let v = a.eval(params, globals, &mut || host.random());
                            if !v.is_finite() {
                                return Err(LsError::Rule {
                                    origin: def.origin,
                                    rule: def.text.clone(),
                                    message: format!(
                                        "a parameter of the successor evaluated to {v}"
                                    ),
                                }
                                .into());
                            }
                            out.push_param(v);
                        }
                        out.end();
                    }
                    return Ok(true);
                }
            }
        }
        Ok(false)
    }

    #[cold]
    fn arity_error(&self, def: &RuleDef, src: &ModuleString, m: usize, k: u16) -> LsError {
        let message = if src.external(m).is_some() {
            format!(
                "a classic production cannot read the non-numeric parameters of module #{} ({})",
                m + 1,
                def.text
                    .split(['<', '>', ':', '-'])
                    .next()
                    .unwrap_or("")
                    .trim()
            )
        } else {
            format!(
                "expects {k} parameter{} but module #{} has {}",
                if k == 1 { "" } else { "s" },
                m + 1,
                src.params(m).len()
            )
        };
        LsError::Rule {
            origin: def.origin,
            rule: def.text.clone(),
            message,
        }
    }

    #[inline]
    fn check_arity(
        &self,
        def: &RuleDef,
        src: &ModuleString,
        m: usize,
        k: u16,
    ) -> Result<(), LsError> {
        if src.external(m).is_some() || src.params(m).len() != k as usize {
            return Err(self.arity_error(def, src, m, k));
        }
        Ok(())
    }
}
