//! `pge derive`: print the string an L-system derives (docs/cli.md).

use std::io::{BufWriter, Write};

use clap::{Args, ValueEnum};
use pge_engine::{Engine, Location};

use crate::common::ScriptArgs;

/// How `pge derive` prints the string.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// Modules separated by one space: `Name` or `Name(p1,p2,...)`, brackets as modules.
    #[default]
    Text,
    /// The number of modules, brackets included.
    Count,
    /// An array of `{"name": ..., "params": ...}`.
    Json,
}

/// Arguments of `pge derive`.
#[derive(Args, Debug)]
pub struct DeriveArgs {
    #[command(flatten)]
    pub script: ScriptArgs,
    /// Derive this many steps instead of the system's `iterations`.
    #[arg(long, value_name = "N")]
    pub steps: Option<u32>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
}

/// Runs `pge derive`: the script must return an L-system (`pge.LSystem`). A system without
/// interpretation rules and rule functions is derived without interpretation.
pub fn derive(engine: &Engine, args: &DeriveArgs) -> anyhow::Result<()> {
    let session = engine.session(args.script.session_options(args.steps))?;
    let value = session.run_script(&args.script.script)?;
    let location = Location {
        file: args.script.script.to_string_lossy().replace('\\', "/"),
        line: None,
    };
    let derivation =
        pge_lsystem::derive_value(session.lua(), &value, &session.context(), &location)?;
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    match args.format {
        Format::Text => derivation.write_text(&mut out)?,
        Format::Count => writeln!(out, "{}", derivation.len())?,
        Format::Json => derivation.write_json(&mut out)?,
    }
    out.flush()?;
    Ok(())
}
