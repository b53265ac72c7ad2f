//! PGE, the procedural generation engine: this package is the `pge` command and the
//! batteries-included engine.
//!
//! [`default_engine`] returns an [`EngineBuilder`](pge_engine::EngineBuilder) with every
//! plugin of the project and the script library, so a host application generates a model
//! in a few lines:
//!
//! ```no_run
//! let engine = pge::default_engine().build()?;
//! let session = engine.session(Default::default())?;
//! let generated = session.generate("scripts/examples/spiral.lua".as_ref(), &mut |_, _| {})?;
//! let glb = pge_engine::export::glb_bytes(&generated.model, &Default::default())?;
//! std::fs::write("spiral.glb", glb)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::PathBuf;

pub use pge_engine;

/// The folder of the script library: `$PGE_LIBRARY` if set, else the `scripts/` folder of
/// this source tree.
#[must_use]
pub fn library_folder() -> PathBuf {
    match std::env::var_os("PGE_LIBRARY") {
        Some(p) => PathBuf::from(p),
        None => PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/scripts")),
    }
}

/// An engine builder with every PGE plugin and the script library.
#[must_use]
pub fn default_engine() -> pge_engine::EngineBuilder {
    pge_engine::Engine::builder()
        .library(library_folder())
        .plugin(pge_lsystem::LSystemPlugin)
        .plugin(pge_turtle::TurtlePlugin)
        .plugin(pge_spacecol::SpaceColonizationPlugin)
        .plugin(pge_extruder::ExtruderPlugin)
        .plugin(pge_metaballs::MetaballsPlugin)
        .plugin(pge_canvas::CanvasPlugin)
        .plugin(pge_lod::LodPlugin)
}
