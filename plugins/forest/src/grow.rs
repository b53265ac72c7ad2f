//! Growing a forest's variants: every variant of a script species by the host's
//! [`SpeciesGrower`], in parallel on every core (through the variant cache when the run has
//! one), then the variants of species functions in order on the calling thread, then the
//! forest's levels of detail on every variant. The result is the same for any thread count:
//! each variant depends only on its species and its seed.

use pge_engine::RunContext;
use pge_engine::geometry::Model;
use pge_lod::LodOptions;
use rayon::prelude::*;

use crate::{
    ForestError, ForestSpec, Grown, GrownVariant, Layout, ScriptSpecies, Species, VariantCache,
    VariantKey, VariantSharing, Variants, shared_layer, unique_seed, variant_seed, with_lod,
};

/// Grows the variants of script species for a forest run: the host's way to run a species
/// script (`pge_forest::lua::SessionGrower` runs it in a sandboxed session of its own).
///
/// [`grow`](SpeciesGrower::grow) is called once per variant, from any worker thread and in
/// no particular order, so what it returns must depend on its arguments alone (the output
/// is then byte-identical for any thread count). `ctx` holds the forest run's deadline and
/// memory budget, for the whole run: a grower charges what it holds to `ctx.budget` and
/// stops at `ctx.deadline` (or when [`RunContext::check_deadline`] says the run stopped). An
/// error stops the run and the variants still growing: the first failing variant in (layer,
/// variant) order (the ones stopped by it aside) is reported as [`ForestError::Species`],
/// its error kept as it was (a [`pge_engine::Error::TimeLimit`] stays one).
///
/// Any `Fn(&ScriptSpecies, u64, &RunContext) -> pge_engine::Result<GrownVariant>` that is
/// `Send + Sync` is a grower.
pub trait SpeciesGrower: Send + Sync {
    /// Grows the variant of `species` seeded by `seed`: its model and the files it read
    /// (checked again by the variant cache on every hit; empty when there are none). `ctx`
    /// is the forest run's context (its deadline, module cap and cancel flag).
    fn grow(
        &self,
        species: &ScriptSpecies,
        seed: u64,
        ctx: &RunContext,
    ) -> pge_engine::Result<GrownVariant>;
}

impl<F> SpeciesGrower for F
where
    F: Fn(&ScriptSpecies, u64, &RunContext) -> pge_engine::Result<GrownVariant> + Send + Sync,
{
    fn grow(
        &self,
        species: &ScriptSpecies,
        seed: u64,
        ctx: &RunContext,
    ) -> pge_engine::Result<GrownVariant> {
        self(species, seed, ctx)
    }
}

/// What a forest run does besides growing and placing: keep grown variants in a cache, and
/// share the variants of its layers of a few variants between the tiles of a world.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ForestConfig {
    /// Variants of script species are read from and kept in this cache
    /// (`pge run --variant-cache DIR`); the output is the same.
    pub cache: Option<VariantCache>,
    /// Write only the shared variants, or refer to them (`--variants-out`, `--variants`).
    pub sharing: Option<VariantSharing>,
}

impl ForestConfig {
    /// Whether layer `l` refers to shared variants instead of growing them.
    pub(crate) fn referred(&self, spec: &ForestSpec, l: usize) -> bool {
        self.sharing == Some(VariantSharing::Refer) && shared_layer(spec.forest(), l)
    }
}

/// [`SpeciesGrower::grow`] through the cache, when there is one.
fn grow_cached(
    grower: &dyn SpeciesGrower,
    cache: Option<&VariantCache>,
    species: &ScriptSpecies,
    seed: u64,
    ctx: &RunContext,
    where_: &str,
) -> pge_engine::Result<Model> {
    let grow = || grower.grow(species, seed, ctx);
    match cache {
        None => grow().map(|(model, _)| model),
        Some(cache) => {
            let key = VariantKey {
                shown: &species.path,
                params: &species.params,
                seed,
                max_modules: ctx.max_modules,
            };
            cache.variant(&key, where_, grow)
        }
    }
}

/// Where a variant of `species` that has not started yet stops: its script.
fn species_origin(species: &ScriptSpecies) -> pge_engine::Location {
    pge_engine::Location {
        file: species.path.clone(),
        line: None,
    }
}

/// The seeds of every variant to grow, layer by layer, in a fixed order: `variants = N`
/// layers their N variant seeds, `"unique"` layers one per instance of `layout`.
fn variant_seeds(spec: &ForestSpec, layout: &Layout) -> Vec<Vec<u64>> {
    let forest = spec.forest();
    let seed = forest.seed;
    forest
        .layers
        .iter()
        .enumerate()
        .map(|(l, layer)| match layer.variants {
            Variants::Count(n) => (0..n).map(|v| variant_seed(seed, l, v)).collect(),
            Variants::Unique => layout
                .instances
                .iter()
                .filter(|i| i.layer as usize == l)
                .map(|i| unique_seed(seed, i))
                .collect(),
        })
        .collect()
}

