//! Algorithms: the unit of generation, run step by step.

use crate::clock::Instant;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::geometry::{Model, Skeleton};
use crate::{Budget, Error, Location, Result};

/// What a step reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// More steps would change the result.
    Continue,
    /// The algorithm has reached its end; further steps are not taken.
    Done,
}

/// What every call of an [`Algorithm`] can read: the run's seed, step override and limits.
#[derive(Clone, Debug)]
pub struct RunContext {
    /// The run's seed (`--seed`).
    pub seed: u64,
    /// `--steps`: the number of steps asked for, overriding the algorithm's own count
    /// (an L-system's `iterations`, a growth's `steps`) when set.
    pub steps: Option<u32>,
    /// When the run must stop (`--time-limit`); long Rust loops check it with
    /// [`RunContext::check_deadline`].
    pub deadline: Option<Instant>,
    /// The module-count cap for rewriting systems.
    pub max_modules: usize,
    /// Set by another thread to stop the run early (the preview superseding a run).
    pub cancel: Option<Arc<AtomicBool>>,
    /// The run's memory budget (`--memory-limit`), one for the whole run and every thread
    /// of it: check a size before allocating a buffer that grows with the input
    /// ([`Budget::check`]) and charge what is kept ([`Budget::charge`]). Its stop flag
    /// ([`Budget::stop`]) ends the parts of a run that fail together, at their next
    /// [`RunContext::check_deadline`].
    pub budget: Budget,
}

impl Default for RunContext {
    fn default() -> Self {
        RunContext {
            seed: 1,
            steps: None,
            deadline: None,
            max_modules: 10_000_000,
            cancel: None,
            budget: Budget::default(),
        }
    }
}

impl RunContext {
    /// A context with no deadline and no memory limit, for work outside a run (a host
    /// laying out a forest itself, tests).
    #[must_use]
    pub fn unlimited() -> RunContext {
        RunContext {
            budget: Budget::new(usize::MAX),
            ..RunContext::default()
        }
    }

    /// An error if the deadline has passed or the run was cancelled (or stopped by its
    /// budget's flag, [`Budget::stop`]), pointing at `location`. Cheap: call it in every
    /// loop whose length a script decides.
    pub fn check_deadline(&self, location: &Location) -> Result<()> {
        if self
            .cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
            || self.budget.stopped()
        {
            return Err(Error::Cancelled {
                location: location.clone(),
            });
        }
        match self.deadline {
            Some(d) if Instant::now() >= d => Err(Error::TimeLimit {
                location: location.clone(),
            }),
            _ => Ok(()),
        }
    }
}

/// A step-wise generator: an L-system, space colonization, a growth model, a forest.
///
/// # Lifecycle
/// 1. [`init`](Algorithm::init) is called once, before any step.
/// 2. [`step`](Algorithm::step) is called until it returns [`Step::Done`], or until the caller
///    has taken the number of steps it wanted (the preview's scrubber, `--steps`).
/// 3. [`finish`](Algorithm::finish) builds the model of the current state. It may be called
///    after any step, and it leaves the state intact: a caller may step again and call
///    `finish` again (watching growth).
///
/// After an error from any method the algorithm is in an unspecified state and must not be
/// called again.
pub trait Algorithm {
    /// A short name for progress messages.
    fn name(&self) -> &str {
        "algorithm"
    }

    /// Prepares the first step.
    fn init(&mut self, ctx: &RunContext) -> Result<()>;

    /// Takes one step of growth.
    fn step(&mut self, ctx: &RunContext) -> Result<Step>;

    /// Builds the model of the current state.
    fn finish(&mut self, ctx: &RunContext) -> Result<Model>;

    /// The number of steps the algorithm expects to take, if known (for progress bars).
    fn planned_steps(&self) -> Option<u32> {
        None
    }

    /// The branch skeleton of the current state, for generators that grow one (space
    /// colonization, growth); `None` for the others, whose skeleton (if any) is then read
    /// from the bark meshes of [`finish`](Algorithm::finish)'s model.
    fn skeleton(&self) -> Option<Skeleton> {
        None
    }

    /// A copy of the current state that steps and finishes on its own, without the session
    /// that made it (so nothing of a Lua state in it), for callers that go back to an earlier
    /// step: the preview's scrubber keeps copies every few steps and re-runs from the
    /// nearest one instead of re-running the script. A copy taken after a step that returned
    /// [`Step::Continue`], or [`Step::Done`] on reaching `ctx.steps`, must go on exactly as
    /// the original would under any larger `ctx.steps` (a step may read `ctx.steps` only to
    /// decide when it is done, and a state stopped there is not finished). `None`, the
    /// default, when the state cannot be copied.
    fn snapshot(&self) -> Option<Box<dyn Algorithm>> {
        None
    }

    /// The algorithm as [`Any`](std::any::Any), for a host that asks what a script returned
    /// (a forest, for its tiles) and calls the concrete type's own methods:
    /// `algorithm.as_any_mut()?.downcast_mut::<T>()`. `None`, the default, for algorithms
    /// that offer nothing beyond this trait.
    fn as_any_mut(&mut self) -> Option<&mut dyn std::any::Any> {
        None
    }
}

