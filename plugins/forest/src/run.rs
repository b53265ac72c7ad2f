//! A forest run: the layout, then the variants, then the assembly, as three steps of an
//! [`Algorithm`] (the phases `--stats` reports), or at once with [`ForestRun::run`].

use pge_engine::clock::Instant;
use std::sync::Arc;

use pge_engine::geometry::Model;
use pge_engine::{Algorithm, Error, RunContext, Step};

use crate::grow::{ForestConfig, SpeciesGrower, grow_variants};
use crate::{
    ForestError, ForestSpec, Grown, Layout, Tile, VariantLod, VariantSharing, assemble_checked,
    check_budget, instance_leaves_within, layout_model, variant_lod, variants_model,
};

/// Bytes the assembly and the export hold per placed tree (its transform, its node or
/// instance attributes).
const PLACEMENT_BYTES: u64 = 96;

/// A forest being run: a [`ForestSpec`], the [`SpeciesGrower`] that grows its script
/// species and the run's [`ForestConfig`]. No Lua in it: a host builds the spec in Rust and
/// hands over its own grower.
///
/// It is an [`Algorithm`] of three steps (layout, variants, assembly) whose errors are the
/// engine's, placed at the lines that described the forest (a variant's limit stays the
/// limit it was); [`ForestRun::run`] runs it at once and keeps the [`ForestError`]. A host
/// that got an algorithm from a script asks it for the forest with [`ForestRun::of`].
///
/// ```
/// use pge_engine::RunContext;
/// use pge_engine::geometry::{Mesh, Model};
/// use pge_forest::{ForestRun, ForestSpec, Layer, Species};
/// use std::rc::Rc;
///
/// let mut spec = ForestSpec::new([60.0, 60.0], 7, None).unwrap();
/// let stick = Species::Function(Rc::new(|_seed, _ctx| {
///     let tri = Mesh::from_triangles(
///         vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
///         vec![0, 1, 2],
///     )?;
///     Ok(Model::from_mesh(tri))
/// }));
/// let mut layer = Layer::new("stick", 5.0);
/// layer.variants = pge_forest::Variants::Count(2);
/// spec.add_layer(layer, stick).unwrap();
/// let model = ForestRun::new(spec).run(&RunContext::default()).unwrap();
/// assert_eq!(model.groups.len(), 2);
/// ```
pub struct ForestRun {
    spec: ForestSpec,
    grower: Option<Arc<dyn SpeciesGrower>>,
    config: ForestConfig,
    layout: Option<Layout>,
    grown: Option<Vec<Grown>>,
    model: Option<Model>,
    /// Seconds of each step, reported as phases of the run.
    phases: Vec<(&'static str, f64)>,
}

impl ForestRun {
    /// The run of `spec`, not started, without a grower (a spec whose species are all
    /// functions needs none) or configuration.
    #[must_use]
    pub fn new(spec: ForestSpec) -> ForestRun {
        ForestRun {
            spec,
            grower: None,
            config: ForestConfig::default(),
            layout: None,
            grown: None,
            model: None,
            phases: Vec::new(),
        }
    }

    /// Script species are grown by `grower`.
    #[must_use]
    pub fn grower(mut self, grower: Arc<dyn SpeciesGrower>) -> ForestRun {
        self.grower = Some(grower);
        self
    }

    /// The run keeps its variants in a cache, or shares them, as `config` says.
    #[must_use]
    pub fn config(mut self, config: ForestConfig) -> ForestRun {
        self.config = config;
        self
    }

    /// The forest run by `algorithm`, if it is one (what a forest script returns).
    pub fn of(algorithm: &mut dyn Algorithm) -> Option<&mut ForestRun> {
        algorithm.as_any_mut()?.downcast_mut::<ForestRun>()
    }

    /// What is run.
    #[must_use]
    pub fn spec(&self) -> &ForestSpec {
        &self.spec
    }

    /// The tiles of the forest ([`ForestSpec::tiles`]), if the list fits in `budget`.
    pub fn tiles(&self, budget: &pge_engine::Budget) -> Result<Vec<Tile>, ForestError> {
        self.spec.tiles(budget)
    }

    /// Makes the run make tile `(i, j)` alone ([`ForestSpec::select_tile`]), from its start.
    pub fn select_tile(&mut self, i: usize, j: usize) -> Result<(), ForestError> {
        self.spec.select_tile(i, j)?;
        self.restart();
        Ok(())
    }

    fn restart(&mut self) {
        self.layout = None;
        self.grown = None;
        self.model = None;
        self.phases.clear();
    }

    fn sharing(&self) -> Option<VariantSharing> {
        self.config.sharing
    }

