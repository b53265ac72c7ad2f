//! `pge tiles`: the tiles of a forest, as JSON, for schedulers (one job per tile).

use clap::Args;
use pge_engine::mlua::{ObjectLike, Table, Value};

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
    let Value::UserData(ud) = &value else {
        anyhow::bail!(
            "{}: pge tiles needs a script that returns a forest (pge.Forest with tile = T)",
            path.display()
        );
    };
    if !matches!(ud.get::<Value>("tiles"), Ok(Value::Function(_))) {
        anyhow::bail!(
            "{}: pge tiles needs a script that returns a forest (pge.Forest with tile = T)",
            path.display()
        );
    }
    let list: Table = ud
        .call_method("tiles", ())
        .map_err(|e| pge_engine::lua::to_engine_error(session.lua(), e))?;
    let read = |t: &Table| -> pge_engine::mlua::Result<serde_json::Value> {
        let min: Table = t.get("min")?;
        let max: Table = t.get("max")?;
        Ok(serde_json::json!({
            "i": t.get::<u64>("i")?,
            "j": t.get::<u64>("j")?,
            "min": [min.get::<f64>(1)?, min.get::<f64>(2)?],
            "max": [max.get::<f64>(1)?, max.get::<f64>(2)?],
        }))
    };
    let mut out = Vec::new();
    for t in list.sequence_values::<Table>() {
        let t = t.map_err(|e| pge_engine::lua::to_engine_error(session.lua(), e))?;
        out.push(read(&t).map_err(|e| pge_engine::lua::to_engine_error(session.lua(), e))?);
    }
    println!("{}", serde_json::Value::Array(out));
    Ok(())
}
