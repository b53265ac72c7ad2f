//! A forest run step by step: the layout, then the variants of every species (species
//! scripts grown in parallel, each in a session of its own), then the assembly.

use std::cell::RefCell;
use std::path::Path;
use std::rc::Rc;

use mlua::{Value, WeakLua};
use pge_engine::algorithm::run;
use pge_engine::geometry::Model;
use pge_engine::lua::{algorithm_from, to_engine_error};
use pge_engine::{Algorithm, Engine, Error, Location, RunContext, SessionOptions, Step};
use rayon::prelude::*;

use pge_tree::lod::LodOptions;

use super::{Spec, Species};
use crate::{
    ForestError, Grown, GrownVariant, Layout, VariantCache, VariantKey, VariantLod, VariantSharing,
    Variants, assemble_budgeted, check_budget, instance_leaves, layout_model, shared_layer,
    unique_seed, variant_lod, variant_seed, variants_model, with_lod,
};

fn forest_error(location: &Location, e: ForestError) -> Error {
    match e {
        ForestError::Script(e) => e,
        other => Error::script(location.clone(), other.to_string()),
    }
}

/// A forest run step by step: layout, variants, assembly.
pub(super) struct ForestAlgorithm {
    spec: Rc<RefCell<Spec>>,
    lua: WeakLua,
    layout: Option<Layout>,
    grown: Option<Vec<Grown>>,
    model: Option<Model>,
    /// Seconds of each step, reported as phases of the run.
    phases: Vec<(&'static str, f64)>,
}

impl ForestAlgorithm {
    /// The forest of `spec`, not yet run.
    pub(super) fn new(spec: Rc<RefCell<Spec>>, lua: WeakLua) -> ForestAlgorithm {
        ForestAlgorithm {
            spec,
            lua,
            layout: None,
            grown: None,
            model: None,
            phases: Vec::new(),
        }
    }
}

/// A species script: its shown path and `params` overrides.
type ScriptSpecies = (String, Vec<(String, String)>);

/// Grows one variant of a species script in a session of its own; returns it with the
/// files the session read.
fn grow_script(
    engine: &Engine,
    shown: &str,
    params: &[(String, String)],
    seed: u64,
    ctx: &RunContext,
) -> pge_engine::Result<GrownVariant> {
    let session = engine.session(SessionOptions {
        seed,
        params: params.to_vec(),
        steps: None,
        cancel: ctx.cancel.clone(),
    })?;
    let model = session.generate(Path::new(shown), &mut |_, _| {})?.model;
    Ok((model, session.loaded_files()))
}

/// [`grow_script`] through the variant cache, when the run has one (`--variant-cache`).
fn grow_cached(
    engine: &Engine,
    cache: Option<&VariantCache>,
    (shown, params): &ScriptSpecies,
    seed: u64,
    ctx: &RunContext,
    location: &Location,
) -> pge_engine::Result<Model> {
    let grow = || grow_script(engine, shown, params, seed, ctx);
    match cache {
        None => grow().map(|(model, _)| model),
        Some(cache) => {
            let key = VariantKey {
                shown,
                params,
                seed,
                max_modules: ctx.max_modules,
            };
            cache.variant(&key, &location.to_string(), grow)
        }
    }
}

impl ForestAlgorithm {
    pub(super) fn grow(&self, layout: &Layout, ctx: &RunContext) -> pge_engine::Result<Vec<Grown>> {
        let spec = self.spec.borrow();
        let seed = spec.forest.seed;
        // Layers whose variants a tile refers to rather than grows (`--variants DIR`).
        let referred = |l: usize| {
            self.sharing() == Some(VariantSharing::Refer) && shared_layer(&spec.forest, l)
        };
        // (layer, variant, seed) of every tree to grow, in a fixed order.
        let mut jobs: Vec<Vec<u64>> = Vec::new();
        for (l, layer) in spec.forest.layers.iter().enumerate() {
            jobs.push(match layer.variants {
                Variants::Count(n) => (0..n).map(|v| variant_seed(seed, l, v)).collect(),
                Variants::Unique => layout
                    .instances
                    .iter()
                    .filter(|i| i.layer as usize == l)
                    .map(|i| unique_seed(seed, i))
                    .collect(),
            });
        }
        let mut scripts: Vec<(usize, usize, u64)> = Vec::new();
        for (l, (species, _)) in spec.species.iter().enumerate() {
            if matches!(species, Species::Path { .. }) && !referred(l) {
                scripts.extend(jobs[l].iter().enumerate().map(|(v, &s)| (l, v, s)));
            }
        }
        let engine = match self.lua.try_upgrade() {
            Some(lua) => pge_engine::lua::engine(&lua),
            None => None,
        };
        let mut grown: Vec<Grown> = jobs
            .iter()
            .map(|j| Grown {
                variants: Vec::with_capacity(j.len()),
            })
            .collect();
        if !scripts.is_empty() {
            let Some(engine) = engine else {
                return Err(Error::script(
                    spec.location.clone(),
                    "pge.Forest: species scripts need a session created by an engine",
                ));
            };
            let paths: Vec<Option<ScriptSpecies>> = spec
                .species
                .iter()
                .map(|(s, _)| match s {
                    Species::Path { shown, params } => Some((shown.clone(), params.clone())),
                    Species::Function { .. } => None,
                })
                .collect();
            let ctx_send = ctx.clone();
            // Layers of a few variants shared by every tile go through the cache; "unique"
            // trees are grown where they stand.
            let cache = self.lua.try_upgrade().and_then(|lua| {
                lua.app_data_ref::<VariantCache>()
                    .map(|c| VariantCache::clone(&c))
            });
            let cached: Vec<Option<&VariantCache>> = spec
                .forest
                .layers
                .iter()
                .map(|layer| match layer.variants {
                    Variants::Count(_) => cache.as_ref(),
                    Variants::Unique => None,
                })
                .collect();
            let locations: Vec<Location> = spec.species.iter().map(|(_, l)| l.clone()).collect();
            let results: Vec<pge_engine::Result<Model>> = scripts
                .par_iter()
                .map(|&(l, _, s)| match &paths[l] {
                    Some(species) => {
                        grow_cached(&engine, cached[l], species, s, &ctx_send, &locations[l])
                    }
                    None => Err(Error::Export("not a script species".into())),
                })
                .collect();
            for (&(l, _, _), r) in scripts.iter().zip(results) {
                let model = r.map_err(|e| {
                    let shown = match &spec.species[l].0 {
                        Species::Path { shown, .. } => shown.as_str(),
                        Species::Function { .. } => "",
                    };
                    Error::script(
                        spec.species[l].1.clone(),
                        format!("forest:scatter: species '{shown}' failed: {e}"),
                    )
                })?;
                grown[l].variants.push(model);
            }
        }
        for (l, (species, location)) in spec.species.iter().enumerate() {
            let Species::Function { f, params } = species else {
                continue;
            };
            if referred(l) {
                continue;
            }
            let Some(lua) = self.lua.try_upgrade() else {
                return Err(Error::script(location.clone(), "the Lua state is gone"));
            };
            for &s in &jobs[l] {
                ctx.check_deadline(location)?;
                let value: Value = f
                    .call((params.clone(), s))
                    .map_err(|e| to_engine_error(&lua, e))?;
                let mut algorithm = algorithm_from(&lua, value, location)?;
                let inner = RunContext {
                    seed: s,
                    steps: None,
                    ..ctx.clone()
                };
                grown[l]
                    .variants
                    .push(run(&mut *algorithm, &inner, &mut |_| {})?);
            }
        }
        for (l, g) in grown.iter_mut().enumerate() {
            if referred(l) {
                g.variants = vec![Model::new(); jobs[l].len()];
            }
        }
        if let Some(options) = &spec.lod.variants {
            give_levels(&spec, &mut grown, options)?;
        }
        Ok(grown)
    }

