//! A host program that builds a forest from Rust, without a script: a terrain, two layers,
//! the layout read back instance by instance, then each variant given a mesh the host made
//! itself (a cone) and the whole written as an instanced `.glb`.
//!
//! Run with `cargo run --example forest_host [OUT.glb]`. `tests/forest.rs` runs [`run`].

use std::path::Path;

use glam::Vec3;
use pge_engine::export::{ExportMeta, glb_bytes};
use pge_engine::geometry::{Mesh, Model};
use pge_forest::{
    Density, FbmOptions, Forest, Grown, Instance, Layer, Terrain, Variants, assemble,
};

/// A cone of `height` metres: the host's stand-in for a tree.
fn cone(height: f32, radius: f32) -> Result<Mesh, Box<dyn std::error::Error>> {
    let sides = 8u32;
    let mut positions = vec![Vec3::new(0.0, height, 0.0)];
    for k in 0..sides {
        let a = k as f32 * std::f32::consts::TAU / sides as f32;
        positions.push(Vec3::new(radius * a.cos(), 0.0, radius * a.sin()));
    }
    let mut indices = Vec::new();
    for k in 0..sides {
        indices.extend_from_slice(&[0, 1 + (k + 1) % sides, 1 + k]);
    }
    Ok(Mesh::from_triangles(positions, indices)?)
}

/// Lays out a 300 m forest of firs (3 variants) and birches (2 variants), prints what it
/// placed, writes the instanced `.glb` to `out` and returns the layout's instances.
pub fn run(out: &Path) -> Result<Vec<Instance>, Box<dyn std::error::Error>> {
    let mut forest = Forest::new([300.0, 300.0], 42, Some(100.0))?;
    let relief = FbmOptions {
        height: 25.0,
        scale: 200.0,
        ..FbmOptions::default()
    };
    forest.terrain = Terrain::fbm(forest.size, relief, forest.seed);
    let mut firs = Layer::new("fir", 5.0);
    firs.altitude = [0.0, 100.0];
    firs.variants = Variants::Count(3);
    let mut birches = Layer::new("birch", 4.0);
    birches.density = Density::Constant(0.5);
    birches.variants = Variants::Count(2);
    forest.layers = vec![firs, birches];

    let layout = forest.layout(None)?;
    for (layer, count) in forest.layers.iter().zip(&layout.counts) {
        println!("{}: {count} trees", layer.name);
    }
    if let Some(first) = layout.instances.first() {
        println!(
            "first tree: {} variant {} at {:?}, yaw {:.1} deg, scale {:.2}",
            forest.layers[first.layer as usize].name,
            first.variant,
            first.position,
            first.yaw.to_degrees(),
            first.scale
        );
    }

    // One model per variant; a real host would grow trees here.
    let grown = vec![
        Grown {
            variants: (0..3)
                .map(|v| cone(6.0 + v as f32, 1.5).map(Model::from_mesh))
                .collect::<Result<_, _>>()?,
        },
        Grown {
            variants: (0..2)
                .map(|v| cone(4.0 + v as f32, 1.0).map(Model::from_mesh))
                .collect::<Result<_, _>>()?,
        },
    ];
    let model = assemble(&forest, &layout, &grown, None);
    std::fs::write(out, glb_bytes(&model, &ExportMeta::default())?)?;
    println!(
        "{} instances written to {}",
        model.instance_count() - 1,
        out.display()
    );
    Ok(layout.instances)
}

#[allow(dead_code, reason = "the test includes this file for run() alone")]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "forest_host.glb".into());
    run(Path::new(&out)).map(|_| ())
}
