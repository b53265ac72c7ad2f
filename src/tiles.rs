//! `pge tiles`: the tiles of a forest, as JSON, for schedulers (one job per tile).

use clap::Args;
use pge_forest::ForestRun;

use crate::common::ScriptArgs;

/// Arguments of `pge tiles`.
#[derive(Args, Debug)]
pub struct TilesArgs {
    #[command(flatten)]
    pub script: ScriptArgs,
}

/// Runs the script and prints `[{"i", "j", "min": [x, z], "max": [x, z]}, ...]`.
pub fn tiles(args: &TilesArgs) -> anyhow::Result<()> {
    let engine = args.script.engine()?;
    let session = engine.session(args.script.session_options(None))?;
    let path = &args.script.script;
    let value = session.run_script(path)?;
    let mut algorithm = session.algorithm_from(value)?;
    let Some(forest) = ForestRun::of(&mut *algorithm) else {
        anyhow::bail!(
            "{}: pge tiles needs a script that returns a forest (pge.Forest with tile = T)",
            path.display()
        );
    };
    let tiles = forest
        .tiles(&session.context().budget)
        .map_err(|e| forest.engine_error(e))?;
    let out: Vec<serde_json::Value> = tiles
        .iter()
        .map(|t| {
            serde_json::json!({
                "i": t.i,
                "j": t.j,
                "min": t.rect.min,
                "max": t.rect.max,
            })
        })
        .collect();
    println!("{}", serde_json::Value::Array(out));
    Ok(())
}
