//! `pge tiles`: the tiles of a forest, as JSON, for schedulers (one job per tile).

use clap::Args;

use crate::common::ScriptArgs;

/// Arguments of `pge tiles`.
#[derive(Args, Debug)]
pub struct TilesArgs {
    #[command(flatten)]
    pub script: ScriptArgs,
}

/// Runs the script and prints `[{"i", "j", "min": [x, z], "max": [x, z]}, ...]`.
pub fn tiles(args: &TilesArgs) -> anyhow::Result<()> {
    let tiles = pge::tiles(&args.script.request(None))?;
    let out: Vec<serde_json::Value> = tiles
        .iter()
        .map(|t| {
            serde_json::json!({
                "i": t.i,
                "j": t.j,
                "min": t.min,
                "max": t.max,
            })
        })
        .collect();
    crate::common::print_line(serde_json::Value::Array(out))?;
    Ok(())
}
