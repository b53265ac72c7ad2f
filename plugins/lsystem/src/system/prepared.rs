//! A system's rules compiled for derivation, and the one entry point that derives: it picks
//! how to take the steps (one after the other, depth first piece by piece, or counted a
//! symbol at a time) from the rules and from what the caller wants of the result.

use super::compile::Tables;
use super::derive::{Deriver, StepOptions};
use super::host::Host;
use super::rule::RuleDef;
use crate::module_string::ModuleString;
use crate::symbol::Sym;

/// Modules of the string before the last step rewritten per piece handed to
/// [`Output::Pieces`] when the steps are taken one after the other.
const PIECE: usize = 1 << 14;

/// Which steps [`Prepared::derive`] takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeriveOptions {
    /// The number of the first step taken (1-based), for error messages.
    pub first_step: u32,
    /// How many steps to take.
    pub steps: u32,
    /// The module cap, for every step.
    pub max_modules: usize,
    /// Call [`Host::interpret`] after each module's successor (streaming interpretation):
    /// the steps are then taken one after the other.
    pub interpret: bool,
}

impl DeriveOptions {
    /// `steps` steps from step `first_step` under the cap `max_modules`, not interpreted.
    #[must_use]
    pub fn new(first_step: u32, steps: u32, max_modules: usize) -> DeriveOptions {
        DeriveOptions {
            first_step,
            steps,
            max_modules,
            interpret: false,
        }
    }
}

