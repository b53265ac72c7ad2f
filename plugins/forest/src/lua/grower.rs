//! How the Lua side grows variants: species scripts in sessions of their own, made by the
//! engine that made the forest's session ([`SessionGrower`]), and species functions in the
//! forest's own session.

use std::path::Path;

use mlua::{Function, Table, Value};
use pge_engine::algorithm::run;
use pge_engine::geometry::Model;
use pge_engine::lua::{algorithm_from, to_engine_error};
use pge_engine::{Engine, Error, Location, RunContext, SessionOptions};

use crate::{GrownVariant, ScriptSpecies, SpeciesGrower};

/// Grows each variant of a species script in a sandboxed session of its own, created by an
/// engine (the same plugins and sandbox as the forest's session), within the forest run's
/// limits: its deadline and its memory budget, which the variants grown in parallel share
/// (a variant that runs out of time fails with [`Error::TimeLimit`] at the species script's
/// line). Sessions are made on whichever worker thread grows the variant.
///
/// ```no_run
/// use std::sync::Arc;
/// use pge_forest::lua::SessionGrower;
/// use pge_forest::{ForestRun, ForestSpec};
///
/// let engine = pge_engine::Engine::builder().build()?;
/// let spec = ForestSpec::new([100.0, 100.0], 1, None)?;
/// let run = ForestRun::new(spec).grower(Arc::new(SessionGrower::new(engine)));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone)]
pub struct SessionGrower {
    engine: Engine,
}

impl SessionGrower {
    /// A grower whose sessions `engine` creates.
    #[must_use]
    pub fn new(engine: Engine) -> SessionGrower {
        SessionGrower { engine }
    }
}

impl SpeciesGrower for SessionGrower {
    fn grow(
        &self,
        species: &ScriptSpecies,
        seed: u64,
        ctx: &RunContext,
    ) -> pge_engine::Result<GrownVariant> {
        // The variant is part of the forest's run: its deadline and its memory budget.
        let session = self.engine.session(SessionOptions {
            seed,
            params: species.params.clone(),
            steps: None,
            cancel: ctx.cancel.clone(),
            deadline: ctx.deadline,
            budget: Some(ctx.budget.clone()),
        })?;
        let model = session
            .generate(Path::new(&species.path), &mut |_, _| {})?
            .model;
        Ok((model, session.loaded_files()))
    }
}

/// One variant of a species function: `f(params, seed)` in the forest's session, its value
/// run to the end as the forest's own script value would be (with `ctx`, whose seed is the
/// variant's). `location` (the `forest:scatter` call) is blamed when the value grows
/// nothing.
pub(super) fn grow_with_function(
    f: &Function,
    params: &Table,
    ctx: &RunContext,
    location: &Location,
) -> pge_engine::Result<Model> {
    let Some(lua) = f.weak_lua().try_upgrade() else {
        return Err(Error::script(location.clone(), "the Lua state is gone"));
    };
    let value: Value = f
        .call((params.clone(), ctx.seed))
        .map_err(|e| to_engine_error(&lua, e))?;
    let mut algorithm = algorithm_from(&lua, value, location)?;
    run(&mut *algorithm, ctx, &mut |_| {})
}
