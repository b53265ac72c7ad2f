//! How the Lua side grows variants: species scripts in sessions of their own, made by the
//! engine that made the forest's session ([`SessionGrower`]), and species functions in the
//! forest's own session.

use std::cell::Cell;
use std::path::{Path, PathBuf};

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
    /// The species scripts whose sessions this grower's forest runs inside, outermost first.
    within: Vec<PathBuf>,
    /// The folder the forest's session writes into: its species' sessions write there too
    /// (`img:save` of a library species goes beside the output, not into the library).
    output: Option<PathBuf>,
}

/// How deep forests may grow inside species (a forest whose species is a forest...): past
/// it, a species is taken for a forest that grows itself.
pub const NESTING_LIMIT: usize = 8;

/// What a species script's session records for the forests it makes: the scripts it runs
/// inside (the main script first), itself last.
#[derive(Clone)]
struct Within(Vec<PathBuf>);

impl SessionGrower {
    /// A grower whose sessions `engine` creates.
    #[must_use]
    pub fn new(engine: Engine) -> SessionGrower {
        SessionGrower {
            engine,
            within: Vec::new(),
            output: None,
        }
    }

    /// A grower for the forests of the session of `lua`: inside the species scripts that
    /// session grows for, or its main script for a session the host made.
    pub(super) fn for_session(engine: Engine, lua: &mlua::Lua) -> SessionGrower {
        let within = match lua.app_data_ref::<Within>() {
            Some(w) => w.0.clone(),
            None => pge_engine::lua::main_script(lua).into_iter().collect(),
        };
        SessionGrower {
            engine,
            within,
            output: pge_engine::lua::write_folder(lua),
        }
    }
}

impl SpeciesGrower for SessionGrower {
    fn grow(
        &self,
        species: &ScriptSpecies,
        seed: u64,
        ctx: &RunContext,
    ) -> pge_engine::Result<GrownVariant> {
        let path = std::fs::canonicalize(&species.path).unwrap_or_else(|_| (&species.path).into());
        if self.within.contains(&path) || self.within.len() >= NESTING_LIMIT {
            let message = if self.within.contains(&path) {
                "it grows the forest it is part of (a forest cannot be its own species)".into()
            } else {
                format!("forests nested in species deeper than the limit of {NESTING_LIMIT}")
            };
            return Err(Error::script(
                Location {
                    file: species.path.clone(),
                    line: None,
                },
                message,
            ));
        }
        // The variant is part of the forest's run: its deadline and its memory budget.
        let session = self.engine.session(SessionOptions {
            seed,
            params: species.params.clone(),
            steps: None,
            cancel: ctx.cancel.clone(),
            deadline: ctx.deadline,
            budget: Some(ctx.budget.clone()),
        })?;
        if let Some(output) = &self.output {
            session.set_output_folder(output)?;
        }
        let mut within = self.within.clone();
        within.push(path);
        session.lua().set_app_data(Within(within));
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
    let depth = FUNCTION_DEPTH.get();
    if depth >= NESTING_LIMIT {
        return Err(Error::script(
            location.clone(),
            format!(
                "forests nested in species functions deeper than the limit of {NESTING_LIMIT} \
                 (a species function that returns its own forest?)"
            ),
        ));
    }
    FUNCTION_DEPTH.set(depth + 1);
    let grown = (|| {
        let value: Value = f
            .call((params.clone(), ctx.seed))
            .map_err(|e| to_engine_error(&lua, e))?;
        let mut algorithm = algorithm_from(&lua, value, location)?;
        run(&mut *algorithm, ctx, &mut |_| {})
    })();
    FUNCTION_DEPTH.set(depth);
    grown
}

thread_local! {
    /// How many species functions are growing on this thread, one inside another (a Lua
    /// state and the functions it calls stay on one thread).
    static FUNCTION_DEPTH: Cell<usize> = const { Cell::new(0) };
}

#[cfg(test)]
mod tests {
    use pge_engine::clock::Instant;

    use pge_engine::{Budget, Engine, Error, Location, RunContext};

    use super::*;

    /// A species script `source` in a folder of its own.
    fn species(source: &str) -> (tempfile::TempDir, ScriptSpecies) {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("species.lua");
        std::fs::write(&path, source).expect("script");
        let species = ScriptSpecies::new(path.to_string_lossy().to_string(), &[]);
        (dir, species)
    }

    fn grower() -> SessionGrower {
        // No time limit of the engine's own: only the run's deadline can stop a variant.
        let engine = Engine::builder().time_limit(None).build().expect("engine");
        SessionGrower::new(engine)
    }

    #[test]
    fn a_variant_keeps_to_the_runs_deadline() {
        let (_dir, species) = species(
            "for i = 1, 1e6 do end\nreturn pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, \
             indices = {0,1,2} }",
        );
        let ctx = RunContext::default();
        grower()
            .grow(&species, 1, &ctx)
            .expect("grows without a deadline");
        let passed = RunContext {
            deadline: Some(Instant::now()),
            ..RunContext::default()
        };
        let e = grower()
            .grow(&species, 1, &passed)
            .expect_err("the run's time is up");
        assert!(matches!(e, Error::TimeLimit { .. }), "{e:?}");
    }

    #[test]
    fn a_variant_charges_the_runs_memory_budget() {
        let (_dir, species) = species(
            "local t = {}\nfor i = 1, 200000 do t[i] = i end\n\
             return pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }",
        );
        // The run's budget: 16 MiB, of which the rest of the run holds all but 2.
        let budget = Budget::new(16 << 20);
        let held = budget
            .charge(14 << 20, &Location::new("forest.lua", 1), String::new)
            .expect("fits");
        let ctx = RunContext {
            budget: budget.clone(),
            ..RunContext::default()
        };
        let e = grower()
            .grow(&species, 1, &ctx)
            .expect_err("past the budget");
        assert!(matches!(e, Error::MemoryLimit { .. }), "{e:?}");
        drop(held);
        grower()
            .grow(&species, 1, &ctx)
            .expect("fits once the rest is given back");
        assert_eq!(
            budget.used(),
            0,
            "the variant's session gave its memory back"
        );
    }
}
