//! A host application hands its own object to scripts: a custom [`Plugin`] exposes the
//! host's `Heightfield` as a Lua `UserData` (`pge.world`), and the script
//! `examples/host_object.lua` plants markers on it, asking the host for heights and
//! reporting back what it planted.
//!
//! ```text
//! cargo run --example host_object
//! ```

use pge_engine::math;
use std::sync::{Arc, Mutex};

use mlua::{Lua, Table, UserData, UserDataMethods};
use pge_engine::{Plugin, SessionOptions};

/// The host's own terrain: heights on a grid, as a game would keep them.
struct Heightfield {
    size: usize,
    cell: f32,
    heights: Vec<f32>,
}

impl Heightfield {
    fn new(size: usize, cell: f32) -> Heightfield {
        let mut heights = Vec::with_capacity(size * size);
        for j in 0..size {
            for i in 0..size {
                let (x, z) = (i as f32 * cell, j as f32 * cell);
                heights.push(math::sin(x * 0.3) * 1.5 + math::cos(z * 0.2));
            }
        }
        Heightfield {
            size,
            cell,
            heights,
        }
    }

    /// Bilinear height at world (x, z), clamped to the grid.
    fn height(&self, x: f32, z: f32) -> f32 {
        let max = (self.size - 1) as f32;
        let (gx, gz) = (
            (x / self.cell).clamp(0.0, max),
            (z / self.cell).clamp(0.0, max),
        );
        let (i, j) = (gx.floor() as usize, gz.floor() as usize);
        let (i1, j1) = ((i + 1).min(self.size - 1), (j + 1).min(self.size - 1));
        let (fx, fz) = (gx - i as f32, gz - j as f32);
        let h = |i: usize, j: usize| self.heights[j * self.size + i];
        let a = h(i, j) * (1.0 - fx) + h(i1, j) * fx;
        let b = h(i, j1) * (1.0 - fx) + h(i1, j1) * fx;
        a * (1.0 - fz) + b * fz
    }
}

/// What scripts see: the heightfield plus a log of what they planted.
struct World {
    field: Arc<Heightfield>,
    planted: Arc<Mutex<Vec<[f32; 3]>>>,
}

impl UserData for World {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method("height", |_, w, (x, z): (f32, f32)| {
            Ok(w.field.height(x, z))
        });
        m.add_method("extent", |_, w, ()| {
            Ok((w.field.size - 1) as f32 * w.field.cell)
        });
        m.add_method("plant", |_, w, (x, y, z): (f32, f32, f32)| {
            w.planted
                .lock()
                .map_err(|_| mlua::Error::runtime("planted log poisoned"))?
                .push([x, y, z]);
            Ok(())
        });
    }
}

/// The plugin that puts `pge.world` into every session.
struct WorldPlugin {
    field: Arc<Heightfield>,
    planted: Arc<Mutex<Vec<[f32; 3]>>>,
}

impl Plugin for WorldPlugin {
    fn name(&self) -> &str {
        "world"
    }

    fn register(&self, _lua: &Lua, pge: &Table) -> mlua::Result<()> {
        pge.set(
            "world",
            World {
                field: self.field.clone(),
                planted: self.planted.clone(),
            },
        )
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let field = Arc::new(Heightfield::new(64, 0.5));
    let planted = Arc::new(Mutex::new(Vec::new()));
    let engine = pge::default_engine()
        .plugin(WorldPlugin {
            field: field.clone(),
            planted: planted.clone(),
        })
        .build()?;
    let session = engine.session(SessionOptions::default())?;
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/host_object.lua");
    let generated = session.generate(script.as_ref(), &mut |_, _| {})?;
    let planted = planted.lock().map_err(|_| "planted log poisoned")?;
    for p in planted.iter() {
        let ground = field.height(p[0], p[2]);
        assert!(
            (p[1] - ground).abs() < 1e-4,
            "the script asked the host for the height"
        );
    }
    let glb = pge_engine::export::glb_bytes(&generated.model, &Default::default())?;
    std::fs::write("host_object.glb", glb)?;
    println!(
        "planted {} markers on the host's terrain; wrote host_object.glb",
        planted.len()
    );
    Ok(())
}