    /// Runs the forest to the end and returns its model, cleaned as
    /// [`pge_engine::algorithm::run`] cleans it.
    pub fn run(&mut self, ctx: &RunContext) -> Result<Model, ForestError> {
        self.restart();
        while self.step_forest(ctx)? == Step::Continue {}
        let mut model = self.model()?;
        model.remove_unusable_triangles();
        Ok(model)
    }

    /// Takes the next step (layout, variants or assembly), timed as a phase of the run.
    pub fn step_forest(&mut self, ctx: &RunContext) -> Result<Step, ForestError> {
        let t0 = Instant::now();
        let (name, step) = self.step_timed(ctx)?;
        self.phases.push((name, t0.elapsed().as_secs_f64()));
        Ok(step)
    }

    /// The model of the steps taken so far: the assembled forest after the last step (or
    /// the shared variants, with [`VariantSharing::Write`]), markers where the trees will
    /// stand after the layout.
    pub fn model(&self) -> Result<Model, ForestError> {
        let forest = self.spec.forest();
        let tile = self.spec.tile();
        let mut model = match (&self.model, &self.layout, &self.grown) {
            (Some(model), _, _) => model.clone(),
            (None, _, Some(grown)) if self.sharing() == Some(VariantSharing::Write) => {
                variants_model(forest, grown)
            }
            (None, Some(layout), Some(grown)) => {
                self.assembled(layout, grown, &RunContext::default())?
            }
            (None, Some(layout), None) => layout_model(forest, layout, tile),
            _ => layout_model(forest, &Layout::default(), tile),
        };
        for (name, seconds) in &self.phases {
            model.stats.add_phase(name, *seconds);
        }
        Ok(model)
    }

    /// The layout of the forest (or its tile), its empty layers' warnings placed at the lines
    /// that described them.
    pub fn layout(&self) -> Result<Layout, ForestError> {
        self.layout_within(&RunContext::unlimited())
    }

    /// [`ForestRun::layout`] within the run's limits ([`crate::Forest::layout_within`]).
    pub fn layout_within(&self, ctx: &RunContext) -> Result<Layout, ForestError> {
        let forest = self.spec.forest();
        let at = |layer: Option<usize>| match layer {
            Some(l) => self.spec.layer_origin(l),
            None => self.spec.origin(),
        };
        let mut layout = forest.layout_located(self.spec.tile(), ctx, &at)?;
        let empty = layout.counts.iter().enumerate().filter(|(_, c)| **c == 0);
        let located: Vec<String> = empty
            .zip(&layout.warnings)
            .map(|((l, _), w)| {
                format!(
                    "{}: warning: forest:scatter: {w}",
                    self.spec.layer_origin(l)
                )
            })
            .collect();
        layout.warnings = located;
        Ok(layout)
    }

    /// Grows the variants the trees of `layout` need (none for the layers that refer to
    /// shared variants), with the forest's levels of detail.
    pub fn grow(&self, layout: &Layout, ctx: &RunContext) -> Result<Vec<Grown>, ForestError> {
        grow_variants(
            &self.spec,
            layout,
            self.grower.as_deref(),
            &self.config,
            ctx,
        )
    }

    /// How many leaves each instance of `layout` draws for the forest's camera, `None`
    /// without one.
    /// A tile's budget is computed on the whole forest's layout, laid out within `ctx`'s
    /// limits ([`instance_leaves_within`]).
    pub fn budgeted_leaves(
        &self,
        layout: &Layout,
        grown: &[Grown],
        ctx: &RunContext,
    ) -> Result<Option<Vec<Option<u32>>>, ForestError> {
        let Some(camera) = &self.spec.lod.camera else {
            return Ok(None);
        };
        let at = |layer: Option<usize>| match layer {
            Some(l) => self.spec.layer_origin(l),
            None => self.spec.origin(),
        };
        instance_leaves_within(
            self.spec.forest(),
            layout,
            self.spec.tile(),
            &levels(grown),
            camera,
            ctx,
            &at,
        )
        .map(Some)
    }

    /// The forest's model: the layout's instances of the grown variants, with each
    /// instance's leaves when the forest has a camera.
    /// The run's deadline is checked as it goes ([`assemble_checked`]).
    fn assembled(
        &self,
        layout: &Layout,
        grown: &[Grown],
        ctx: &RunContext,
    ) -> Result<Model, ForestError> {
        let leaves = self.budgeted_leaves(layout, grown, ctx)?;
        let origin = self.spec.origin();
        assemble_checked(
            self.spec.forest(),
            layout,
            grown,
            self.spec.tile(),
            leaves.as_deref(),
            &mut || ctx.check_deadline(&origin).map_err(ForestError::Script),
        )
    }

