//! A host program that grows a forest from the library's species scripts without writing
//! any Lua: the world, its terrain and its layers are a [`ForestSpec`] built in Rust; each
//! layer's trees come from a script of `scripts/species/`, whose variants a
//! [`SessionGrower`] grows in parallel, each in a sandboxed session of its own; the
//! [`ForestRun`] lays the trees out, grows the variants and assembles the instanced model,
//! written as a `.glb`. A failure is a typed [`ForestError`]: a species that runs out of
//! time is an `Error::TimeLimit` at its script's line.
//!
//! Run with `cargo run --release --example forest_species [OUT.glb]`. `tests/forest.rs`
//! runs [`run`] with few attraction points.

use std::path::Path;
use std::sync::Arc;

use pge_engine::RunContext;
use pge_engine::export::{ExportMeta, glb_bytes};
use pge_engine::geometry::Model;
use pge_forest::lua::SessionGrower;
use pge_forest::{
    FbmOptions, ForestError, ForestRun, ForestSpec, Layer, ScriptSpecies, Species, Terrain,
    Variants,
};

/// A species script of the library (this checkout's `scripts/species/`) with these
/// parameter overrides.
fn species(name: &str, params: &[(&str, &str)]) -> Species {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scripts/species")
        .join(name);
    Species::Script(ScriptSpecies::new(path.to_string_lossy(), params))
}

/// The forest of the host: 160 m of rolling ground, oaks in the valleys and conifers on the
/// slopes above them, two variants of each; `points` attraction points per oak (the
/// conifers, grown by `pge.Conifer`, take none).
pub fn spec(points: u32) -> Result<ForestSpec, ForestError> {
    let mut spec = ForestSpec::new([160.0, 160.0], 11, Some(80.0))?;
    let relief = FbmOptions {
        height: 20.0,
        scale: 150.0,
        ..FbmOptions::default()
    };
    spec.set_terrain(Terrain::fbm(spec.forest().size, relief, spec.forest().seed));
    let mut oaks = Layer::new("oak", 12.0);
    oaks.altitude = [-100.0, 3.0];
    oaks.variants = Variants::Count(2);
    let points = points.to_string();
    spec.add_layer(oaks, species("oak.lua", &[("points", points.as_str())]))?;
    let mut conifers = Layer::new("conifer", 6.0);
    conifers.altitude = [1.0, 100.0];
    conifers.slope = [0.0, 40.0];
    conifers.variants = Variants::Count(2);
    spec.add_layer(conifers, species("conifer.lua", &[]))?;
    Ok(spec)
}

/// Grows the forest of [`spec`] (or its tile `(i, j)`) with `engine`'s sessions, writes it
/// to `out` and returns its model.
pub fn run(
    engine: pge_engine::Engine,
    points: u32,
    tile: Option<(usize, usize)>,
    out: &Path,
) -> Result<Model, Box<dyn std::error::Error>> {
    let mut forest = ForestRun::new(spec(points)?).grower(Arc::new(SessionGrower::new(engine)));
    if let Some((i, j)) = tile {
        forest.select_tile(i, j)?;
    }
    let model = forest.run(&RunContext::default())?;
    for (layer, count) in forest.spec().forest().layers.iter().zip(counts(&model)) {
        println!("{}: {count} trees", layer.name);
    }
    std::fs::write(out, glb_bytes(&model, &ExportMeta::default())?)?;
    println!(
        "{} instances written to {}",
        model.instance_count() - 1,
        out.display()
    );
    Ok(model)
}

/// The trees of each layer in `model`, from its instance groups (`SPECIES/VARIANT`, in
/// layer order).
pub fn counts(model: &Model) -> Vec<usize> {
    let mut counts: Vec<(String, usize)> = Vec::new();
    for group in &model.groups {
        let species = group.name.split('/').next().unwrap_or("").to_string();
        match counts.last_mut() {
            Some((name, n)) if *name == species => *n += group.transforms.len(),
            _ => counts.push((species, group.transforms.len())),
        }
    }
    counts.into_iter().map(|(_, n)| n).collect()
}

#[allow(dead_code, reason = "the test includes this file for run() alone")]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "forest_species.glb".into());
    let engine = pge::default_engine().build()?;
    run(engine, 1500, None, Path::new(&out)).map(|_| ())
}
