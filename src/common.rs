//! What every subcommand shares: the script options, engine limits, error printing.

use std::path::PathBuf;
use std::time::Duration;

use clap::Args;
use pge_engine::{Engine, EngineBuilder, SessionOptions};

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
    /// Wall-clock limit of the script and its algorithm, in seconds (> 0).
    #[arg(long, value_name = "SECONDS", default_value_t = 300.0, value_parser = parse_seconds)]
    pub time_limit: f64,
    /// Memory limit of the Lua state and of the plugins' buffers, in MiB (>= 1).
    #[arg(long, value_name = "MIB", default_value_t = 4096, value_parser = parse_mib)]
    pub memory_limit: usize,
}

/// `--time-limit`: a positive, finite number of seconds (otherwise a usage error, exit 2).
pub fn parse_seconds(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(s) if s.is_finite() && s > 0.0 => Ok(s),
        _ => Err(format!("'{text}' is not a positive number of seconds")),
    }
}

/// `--memory-limit`: a whole number of MiB, at least 1 (0 would mean "unlimited" to Lua
/// and "nothing" to the plugins, so it is a usage error, exit 2).
pub fn parse_mib(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(mib) if mib >= 1 => Ok(mib),
        _ => Err(format!("'{text}' is not a whole number of MiB, at least 1")),
    }
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
        Ok(self.limits(pge::engine_with_forest(forest)).build()?)
    }

    /// `builder` with these limits (`--time-limit`, `--memory-limit`).
    pub fn limits(&self, builder: EngineBuilder) -> EngineBuilder {
        // `--time-limit` is checked positive and finite when the arguments are parsed.
        builder
            .time_limit(Some(Duration::from_secs_f64(self.time_limit)))
            .memory_limit_mib(self.memory_limit)
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

/// A usage problem found after the arguments parsed (an impossible combination, an output
/// name the command cannot write): `pge` exits with 2 for it, as for clap's own errors.
#[derive(Debug)]
pub struct Usage(pub String);

impl std::fmt::Display for Usage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Usage {}

/// Returns early with a [`Usage`] error.
macro_rules! usage {
    ($($arg:tt)*) => {
        return Err(anyhow::Error::new($crate::common::Usage(format!($($arg)*))))
    };
}
pub(crate) use usage;

/// One line for the terminal: script errors are already `FILE:LINE: message`.
pub fn describe_error(e: &anyhow::Error) -> String {
    let mut s = e.to_string();
    for cause in e.chain().skip(1) {
        s.push_str(": ");
        s.push_str(&cause.to_string());
    }
    s.replace('\n', " ")
}

/// `--instancing`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum InstancingArg {
    /// One node per variant with EXT_mesh_gpu_instancing.
    Gpu,
    /// One node per instance.
    Nodes,
}

impl From<InstancingArg> for pge_engine::export::Instancing {
    fn from(arg: InstancingArg) -> pge_engine::export::Instancing {
        match arg {
            InstancingArg::Gpu => pge_engine::export::Instancing::Gpu,
            InstancingArg::Nodes => pge_engine::export::Instancing::Nodes,
        }
    }
}

/// The progress bar of a run, drawn on stderr; none with `--quiet`, or when stderr is not a
/// terminal (where indicatif would draw nothing either: a hidden bar still costs a short run
/// tens of microseconds to make and a clock read at every step).
pub(crate) fn progress_bar(quiet: bool) -> Option<indicatif::ProgressBar> {
    if quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        return None;
    }
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} {msg} step {pos}{len_suffix} [{elapsed}]",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    Some(bar)
}
