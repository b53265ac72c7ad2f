//! What a derivation needs from outside the rules: randomness, limits, external rules.

use pge_engine::random::uniform;
use rand_mt::Mt;

use crate::error::LsError;
use crate::module_string::ModuleString;

/// What the derivation needs from its environment: randomness, limits, rules written in
/// another language (Lua functions) and the interpretation of new modules.
pub trait Host {
    /// The error type of the host; engine errors convert into it.
    type Error: From<LsError>;

    /// A uniform draw in `[0, 1)` from the instance's generator.
    fn random(&mut self) -> f64;

    /// Called every 65 536 modules: an error stops the step (time limit, cancellation).
    fn check(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }

    /// Applies external rule `rule` (the id given to
    /// [`System::add_external`](crate::System::add_external)) to the modules
    /// `matched` of `src` (left context, predecessor, right context, brackets excluded),
    /// appending its successor to `out`. Returns false when the rule does not apply.
    fn apply(
        &mut self,
        rule: u32,
        matched: &[usize],
        src: &ModuleString,
        out: &mut ModuleString,
    ) -> Result<bool, Self::Error>;

    /// Interprets the modules `out[from..]` just produced (streaming interpretation).
    fn interpret(&mut self, out: &ModuleString, from: usize) -> Result<(), Self::Error> {
        let _ = (out, from);
        Ok(())
    }

    /// Whether runs of modules may be handed to [`Host::apply_run`] in this step: only when
    /// nothing can tell a run from the modules applied one by one (the host interprets
    /// nothing while the step runs, or its interpretation does nothing).
    fn runs(&self) -> bool {
        false
    }

    /// Rewrites a run of modules of `src` at once, appending to `out` what the step would
    /// append module by module. `jobs` are the modules, in increasing order, whose first rule
    /// is external rule `rule` (without context); the modules between two jobs have no
    /// rules and are copied. When `more` is true other rules follow `rule`: the run stops at
    /// the first job `rule` does not apply to, with [`RunEnd::fell_through`]. At most
    /// `budget` modules may be appended: the run stops after the module whose successor
    /// passes it, or before the copies that would (the caller reports the module cap).
    ///
    /// The default applies the jobs one by one with [`Host::apply`].
    fn apply_run(
        &mut self,
        rule: u32,
        jobs: &[usize],
        more: bool,
        src: &ModuleString,
        out: &mut ModuleString,
        budget: u64,
    ) -> Result<RunEnd, Self::Error> {
        let start = out.len();
        let mut next = jobs[0];
        for &m in jobs {
            if (out.len() - start + m - next) as u64 > budget {
                break;
            }
            out.extend_from(src, next..m);
            if !self.apply(rule, &[m], src, out)? {
                if more {
                    return Ok(RunEnd {
                        next: m,
                        fell_through: true,
                    });
                }
                out.push_from(src, m);
            }
            next = m + 1;
            if (out.len() - start) as u64 > budget {
                break;
            }
        }
        Ok(RunEnd {
            next,
            fell_through: false,
        })
    }
}

/// Where [`Host::apply_run`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RunEnd {
    /// The first module of `src` not rewritten yet.
    pub next: usize,
    /// Module `next` is a job the run's rule did not apply to: the rules after it are to be
    /// tried.
    pub fell_through: bool,
}

/// A host for systems without external rules: randomness from a Mersenne Twister.
pub struct NativeHost<'a> {
    /// The instance's generator.
    pub rng: &'a mut Mt,
}

impl Host for NativeHost<'_> {
    type Error = LsError;
    fn random(&mut self) -> f64 {
        uniform(self.rng)
    }
    fn apply(
        &mut self,
        rule: u32,
        _: &[usize],
        _: &ModuleString,
        _: &mut ModuleString,
    ) -> Result<bool, LsError> {
        Err(LsError::Syntax {
            text: format!("external rule {rule}"),
            message: "this host runs no external rules".into(),
        })
    }
}