/// Grows every variant the trees of `layout` need (see the module's documentation); layers
/// that refer to shared variants get empty models.
pub(crate) fn grow_variants(
    spec: &ForestSpec,
    layout: &Layout,
    grower: Option<&dyn SpeciesGrower>,
    config: &ForestConfig,
    ctx: &RunContext,
) -> Result<Vec<Grown>, ForestError> {
    let seeds = variant_seeds(spec, layout);
    let mut grown: Vec<Grown> = seeds
        .iter()
        .map(|s| Grown {
            variants: Vec::with_capacity(s.len()),
        })
        .collect();
    // (layer, seed) of every variant of a script species, in (layer, variant) order.
    let mut scripts: Vec<(usize, &ScriptSpecies, u64)> = Vec::new();
    for (l, species) in spec.species().iter().enumerate() {
        if let Species::Script(script) = species
            && !config.referred(spec, l)
        {
            scripts.extend(seeds[l].iter().map(|&s| (l, script, s)));
        }
    }
    if let Some(&(l, _, _)) = scripts.first() {
        let Some(grower) = grower else {
            return Err(ForestError::NoGrower { layer: l });
        };
        // Layers of a few variants, shared by every tile, go through the cache; "unique"
        // trees are grown where they stand.
        let layers = &spec.forest().layers;
        let cached: Vec<Option<&VariantCache>> = layers
            .iter()
            .map(|layer| match layer.variants {
                Variants::Count(_) => config.cache.as_ref(),
                Variants::Unique => None,
            })
            .collect();
        let places: Vec<String> = (0..layers.len())
            .map(|l| spec.layer_origin(l).to_string())
            .collect();
        // The variants fail together: the first failure stops the others (a variant not
        // started yet is not started, one growing stops at its next check), whose
        // cancellation is not the run's error.
        let together = RunContext {
            budget: ctx.budget.child(),
            ..ctx.clone()
        };
        let results: Vec<pge_engine::Result<Model>> = scripts
            .par_iter()
            .map(|&(l, species, s)| {
                together.check_deadline(&species_origin(species))?;
                let r = grow_cached(grower, cached[l], species, s, &together, &places[l]);
                if r.is_err() {
                    together.budget.stop();
                }
                r
            })
            .collect();
        let failures: Vec<(usize, &ScriptSpecies, &pge_engine::Error)> = scripts
            .iter()
            .zip(&results)
            .filter_map(|(&(l, species, _), r)| r.as_ref().err().map(|e| (l, species, e)))
            .collect();
        let first = failures
            .iter()
            .find(|(_, _, e)| !matches!(e, pge_engine::Error::Cancelled { .. }))
            .or(failures.first());
        if let Some((l, species, error)) = first {
            return Err(ForestError::Species {
                layer: *l,
                species: species.path.clone(),
                error: error.duplicate(),
            });
        }
        for (&(l, _, _), r) in scripts.iter().zip(results) {
            grown[l].variants.extend(r.ok());
        }
    }
    for (l, species) in spec.species().iter().enumerate() {
        let Species::Function(f) = species else {
            continue;
        };
        if config.referred(spec, l) {
            continue;
        }
        let origin = spec.layer_origin(l);
        for &s in &seeds[l] {
            ctx.check_deadline(&origin).map_err(ForestError::Script)?;
            let inner = RunContext {
                seed: s,
                steps: None,
                ..ctx.clone()
            };
            grown[l]
                .variants
                .push(f(s, &inner).map_err(ForestError::Script)?);
        }
    }
    for (l, g) in grown.iter_mut().enumerate() {
        if config.referred(spec, l) {
            g.variants = vec![Model::new(); seeds[l].len()];
        }
    }
    if let Some(options) = &spec.lod.variants {
        give_levels(spec, &mut grown, options)?;
    }
    Ok(grown)
}

/// Gives every grown variant the forest's levels of detail ([`with_lod`]), in parallel; the
/// first failure in (layer, variant) order is the error.
fn give_levels(
    spec: &ForestSpec,
    grown: &mut [Grown],
    options: &LodOptions,
) -> Result<(), ForestError> {
    let mut models: Vec<(usize, usize, &mut Model)> = Vec::new();
    for (l, g) in grown.iter_mut().enumerate() {
        for (v, model) in g.variants.iter_mut().enumerate() {
            models.push((l, v, model));
        }
    }
    let names: Vec<&str> = spec
        .forest()
        .layers
        .iter()
        .map(|x| x.name.as_str())
        .collect();
    let results: Vec<Result<(), ForestError>> = models
        .par_iter_mut()
        .map(|(l, v, model)| {
            **model = with_lod(model, options).map_err(|error| ForestError::Lod {
                layer: *l,
                name: names.get(*l).copied().unwrap_or("").to_string(),
                variant: *v,
                error,
            })?;
            Ok(())
        })
        .collect();
    results.into_iter().collect()
}