    /// The run's [`VariantSharing`], if any.
    fn sharing(&self) -> Option<VariantSharing> {
        let lua = self.lua.try_upgrade()?;
        lua.app_data_ref::<VariantSharing>().map(|s| *s)
    }
}

/// The levels of every grown variant, by layer and variant.
pub(super) fn levels(grown: &[Grown]) -> Vec<Vec<Option<VariantLod>>> {
    grown
        .iter()
        .map(|g| g.variants.iter().map(variant_lod).collect())
        .collect()
}

/// How many leaves each instance of `layout` draws for the forest's camera, `None` without
/// one; errors at the `pge.Forest` line.
pub(super) fn budgeted_leaves(
    spec: &Spec,
    layout: &Layout,
    grown: &[Grown],
) -> pge_engine::Result<Option<Vec<Option<u32>>>> {
    let Some(camera) = &spec.lod.camera else {
        return Ok(None);
    };
    instance_leaves(&spec.forest, layout, spec.selected, &levels(grown), camera)
        .map(Some)
        .map_err(|e| forest_error(&spec.location, e))
}

/// The forest's model: the layout's instances of the grown variants, with each instance's
/// leaves when the forest has a camera.
fn assembled(spec: &Spec, layout: &Layout, grown: &[Grown]) -> pge_engine::Result<Model> {
    let leaves = budgeted_leaves(spec, layout, grown)?;
    Ok(assemble_budgeted(
        &spec.forest,
        layout,
        grown,
        spec.selected,
        leaves.as_deref(),
    ))
}

/// Gives every grown variant the forest's levels of detail ([`with_lod`]), in parallel; the
/// first failure in (layer, variant) order is the error, at the `pge.Forest` line.
fn give_levels(spec: &Spec, grown: &mut [Grown], options: &LodOptions) -> pge_engine::Result<()> {
    let mut models: Vec<(usize, usize, &mut Model)> = Vec::new();
    for (l, g) in grown.iter_mut().enumerate() {
        for (v, model) in g.variants.iter_mut().enumerate() {
            models.push((l, v, model));
        }
    }
    let names: Vec<&str> = spec.forest.layers.iter().map(|x| x.name.as_str()).collect();
    let results: Vec<Result<(), String>> = models
        .par_iter_mut()
        .map(|(l, v, model)| {
            let given = with_lod(model, options).map_err(|e| {
                let name = names.get(*l).copied().unwrap_or("");
                format!(
                    "pge.Forest: lod: variant {v} of layer {} ({name}): {e}",
                    *l + 1
                )
            })?;
            **model = given;
            Ok(())
        })
        .collect();
    match results.into_iter().find_map(Result::err) {
        Some(message) => Err(Error::script(spec.location.clone(), message)),
        None => Ok(()),
    }
}

impl Algorithm for ForestAlgorithm {
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
        let t0 = std::time::Instant::now();
        let (name, step) = self.step_timed(ctx)?;
        self.phases.push((name, t0.elapsed().as_secs_f64()));
        Ok(step)
    }

