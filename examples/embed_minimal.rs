//! The smallest host program: build the engine with every plugin, run a script, write the
//! model as a `.glb`.
//!
//! ```text
//! cargo run --example embed_minimal -- scripts/examples/spiral.lua spiral.glb
//! ```

use pge_engine::SessionOptions;
use pge_engine::export::{ExportMeta, glb_bytes};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let script = args
        .next()
        .unwrap_or_else(|| "scripts/examples/spiral.lua".into());
    let out = args.next().unwrap_or_else(|| "embed_minimal.glb".into());

    let engine = pge::default_engine().build()?;
    let session = engine.session(SessionOptions {
        seed: 42,
        ..SessionOptions::default()
    })?;
    let generated = session.generate(script.as_ref(), &mut |_, _| {})?;
    let glb = glb_bytes(
        &generated.model,
        &ExportMeta {
            seed: 42,
            params: Vec::new(),
        },
    )?;
    std::fs::write(&out, glb)?;
    println!(
        "{out}: {} triangles in {:.3} s",
        generated.model.triangle_count(),
        generated.seconds
    );
    Ok(())
}