    /// One step: layout, then variants, then assembly; returns the step's name.
    fn step_timed(&mut self, ctx: &RunContext) -> Result<(&'static str, Step), ForestError> {
        let writing = self.sharing() == Some(VariantSharing::Write);
        if self.layout.is_none() && writing {
            // Writing the shared variants: no trees to place.
            self.layout = Some(Layout::default());
            return Ok(("layout", Step::Continue));
        }
        let Some(layout) = &self.layout else {
            if let Some(camera) = &self.spec.lod.camera {
                check_budget(self.spec.forest(), camera)?;
                if self.sharing() == Some(VariantSharing::Refer) {
                    return Err(ForestError::CameraWithSharedVariants);
                }
            }
            // The terrain mesh the assembly will make is checked before anything runs.
            let forest = self.spec.forest();
            let grid = forest.terrain.grid(forest.tile);
            let (kx, kz) = forest.terrain.patch(&grid, self.spec.tile());
            forest
                .terrain
                .check_mesh(kx, kz, &ctx.budget, &self.spec.origin())?;
            self.layout = Some(self.layout_within(ctx)?);
            return Ok(("layout", Step::Continue));
        };
        let Some(grown) = &self.grown else {
            self.grown = Some(self.grow(layout, ctx)?);
            return Ok(("variants", Step::Continue));
        };
        if self.model.is_none() {
            let origin = self.spec.origin();
            ctx.check_deadline(&origin).map_err(ForestError::Script)?;
            let placed = layout.instances.len() as u64;
            ctx.budget
                .check(placed.saturating_mul(PLACEMENT_BYTES), &origin, || {
                    format!(
                        "the placements of {placed} trees need {} MiB",
                        (placed * PLACEMENT_BYTES).div_ceil(1 << 20)
                    )
                })
                .map_err(ForestError::Script)?;
            self.model = Some(if writing {
                variants_model(self.spec.forest(), grown)
            } else {
                self.assembled(layout, grown, ctx)?
            });
        }
        Ok(("assembly", Step::Done))
    }

    /// `e` as the engine's error, placed at the line that described the forest or the
    /// layer it is about: an engine error (a density function's, a species function's) as
    /// it was, a variant's limit as the limit it was, anything else a script error whose
    /// message names what failed.
    #[must_use]
    pub fn engine_error(&self, e: ForestError) -> Error {
        match e {
            ForestError::Script(e) => e,
            ForestError::Species { error, .. } if error.is_limit() => error,
            ForestError::Lod {
                error: pge_lod::LodError::Limit(error),
                ..
            } => *error,
            e @ ForestError::TooMany {
                layer: Some(layer), ..
            } => Error::script(self.spec.layer_origin(layer), e.to_string()),
            e @ ForestError::Species { layer, .. } => Error::script(
                self.spec.layer_origin(layer),
                format!("forest:scatter: {e}"),
            ),
            e @ (ForestError::Lod { .. }
            | ForestError::NoGrower { .. }
            | ForestError::CameraWithSharedVariants
            | ForestError::Option {
                option: "lod" | "lod.camera",
                ..
            }) => Error::script(self.spec.origin(), format!("pge.Forest: {e}")),
            other => Error::script(self.spec.origin(), other.to_string()),
        }
    }
}

/// The levels of every grown variant, by layer and variant.
#[must_use]
pub fn levels(grown: &[Grown]) -> Vec<Vec<Option<VariantLod>>> {
    grown
        .iter()
        .map(|g| g.variants.iter().map(variant_lod).collect())
        .collect()
}

impl Algorithm for ForestRun {
    fn name(&self) -> &str {
        "pge.Forest"
    }

    fn init(&mut self, _: &RunContext) -> pge_engine::Result<()> {
        self.layout = None;
        self.grown = None;
        self.model = None;
        Ok(())
    }

    fn step(&mut self, ctx: &RunContext) -> pge_engine::Result<Step> {
        self.step_forest(ctx).map_err(|e| self.engine_error(e))
    }

    fn finish(&mut self, _: &RunContext) -> pge_engine::Result<Model> {
        self.model().map_err(|e| self.engine_error(e))
    }

    fn planned_steps(&self) -> Option<u32> {
        Some(3)
    }

    fn as_any_mut(&mut self) -> Option<&mut dyn std::any::Any> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use glam::Vec3;
    use pge_engine::Location;
    use pge_engine::geometry::Mesh;

    use super::*;
    use crate::{Layer, ScriptSpecies, Species, Variants};

