//! `pge run`: run a script and write its model.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use crate::common::ScriptArgs;
use crate::output::{export_meta, write_model};

/// Arguments of `pge run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    pub script: ScriptArgs,
    /// Output file: .glb (default: the script's name with .glb) or .obj.
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Run this many steps instead of the algorithm's own count.
    #[arg(long, value_name = "N")]
    pub steps: Option<u32>,
    /// Print statistics as one JSON object on stdout.
    #[arg(long)]
    pub stats: bool,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

fn progress_bar(quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} step {pos}{len_suffix} [{elapsed}]")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    bar
}

/// Runs `pge run`.
pub fn run(args: &RunArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let engine = args.script.engine()?;
    let session = engine.session(args.script.session_options(args.steps))?;
    let output = match &args.output {
        Some(o) => o.clone(),
        None => {
            PathBuf::from(args.script.script.file_stem().unwrap_or_default()).with_extension("glb")
        }
    };
    let ext = output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("glb" | "obj")) {
        anyhow::bail!("{}: the output must end in .glb or .obj", output.display());
    }
    let bar = progress_bar(args.quiet);
    bar.set_message(args.script.script.display().to_string());
    let generated = session.generate(&args.script.script, &mut |taken, planned| {
        if let Some(n) = planned {
            bar.set_length(n as u64);
        }
        bar.set_position(taken as u64);
    });
    bar.finish_and_clear();
    let mut generated = generated?;
    for w in &generated.model.stats.warnings {
        eprintln!("{w}");
    }
    let te = Instant::now();
    let meta = export_meta(args.script.seed, &generated.params);
    write_model(&generated.model, &meta, &output)?;
    generated
        .model
        .stats
        .add_phase("export", te.elapsed().as_secs_f64());
    if args.stats {
        let m = &generated.model;
        let phases: serde_json::Map<String, serde_json::Value> = m
            .stats
            .phases
            .iter()
            .map(|(k, v)| (k.clone(), (*v).into()))
            .collect();
        let stats = serde_json::json!({
            "vertices": m.vertex_count(),
            "triangles": m.triangle_count(),
            "nodes": m.stats.nodes,
            "leaves": m.stats.leaves,
            "modules": m.stats.modules,
            "meshes": m.meshes.len(),
            "instances": m.instances.len(),
            "seconds": t0.elapsed().as_secs_f64(),
            "phases": phases,
            "warnings": m.stats.warnings,
            "output": output.display().to_string(),
        });
        println!("{stats}");
    }
    Ok(())
}