/// An algorithm that is already done: it returns a fixed model.
#[derive(Debug, Clone)]
pub struct Finished(pub Model);

impl Algorithm for Finished {
    fn name(&self) -> &str {
        "model"
    }
    fn init(&mut self, _: &RunContext) -> Result<()> {
        Ok(())
    }
    fn step(&mut self, _: &RunContext) -> Result<Step> {
        Ok(Step::Done)
    }
    fn finish(&mut self, _: &RunContext) -> Result<Model> {
        Ok(self.0.clone())
    }
    fn planned_steps(&self) -> Option<u32> {
        Some(0)
    }
}

/// Runs an algorithm: `init`, then steps until done or until `ctx.steps` steps were taken,
/// then `finish`, and removes the model's degenerate and repeated triangles
/// ([`Model::remove_unusable_triangles`]). `progress` is called after every step with the
/// number of steps taken.
pub fn run(
    algorithm: &mut dyn Algorithm,
    ctx: &RunContext,
    progress: &mut dyn FnMut(u32),
) -> Result<Model> {
    algorithm.init(ctx)?;
    let mut taken = 0u32;
    while ctx.steps.is_none_or(|n| taken < n) {
        let step = algorithm.step(ctx)?;
        taken += 1;
        progress(taken);
        if step == Step::Done {
            break;
        }
    }
    let mut model = algorithm.finish(ctx)?;
    let cleaning = Instant::now();
    model.remove_unusable_triangles();
    // Part of making the meshes: `--stats` counts it in the meshing phase.
    model
        .stats
        .add_phase("meshing", cleaning.elapsed().as_secs_f64());
    Ok(model)
}

/// Grows an algorithm without building its model: `init`, then steps until done or until
/// `ctx.steps` steps were taken; returns the number of steps taken.
pub fn grow(algorithm: &mut dyn Algorithm, ctx: &RunContext) -> Result<u32> {
    algorithm.init(ctx)?;
    let mut taken = 0u32;
    while ctx.steps.is_none_or(|n| taken < n) {
        let step = algorithm.step(ctx)?;
        taken += 1;
        if step == Step::Done {
            break;
        }
    }
    Ok(taken)
}

/// Runs several algorithms interleaved, one step of each in turn, until all are done (or
/// have taken `ctx.steps` steps); returns their models in order.
pub fn interleave(algorithms: &mut [&mut dyn Algorithm], ctx: &RunContext) -> Result<Vec<Model>> {
    for a in algorithms.iter_mut() {
        a.init(ctx)?;
    }
    let mut done = vec![false; algorithms.len()];
    let mut taken = 0u32;
    while done.iter().any(|d| !d) && ctx.steps.is_none_or(|n| taken < n) {
        for (a, d) in algorithms.iter_mut().zip(done.iter_mut()) {
            if !*d && a.step(ctx)? == Step::Done {
                *d = true;
            }
        }
        taken += 1;
    }
    algorithms.iter_mut().map(|a| a.finish(ctx)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Counts its steps and stops after `limit`.
    struct Counter {
        steps: u32,
        limit: u32,
    }

    impl Algorithm for Counter {
        fn init(&mut self, _: &RunContext) -> Result<()> {
            self.steps = 0;
            Ok(())
        }
        fn step(&mut self, _: &RunContext) -> Result<Step> {
            self.steps += 1;
            Ok(if self.steps >= self.limit {
                Step::Done
            } else {
                Step::Continue
            })
        }
        fn finish(&mut self, _: &RunContext) -> Result<Model> {
            let mut m = Model::new();
            m.stats.nodes = self.steps as u64;
            Ok(m)
        }
    }

    #[test]
    fn run_goes_to_the_end_or_to_the_step_count() {
        let mut c = Counter { steps: 0, limit: 5 };
        let mut seen = Vec::new();
        let m = run(&mut c, &RunContext::default(), &mut |s| seen.push(s)).expect("runs");
        assert_eq!(m.stats.nodes, 5);
        assert_eq!(seen, vec![1, 2, 3, 4, 5]);
        let ctx = RunContext {
            steps: Some(2),
            ..RunContext::default()
        };
        assert_eq!(run(&mut c, &ctx, &mut |_| {}).expect("runs").stats.nodes, 2);
    }

    #[test]
    fn interleave_steps_each_in_turn() {
        let mut a = Counter { steps: 0, limit: 2 };
        let mut b = Counter { steps: 0, limit: 4 };
        let models = interleave(&mut [&mut a, &mut b], &RunContext::default()).expect("runs");
        assert_eq!(models[0].stats.nodes, 2);
        assert_eq!(models[1].stats.nodes, 4);
    }

    #[test]
    fn deadline_in_the_past_is_an_error() {
        let ctx = RunContext {
            deadline: Some(Instant::now()),
            ..RunContext::default()
        };
        let err = ctx
            .check_deadline(&Location::new("a.lua", 3))
            .expect_err("expired");
        assert!(matches!(err, Error::TimeLimit { .. }), "{err:?}");
        assert_eq!(
            err.to_string(),
            "a.lua:3: time limit exceeded (see --time-limit)"
        );
    }
}
