//! What every subcommand shares: the script options, engine limits, error printing.

use std::path::PathBuf;
use std::time::Duration;

use clap::Args;
use pge_engine::{Engine, SessionOptions};

/// Options of every command that runs a script.
#[derive(Args, Debug, Clone)]
pub struct ScriptArgs {
    /// The Lua script.
    pub script: PathBuf,
    /// Seed of every random draw.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Override a parameter declared with pge.params (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_set)]
    pub set: Vec<(String, String)>,
    /// Wall-clock limit of the script and its algorithm, in seconds.
    #[arg(long, value_name = "SECONDS", default_value_t = 300.0)]
    pub time_limit: f64,
    /// Memory limit of the Lua state, in MiB.
    #[arg(long, value_name = "MIB", default_value_t = 4096)]
    pub memory_limit: usize,
}

fn parse_set(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((k, v)) if !k.trim().is_empty() => Ok((k.trim().to_string(), v.to_string())),
        _ => Err(format!("'{s}' is not NAME=VALUE")),
    }
}

impl ScriptArgs {
    /// The engine with these limits.
    pub fn engine(&self) -> anyhow::Result<Engine> {
        self.engine_with_forest(pge_forest::ForestPlugin::default())
    }

    /// The engine with these limits and `forest` as its forest plugin.
    pub fn engine_with_forest(&self, forest: pge_forest::ForestPlugin) -> anyhow::Result<Engine> {
        let time = if self.time_limit > 0.0 && self.time_limit.is_finite() {
            Some(Duration::from_secs_f64(self.time_limit))
        } else {
            anyhow::bail!("--time-limit must be a positive number of seconds");
        };
        Ok(pge::engine_with_forest(forest)
            .time_limit(time)
            .memory_limit_mib(self.memory_limit)
            .build()?)
    }

    /// Session options for these arguments.
    pub fn session_options(&self, steps: Option<u32>) -> SessionOptions {
        SessionOptions {
            seed: self.seed,
            params: self.set.clone(),
            steps,
            cancel: None,
        }
    }
}

/// One line for the terminal: script errors are already `FILE:LINE: message`.
pub fn describe_error(e: &anyhow::Error) -> String {
    let mut s = e.to_string();
    for cause in e.chain().skip(1) {
        s.push_str(": ");
        s.push_str(&cause.to_string());
    }
    s.replace('\n', " ")
}
