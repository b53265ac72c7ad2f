//! Last derivation steps left to be streamed: what they need to be derived again, piece by
//! piece, each time the string is read ([`LastStep`]), and their host ([`StreamHost`]).
//! The algorithm counts them ([`super::algorithm`]); a derivation writes them
//! ([`super::derive`]).

use pge_engine::random::uniform;
use pge_engine::{Location, RunContext};
use rand_mt::Mt;

use super::host::HostError;
use crate::{DeriveOptions, Host, LsError, ModuleString, Prepared};

/// The last derivation steps, left to be streamed: derived anew, piece by piece, each time
/// the string is read, and never kept whole.
#[derive(Clone, Debug)]
pub(crate) struct LastStep {
    /// The rules.
    pub(crate) prepared: Prepared,
    /// The instance's generator as the steps start.
    pub(crate) rng: Mt,
    /// The steps and the module cap.
    pub(crate) opts: DeriveOptions,
    /// The number of modules the steps make (counted once, checking every limit).
    pub(crate) len: u64,
}

/// The host of streamed last steps: the instance's generator and, while the steps are
/// counted, the run's deadline (its errors point at the location). No Lua takes part in such
/// steps. Writing derives the steps again without checking the deadline: the count took
/// about as long, within the limit, and a write stopped halfway would leave half an output.
pub(crate) struct StreamHost<'a> {
    pub(crate) rng: &'a mut Mt,
    pub(crate) limits: Option<(&'a RunContext, &'a Location)>,
}

impl Host for StreamHost<'_> {
    type Error = HostError;

    fn random(&mut self) -> f64 {
        uniform(self.rng)
    }

    fn check(&mut self) -> Result<(), HostError> {
        match self.limits {
            Some((ctx, location)) => ctx.check_deadline(location).map_err(HostError::Engine),
            None => Ok(()),
        }
    }

    fn apply(
        &mut self,
        rule: u32,
        _: &[usize],
        _: &ModuleString,
        _: &mut ModuleString,
    ) -> Result<bool, HostError> {
        Err(LsError::Syntax {
            text: format!("external rule {rule}"),
            message: "a streamed step runs no rule functions".into(),
        }
        .into())
    }
}