/// What [`Prepared::derive`] does with the final string.
pub enum Output<'a, E> {
    /// Keeps it in the buffer (cleared first).
    Keep(&'a mut ModuleString),
    /// Only counts its modules: no step's string is kept when the rules let the steps be
    /// taken depth first (see [`Prepared::derives_in_pieces`]), otherwise only the strings
    /// before the last step.
    Count,
    /// Hands it to the sink in pieces, in order (never the whole string at once); the
    /// pieces handed before an error stay handed.
    Pieces(&'a mut dyn FnMut(&ModuleString) -> Result<(), E>),
}

/// A system's rules compiled by [`System::prepare`](crate::System::prepare): the only form
/// that derives, so a derivation never runs rules changed since they were compiled.
#[derive(Clone, Debug)]
pub struct Prepared {
    pub(super) defs: Box<[RuleDef]>,
    pub(super) global_values: Vec<f64>,
    pub(super) tables: Tables,
}

impl Prepared {
    /// Derives `opts.steps` steps of `src` into `output`; returns the number of modules of
    /// the final string. Whatever the output, the result and the errors (module caps,
    /// rules, the host's) are those of the steps taken one after the other; how they are
    /// taken is chosen here:
    /// - kept, or interpreted: one after the other, each step's output allocated once;
    /// - counted or in pieces, for rules without contexts, random draws or rule functions
    ///   ([`Prepared::derives_in_pieces`]): depth first, each piece of a step rewritten by
    ///   the next at once, so that no step's string is kept whole; a system of fixed
    ///   strings is counted a symbol at a time, without rewriting;
    /// - counted or in pieces otherwise: the steps before the last one after the other, the
    ///   last counted (modules without rules counted, not copied) or rewritten in pieces.
    pub fn derive<H: Host>(
        &self,
        src: &ModuleString,
        opts: &DeriveOptions,
        host: &mut H,
        output: Output<'_, H::Error>,
    ) -> Result<u64, H::Error> {
        let d = self.deriver();
        let steps: Vec<StepOptions> = (0..opts.steps)
            .map(|k| StepOptions {
                step: opts.first_step + k,
                max_modules: opts.max_modules,
                stream: opts.interpret,
            })
            .collect();
        let Some((last, before)) = steps.split_last() else {
            return match output {
                Output::Keep(out) => {
                    out.clear();
                    out.append(src);
                    Ok(src.len() as u64)
                }
                Output::Count => Ok(src.len() as u64),
                Output::Pieces(sink) => sink(src).map(|()| src.len() as u64),
            };
        };
        let in_pieces = !opts.interpret && self.derives_in_pieces();
        match output {
            Output::Keep(out) => {
                let mut between = ModuleString::new();
                let took = d.steps_before(src, before, &mut between, out, host)?;
                d.step(if took { &between } else { src }, out, host, last)?;
                Ok(out.len() as u64)
            }
            Output::Count if d.plain_fast_path(src, last) => d.plain_counts(src, &steps, host),
            Output::Count if in_pieces => d.depth_first(src, &steps, host, None, false),
            Output::Count => {
                let (mut between, mut spare) = (ModuleString::new(), ModuleString::new());
                let took = d.steps_before(src, before, &mut between, &mut spare, host)?;
                d.count_step(if took { &between } else { src }, host, last)
            }
            Output::Pieces(sink) if in_pieces => {
                // Fixed strings are counted first (the errors of the steps, exactly), then
                // rewritten without checks.
                let checked = d.plain_fast_path(src, last);
                if checked {
                    d.plain_counts(src, &steps, host)?;
                }
                d.depth_first(src, &steps, host, Some(sink), checked)
            }
            Output::Pieces(sink) => {
                let (mut between, mut spare) = (ModuleString::new(), ModuleString::new());
                let took = d.steps_before(src, before, &mut between, &mut spare, host)?;
                d.step_chunks(
                    if took { &between } else { src },
                    &mut spare,
                    host,
                    last,
                    PIECE,
                    sink,
                )
            }
        }
    }

    /// Whether [`Prepared::derive`] counts, or hands in pieces, a derivation not interpreted
    /// without keeping the string of any step (rules without contexts that draw no random
    /// numbers and call no rule functions); otherwise it keeps the strings before the last
    /// step. A caller that derives again what it counted (to write it) keeps the string
    /// before the steps it leaves to `derive`: the first string, or the one before the last
    /// step.
    #[must_use]
    pub fn derives_in_pieces(&self) -> bool {
        let t = &self.tables;
        !t.uses_context && !t.random && !t.growth.is_empty()
    }

    /// Matches a left context of symbols (leftmost first) for module `i` of `src`: the path
    /// toward the root, skipping whole branches, climbing out of enclosing ones and skipping
    /// ignored symbols. `matches` pairs brackets (see [`ModuleString::bracket_matches`]); only
    /// the entries of `]` before `i` are read. Pushes the matched indices, leftmost first.
    pub fn match_left_context(
        &self,
        left: &[Sym],
        src: &ModuleString,
        matches: &[u32],
        i: usize,
        out: &mut Vec<usize>,
    ) -> bool {
        super::context::match_left(
            &self.tables.ignored,
            left.iter().copied(),
            src,
            matches,
            i,
            out,
        )
    }

    fn deriver(&self) -> Deriver<'_> {
        Deriver {
            defs: &self.defs,
            globals: &self.global_values,
            tables: &self.tables,
            args: self
                .tables
                .exprs
                .iter()
                .map(|e| e.bind(&self.global_values))
                .collect(),
        }
    }
}

impl Deriver<'_> {
    /// Takes the steps `steps` of `src` one after the other, the result in `a` (`b` is
    /// scratch); false when there are no steps.
    fn steps_before<H: Host>(
        &self,
        src: &ModuleString,
        steps: &[StepOptions],
        a: &mut ModuleString,
        b: &mut ModuleString,
        host: &mut H,
    ) -> Result<bool, H::Error> {
        let Some((first, rest)) = steps.split_first() else {
            return Ok(false);
        };
        self.step(src, a, host, first)?;
        for opts in rest {
            self.step(a, b, host, opts)?;
            std::mem::swap(a, b);
        }
        Ok(true)
    }

    /// The number of modules one step makes of `src`, without keeping them: a system of
    /// fixed strings is counted without rewriting, the pass over fixed successors rewrites
    /// piece by piece, the general loop counts modules without rules instead of copying them.
    fn count_step<H: Host>(
        &self,
        src: &ModuleString,
        host: &mut H,
        opts: &StepOptions,
    ) -> Result<u64, H::Error> {
        if self.plain_fast_path(src, opts) {
            return Ok(self.plain_count(src, opts)?);
        }
        if self.fixed_pass(src, opts) {
            let mut buf = ModuleString::new();
            return self.step_chunks(src, &mut buf, host, opts, 1 << 16, &mut |_| Ok(()));
        }
        self.count(src, host, opts)
    }
}