    fn finish(&mut self, _: &RunContext) -> pge_engine::Result<Model> {
        let spec = self.spec.borrow();
        let mut model = match (&self.model, &self.layout, &self.grown) {
            (Some(model), _, _) => model.clone(),
            (None, _, Some(grown)) if self.sharing() == Some(VariantSharing::Write) => {
                variants_model(&spec.forest, grown)
            }
            (None, Some(layout), Some(grown)) => assembled(&spec, layout, grown)?,
            (None, Some(layout), None) => layout_model(&spec.forest, layout, spec.selected),
            _ => layout_model(&spec.forest, &Layout::default(), spec.selected),
        };
        for (name, seconds) in &self.phases {
            model.stats.add_phase(name, *seconds);
        }
        Ok(model)
    }

    fn planned_steps(&self) -> Option<u32> {
        Some(3)
    }
}

impl ForestAlgorithm {
    /// One step: layout, then variants, then assembly; returns the step's name.
    fn step_timed(&mut self, ctx: &RunContext) -> pge_engine::Result<(&'static str, Step)> {
        if self.layout.is_none() && self.sharing() == Some(VariantSharing::Write) {
            // Writing the shared variants: no trees to place.
            self.layout = Some(Layout::default());
            return Ok(("layout", Step::Continue));
        }
        if self.layout.is_none() {
            let spec = self.spec.borrow();
            if let Some(camera) = &spec.lod.camera {
                check_budget(&spec.forest, camera).map_err(|e| {
                    Error::script(spec.location.clone(), format!("pge.Forest: {e}"))
                })?;
                if self.sharing() == Some(VariantSharing::Refer) {
                    return Err(Error::script(
                        spec.location.clone(),
                        "pge.Forest: lod.camera needs the variants' leaves, which a tile \
                         referring to shared variants (--variants) does not grow: write \
                         standalone tiles",
                    ));
                }
            }
            let mut layout = spec
                .forest
                .layout(spec.selected)
                .map_err(|e| forest_error(&spec.location, e))?;
            // Warnings point at the scatter call of the layer that fits no tree.
            let empty = layout.counts.iter().enumerate().filter(|(_, c)| **c == 0);
            let located: Vec<String> = empty
                .zip(&layout.warnings)
                .map(|((l, _), w)| format!("{}: warning: forest:scatter: {w}", spec.species[l].1))
                .collect();
            layout.warnings = located;
            drop(spec);
            self.layout = Some(layout);
            return Ok(("layout", Step::Continue));
        }
        if self.grown.is_none() {
            let grown = match &self.layout {
                Some(layout) => self.grow(layout, ctx)?,
                None => self.grow(&Layout::default(), ctx)?,
            };
            self.grown = Some(grown);
            return Ok(("variants", Step::Continue));
        }
        if self.model.is_none() {
            let spec = self.spec.borrow();
            if let (Some(layout), Some(grown)) = (&self.layout, &self.grown) {
                self.model = Some(if self.sharing() == Some(VariantSharing::Write) {
                    variants_model(&spec.forest, grown)
                } else {
                    assembled(&spec, layout, grown)?
                });
            }
        }
        Ok(("assembly", Step::Done))
    }
}
