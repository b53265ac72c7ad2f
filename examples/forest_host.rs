//! A host program that builds a forest from Rust, without a script: a terrain, two layers,
//! the layout read back instance by instance, then each variant given a mesh the host made
//! itself (a cone with a crown of leaf quads), levels of detail for its leaves, each tree's
//! leaves for a camera within a budget, and the whole written as an instanced `.glb`.
//!
//! Run with `cargo run --example forest_host [OUT.glb]`. `tests/forest.rs` runs [`run`].

use pge_engine::math;
use std::path::Path;

use glam::Vec3;
use pge_engine::export::{ExportMeta, glb_bytes};
use pge_engine::geometry::{Mesh, Model};
use pge_forest::{
    Camera, Density, FbmOptions, Forest, Grown, Instance, Layer, Terrain, Variants,
    assemble_budgeted, instance_leaves, variant_lod, with_lod,
};
use pge_lod::{Budget, LodOptions};

/// A cone of `height` metres: the host's stand-in for a tree.
fn cone(height: f32, radius: f32) -> Result<Mesh, Box<dyn std::error::Error>> {
    let sides = 8u32;
    let mut positions = vec![Vec3::new(0.0, height, 0.0)];
    for k in 0..sides {
        let a = k as f32 * std::f32::consts::TAU / sides as f32;
        positions.push(Vec3::new(radius * math::cos(a), 0.0, radius * math::sin(a)));
    }
    let mut indices = Vec::new();
    for k in 0..sides {
        indices.extend_from_slice(&[0, 1 + (k + 1) % sides, 1 + k]);
    }
    Ok(Mesh::from_triangles(positions, indices)?)
}

/// A crown of `n` square leaves (four vertices each, named `leaves` as a tree's) on a
/// sphere of `radius` around `centre`, facing outwards.
fn crown(n: u32, centre: Vec3, radius: f32) -> Result<Mesh, Box<dyn std::error::Error>> {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    for k in 0..n {
        // Points spread by the golden angle, from the top down.
        let y = 1.0 - 2.0 * (k as f32 + 0.5) / n as f32;
        let a = k as f32 * 2.399_963;
        let out = Vec3::new(
            (1.0 - y * y).sqrt() * math::cos(a),
            y,
            (1.0 - y * y).sqrt() * math::sin(a),
        );
        let (u, v) = out.any_orthonormal_pair();
        let c = centre + out * radius;
        let base = positions.len() as u32;
        for (du, dv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            positions.push(c + (u * du + v * dv) * 0.25);
            normals.push(out);
        }
        indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    let mut mesh = Mesh::from_triangles(positions, indices)?;
    mesh.normals = normals;
    mesh.name = "leaves".into();
    Ok(mesh)
}

/// A tree of the host: a cone of `height` metres and a crown of leaves at its top.
fn tree(height: f32, radius: f32, leaves: u32) -> Result<Model, Box<dyn std::error::Error>> {
    let mut model = Model::from_mesh(cone(height, radius)?);
    let top = Vec3::new(0.0, 0.8 * height, 0.0);
    model.add_mesh(crown(leaves, top, 1.2 * radius)?, glam::Mat4::IDENTITY);
    Ok(model)
}

/// The camera of the host: at the forest's south edge, 2 m up, with a budget of 20,000
/// leaves, full trees within 20 m and none beyond 150 m.
pub const CAMERA: Camera = Camera {
    position: [0.0, 2.0, 150.0],
    budget: Budget {
        near: 20.0,
        far: 150.0,
        total: 20_000,
    },
};

/// Lays out a 300 m forest of firs (3 variants) and birches (2 variants), prints what it
/// placed, writes the instanced `.glb` to `out` and returns the layout's instances with the
/// leaves each draws for [`CAMERA`].
pub fn run(out: &Path) -> Result<Vec<(Instance, u32)>, Box<dyn std::error::Error>> {
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

    // One model per variant; a real host would grow trees here. Their leaves get levels of
    // detail (the vector V and its table), as a tree generator's `lod` would give them.
    let lod = LodOptions::default();
    let mut grown = Vec::new();
    for (count, height, radius, leaves) in [(3, 6.0, 1.5, 120), (2, 4.0, 1.0, 60)] {
        let mut variants = Vec::new();
        for v in 0..count {
            let model = tree(height + v as f32, radius, leaves + 10 * v)?;
            variants.push(with_lod(&model, &lod)?);
        }
        grown.push(Grown { variants });
    }
    // How many leaves each tree draws, seen from the camera.
    let lods: Vec<Vec<_>> = grown
        .iter()
        .map(|g| g.variants.iter().map(variant_lod).collect())
        .collect();
    let leaves = instance_leaves(&forest, &layout, None, &lods, &CAMERA)?;
    if let Some(Some(n)) = leaves.first() {
        let total: u32 = leaves.iter().flatten().sum();
        println!(
            "seen from {:?}: the first tree draws {n} leaves, the forest {total} of at most {}",
            CAMERA.position, CAMERA.budget.total
        );
    }
    let model = assemble_budgeted(&forest, &layout, &grown, None, Some(&leaves));
    std::fs::write(out, glb_bytes(&model, &ExportMeta::default())?)?;
    println!(
        "{} instances written to {}",
        model.instance_count() - 1,
        out.display()
    );
    Ok(layout
        .instances
        .into_iter()
        .zip(leaves)
        .map(|(i, n)| (i, n.unwrap_or(0)))
        .collect())
}

#[allow(dead_code, reason = "the test includes this file for run() alone")]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "forest_host.glb".into());
    run(Path::new(&out)).map(|_| ())
}
