//! Counting: the number of modules steps make, without keeping them. A step is counted
//! with the errors it would raise (the same random draws, the same module cap); a system of
//! fixed successors is counted a symbol at a time across all its steps.

use super::compile::CKind;
use super::derive::{Deriver, Scratch, StepOptions};
use super::dispatch::Dispatch;
use super::host::Host;
use crate::error::LsError;
use crate::module_string::ModuleString;

impl Deriver<'_> {
    /// The number of modules the steps `steps` of a system of fixed strings make of `src`
    /// (see [`Deriver::plain_fast_path`]), counted a symbol at a time: after each step, how
    /// many modules every symbol has become, from what its successor's symbols became the
    /// step before; no string is made. Fails as the steps taken one after the other fail:
    /// at the first step past the module cap, with that step's whole count.
    pub(super) fn plain_counts<H: Host>(
        &self,
        src: &ModuleString,
        steps: &[StepOptions],
        host: &mut H,
    ) -> Result<u64, H::Error> {
        let t = self.tables;
        let n = t.dispatch.len();
        // How many modules of `src` have each symbol; symbols interned after the tables were
        // built have no rules (copied).
        let mut histogram = vec![0u64; n];
        let mut copied = 0u64;
        for &s in src.raw_syms() {
            match histogram.get_mut(s as usize) {
                Some(h) => *h += 1,
                None => copied += 1,
            }
        }
        let mut became = vec![1u64; n];
        let mut next = vec![0u64; n];
        let mut total = src.len() as u64;
        for opts in steps {
            host.check()?;
            for (s, slot) in next.iter_mut().enumerate() {
                *slot = match t.dispatch[s] {
                    Dispatch::Plain { start, len } => t.plain_pool
                        [start as usize..(start + len) as usize]
                        .iter()
                        .fold(0u64, |acc, &c| {
                            acc.saturating_add(became.get(c as usize).copied().unwrap_or(1))
                        }),
                    _ => became[s],
                };
            }
            std::mem::swap(&mut became, &mut next);
            total = histogram.iter().zip(&became).fold(copied, |acc, (&h, &b)| {
                acc.saturating_add(h.saturating_mul(b))
            });
            if total > opts.max_modules as u64 {
                return Err(self.too_many(opts, total).into());
            }
        }
        Ok(total)
    }

    /// The number of modules one step makes of `src`, without keeping them: runs of modules
    /// without rules are counted, not copied, and the successors of rules are written to a
    /// small scratch string only, their conditions and parameters evaluated in order as
    /// [`Deriver::step`] evaluates them (the same random draws, the same errors, the same
    /// module cap).
    pub(super) fn count<H: Host>(
        &self,
        src: &ModuleString,
        host: &mut H,
        opts: &StepOptions,
    ) -> Result<u64, H::Error> {
        let matches = self.bracket_matches(src);
        let mut scratch = Scratch::default();
        let mut successors = ModuleString::new();
        self.count_after(src, &matches, 0, host, opts, &mut scratch, &mut successors)
    }

    /// [`Deriver::count`] of the whole of `src`, a piece of a step of which `before` modules
    /// were produced earlier (for the module cap); `matches` as [`Deriver::context_table`]
    /// gives them, `scratch` and `successors` reused buffers. Returns the modules made of
    /// `src`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn count_after<H: Host>(
        &self,
        src: &ModuleString,
        matches: &[u32],
        before: u64,
        host: &mut H,
        opts: &StepOptions,
        scratch: &mut Scratch,
        successors: &mut ModuleString,
    ) -> Result<u64, H::Error> {
        let max = (opts.max_modules as u64).saturating_sub(before);
        let mut total = 0u64;
        let n = src.len();
        let mut i = 0;
        let mut next_check = 0;
        while i < n {
            if i >= next_check {
                host.check()?;
                next_check = (i | 0xFFFF) + 1;
            }
            let mut bulk = false;
            match self.tables.dispatch.get(src.sym(i).index()) {
                Some(Dispatch::Plain { len, .. }) => {
                    total += u64::from(*len);
                    i += 1;
                }
                Some(Dispatch::Direct { rule }) => {
                    total += self.count_direct(*rule as usize, src, i, host)?;
                    i += 1;
                }
                Some(Dispatch::Rules { start, len }) => {
                    if successors.len() > 4096 {
                        successors.clear();
                    }
                    let mark = successors.len();
                    let list = &self.tables.rule_lists[*start as usize..(*start + *len) as usize];
                    let applied = self.apply_rules(
                        list,
                        src,
                        matches,
                        i,
                        successors,
                        host,
                        &mut scratch.matched,
                        &mut scratch.gathered,
                    )?;
                    total += if applied {
                        (successors.len() - mark) as u64
                    } else {
                        1
                    };
                    i += 1;
                }
                _ => {
                    let mut j = i + 1;
                    let stop = n.min(next_check);
                    while j < stop
                        && matches!(
                            self.tables.dispatch.get(src.sym(j).index()),
                            None | Some(Dispatch::Copy)
                        )
                    {
                        j += 1;
                    }
                    total += (j - i) as u64;
                    bulk = true;
                    i = j;
                }
            }
            if total > max {
                // A run stops where a module-by-module copy would have.
                let count = if bulk { total.min(max + 1) } else { total };
                return Err(self.too_many(opts, before + count).into());
            }
        }
        Ok(total)
    }

    /// The number of modules one step of a plain system makes of `src` (see
    /// [`Deriver::plain_fast_path`]), failing over the module cap.
    pub(super) fn plain_count(
        &self,
        src: &ModuleString,
        opts: &StepOptions,
    ) -> Result<u64, LsError> {
        let mut total = 0u64;
        for &s in src.raw_syms() {
            total += match self.tables.dispatch.get(s as usize) {
                Some(Dispatch::Plain { len, .. }) => u64::from(*len),
                _ => 1,
            };
        }
        if total > opts.max_modules as u64 {
            return Err(self.too_many(opts, total));
        }
        Ok(total)
    }

    /// The number of modules [`Deriver::apply_direct`] would append, its parameters evaluated
    /// (the same random draws and errors) but not kept.
    #[inline]
    fn count_direct<H: Host>(
        &self,
        r: usize,
        src: &ModuleString,
        i: usize,
        host: &mut H,
    ) -> Result<u64, H::Error> {
        let CKind::Classic {
            condition,
            successor,
            ..
        } = &self.tables.rules[r].kind
        else {
            return Ok(1);
        };
        let Some(params) = self.direct_params(r, *condition, src, i, host)? else {
            return Ok(1);
        };
        for a in &self.args[successor.arg_range()] {
            let v = a.eval(params, self.globals, &mut || host.random());
            if !v.is_finite() {
                return Err(self.not_finite(r, v).into());
            }
        }
        Ok(successor.syms.len() as u64)
    }
}