    fn stick() -> Model {
        let tri = Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]);
        Model::from_mesh(tri.expect("mesh"))
    }

    /// Two layers of two variants each, species `a.lua` and `b.lua`.
    fn spec() -> ForestSpec {
        let mut spec = ForestSpec::new([60.0, 60.0], 5, Some(30.0))
            .expect("spec")
            .described_at(Location::new("f.lua", 1));
        for (k, name) in ["a", "b"].into_iter().enumerate() {
            let mut layer = Layer::new(name, 6.0);
            layer.variants = Variants::Count(2);
            let species = Species::Script(ScriptSpecies::new(format!("{name}.lua"), &[]));
            spec.add_layer_at(layer, species, Location::new("f.lua", 2 + k as u32))
                .expect("layer");
        }
        spec
    }

    #[test]
    fn a_failing_variant_keeps_its_engine_error_and_is_placed_at_its_layer() {
        let limit = |species: &ScriptSpecies, _: u64, _: &RunContext| {
            if species.path == "b.lua" {
                return Err(Error::TimeLimit {
                    location: Location::new("b.lua", 7),
                });
            }
            Ok((stick(), Vec::new()))
        };
        let mut run = ForestRun::new(spec()).grower(Arc::new(limit));
        let e = run.run(&RunContext::default()).expect_err("b fails");
        assert!(
            matches!(
                &e,
                ForestError::Species {
                    layer: 1,
                    error: Error::TimeLimit { .. },
                    ..
                }
            ),
            "{e:?}"
        );
        let typed = run.engine_error(e);
        assert!(matches!(&typed, Error::TimeLimit { .. }), "{typed:?}");
        assert_eq!(
            typed.to_string(),
            "b.lua:7: time limit exceeded (see --time-limit)"
        );

        let mistake = |species: &ScriptSpecies, _: u64, _: &RunContext| {
            Err(Error::script(Location::new(&species.path, 3), "no sap"))
        };
        let mut run = ForestRun::new(spec()).grower(Arc::new(mistake));
        let e = run.run(&RunContext::default()).expect_err("both fail");
        assert!(matches!(&e, ForestError::Species { layer: 0, .. }), "{e:?}");
        assert_eq!(
            run.engine_error(e).to_string(),
            "f.lua:2: forest:scatter: species 'a.lua' failed: a.lua:3: no sap"
        );
    }

    #[test]
    fn script_species_need_a_grower() {
        let mut run = ForestRun::new(spec());
        let e = run.run(&RunContext::default()).expect_err("no grower");
        assert!(matches!(e, ForestError::NoGrower { layer: 0 }), "{e:?}");
        assert_eq!(
            run.engine_error(e).to_string(),
            "f.lua:1: pge.Forest: species scripts need a session created by an engine"
        );
    }

    #[test]
    fn the_configuration_decides_what_is_grown_and_the_steps_are_three() {
        let calls = Arc::new(AtomicUsize::new(0));
        let counted = calls.clone();
        let grower = Arc::new(move |_: &ScriptSpecies, _: u64, _: &RunContext| {
            counted.fetch_add(1, Ordering::Relaxed);
            Ok((stick(), Vec::new()))
        });
        let ctx = RunContext::default();
        let mut whole = ForestRun::new(spec()).grower(grower.clone());
        let mut steps = Vec::new();
        loop {
            let step = whole.step_forest(&ctx).expect("steps");
            steps.push(step);
            if step == Step::Done {
                break;
            }
        }
        assert_eq!(steps.len(), 3);
        assert_eq!(
            calls.load(Ordering::Relaxed),
            4,
            "two variants of two layers"
        );
        let model = whole.model().expect("model");
        assert_eq!(model.groups.len(), 4);
        assert!(
            model
                .stats
                .phases
                .iter()
                .any(|(name, _)| name == "variants")
        );

        // Referring to shared variants grows none of them: the groups place trees only.
        calls.store(0, Ordering::Relaxed);
        let refer = ForestConfig {
            cache: None,
            sharing: Some(VariantSharing::Refer),
        };
        let mut tile = ForestRun::new(spec()).grower(grower.clone()).config(refer);
        tile.select_tile(1, 1).expect("tile");
        let model = tile.run(&ctx).expect("runs");
        assert_eq!(calls.load(Ordering::Relaxed), 0);
        assert!(model.groups.iter().all(|g| g.meshes.is_empty()));
        assert!(model.groups.iter().any(|g| !g.transforms.is_empty()));

        // Writing them grows them and places nothing.
        let write = ForestConfig {
            cache: None,
            sharing: Some(VariantSharing::Write),
        };
        let model = ForestRun::new(spec())
            .grower(grower)
            .config(write)
            .run(&ctx)
            .expect("runs");
        assert_eq!(calls.load(Ordering::Relaxed), 4);
        assert_eq!(model.groups.len(), 4);
        assert!(model.groups.iter().all(|g| g.transforms.is_empty()));
    }
}
