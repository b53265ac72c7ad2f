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

pub(crate) fn parse_set(s: &str) -> Result<(String, String), String> {
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
        self.request(None).limits(builder)
    }

    /// The library's request for these arguments and `steps` (`--steps`); the threads are
    /// the global pool's, set by the command.
    pub fn request(&self, steps: Option<u32>) -> pge::Request {
        let mut request = pge::Request::new(pge::Script::File(self.script.clone()));
        request.params = self.set.clone();
        request.seed = self.seed;
        request.steps = steps;
        // `--time-limit` is checked positive and finite when the arguments are parsed.
        request.time_limit = Duration::from_secs_f64(self.time_limit);
        request.memory_limit_mib = self.memory_limit;
        request
    }

    /// Session options for these arguments.
    pub fn session_options(&self, steps: Option<u32>) -> SessionOptions {
        SessionOptions {
            seed: self.seed,
            params: self.set.clone(),
            steps,
            ..SessionOptions::default()
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

/// Writes `text` and a newline to stdout, an error when it cannot (a closed pipe, as in
/// `pge tiles ... | head`: [`is_closed_stdout`] tells `main` to exit quietly then).
pub fn print_line(text: impl std::fmt::Display) -> anyhow::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{text}")?;
    out.flush()?;
    Ok(())
}

/// Whether `e` comes from writing to a stdout whose reader has gone (`EPIPE`): the reader
/// took what it wanted, so the command stops without a message.
pub fn is_closed_stdout(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// One line for the terminal: script errors are already `FILE:LINE: message`.
pub fn describe_error(e: &anyhow::Error) -> String {
    let mut s = e.to_string();
    for cause in e.chain().skip(1) {
        // An error that shows its cause in its own message (`invalid geometry: X`) is not
        // followed by the cause again.
        let cause = cause.to_string();
        if !s.contains(&cause) {
            s.push_str(": ");
            s.push_str(&cause);
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cause_already_in_the_message_is_not_repeated() {
        let io = || std::io::Error::other("uvs[18] is not a finite number");
        let e =
            anyhow::Error::new(io()).context("invalid geometry: uvs[18] is not a finite number");
        assert_eq!(
            describe_error(&e),
            "invalid geometry: uvs[18] is not a finite number"
        );
        let e = anyhow::Error::new(io()).context("cannot write tree.glb");
        assert_eq!(
            describe_error(&e),
            "cannot write tree.glb: uvs[18] is not a finite number"
        );
    }
}
