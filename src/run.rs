//! `pge run`: run a script and write its model.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use pge_engine::export::{ExportMeta, glb_bytes, glb_stages_bytes, obj_files};
use pge_engine::geometry::Model;
use pge_engine::{Error, Location, Step};

use crate::common::ScriptArgs;

/// Arguments of `pge run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    pub script: ScriptArgs,
    /// Output file: .glb (default: the script's name with .glb) or .obj.
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Run this many steps instead of the algorithm's own count.
    #[arg(long, value_name = "N", conflicts_with = "stages")]
    pub steps: Option<u32>,
    /// Write these growth stages (increasing step counts of a step-wise algorithm) as
    /// scenes named `step A`, `step B`, ... of one .glb; stage k is the model of --steps k.
    #[arg(long, value_name = "A,B,...", value_delimiter = ',', num_args = 1..)]
    pub stages: Option<Vec<u32>>,
    /// Print statistics as one JSON object on stdout.
    #[arg(long)]
    pub stats: bool,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Writes `bytes` to `path` through a temporary file in the same folder, so that a failure
/// never leaves a half-written file.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut tmp = tempfile::NamedTempFile::new_in(&dir)
        .with_context(|| format!("cannot write in {}", dir.display()))?;
    tmp.write_all(bytes)
        .with_context(|| format!("cannot write {}", path.display()))?;
    tmp.persist(path)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// The output file: `-o`, or the script's stem with `.glb`; it must end in .glb or .obj.
fn output_path(args: &RunArgs) -> anyhow::Result<PathBuf> {
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
    Ok(output)
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

/// The most steps a stage may ask for.
pub const STAGE_CAP: u32 = 100_000;

/// Where an error about the whole run points: the script's last `return` line (the value
/// that grows), or the script alone.
fn return_location(script: &Path) -> Location {
    let file = script.to_string_lossy().replace('\\', "/");
    let line = std::fs::read_to_string(script).ok().and_then(|text| {
        text.lines()
            .enumerate()
            .filter(|(_, l)| l.trim_start().starts_with("return"))
            .map(|(i, _)| i as u32 + 1)
            .last()
    });
    Location { file, line }
}

/// Checks a `--stages` list: increasing, within [`STAGE_CAP`].
fn check_stages(stages: &[u32]) -> Result<(), String> {
    if stages.is_empty() {
        return Err("--stages needs at least one step count".into());
    }
    for w in stages.windows(2) {
        if w[1] <= w[0] {
            return Err(format!(
                "--stages must be increasing step counts, got {} after {}",
                w[1], w[0]
            ));
        }
    }
    let last = stages[stages.len() - 1];
    if last > STAGE_CAP {
        return Err(format!(
            "--stages must be step counts between 0 and {STAGE_CAP} (the step cap), got {last}"
        ));
    }
    Ok(())
}

/// The named model of every stage, and the script's declared parameters.
type Stages = (Vec<(String, Model)>, Vec<pge_engine::ParamInfo>);

/// Runs the script's algorithm once through every stage, keeping the model of each.
fn generate_stages(args: &RunArgs, stages: &[u32], bar: &ProgressBar) -> anyhow::Result<Stages> {
    let script = &args.script.script;
    check_stages(stages).map_err(|m| Error::script(return_location(script), m))?;
    let last = stages[stages.len() - 1];
    let engine = args.script.engine()?;
    let session = engine.session(args.script.session_options(Some(last)))?;
    let value = session.run_script(script)?;
    let mut algorithm = session.algorithm_from(value)?;
    if algorithm.planned_steps() == Some(0) {
        return Err(Error::script(
            return_location(script),
            format!(
                "--stages needs a step-wise algorithm (an L-system, a space colonization, a \
                 growth, a pge.Algorithm), but the script returned a finished {}",
                algorithm.name()
            ),
        )
        .into());
    }
    let ctx = session.context();
    bar.set_length(u64::from(last));
    algorithm.init(&ctx)?;
    let mut taken = 0u32;
    let mut done = false;
    let mut models = Vec::with_capacity(stages.len());
    for &stage in stages {
        while !done && taken < stage {
            done = algorithm.step(&ctx)? == Step::Done;
            taken += 1;
            bar.set_position(u64::from(taken));
        }
        models.push((format!("step {stage}"), algorithm.finish(&ctx)?));
    }
    Ok((models, session.declared_params()))
}

/// `pge run --stages`: every stage a scene of one .glb.
fn run_stages(args: &RunArgs, stages: &[u32], output: &Path) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let bar = progress_bar(args.quiet);
    bar.set_message(args.script.script.display().to_string());
    let generated = generate_stages(args, stages, &bar);
    bar.finish_and_clear();
    let (models, params) = generated?;
    let meta = ExportMeta {
        seed: args.script.seed,
        params: params
            .iter()
            .map(|p| (p.name.clone(), p.value.to_json()))
            .collect(),
    };
    for (_, m) in &models {
        for w in &m.stats.warnings {
            eprintln!("{w}");
        }
    }
    write_atomically(output, &glb_stages_bytes(&models, &meta)?)?;
    if args.stats {
        let list: Vec<serde_json::Value> = models
            .iter()
            .map(|(name, m)| {
                serde_json::json!({
                    "name": name,
                    "vertices": m.vertex_count(),
                    "triangles": m.triangle_count(),
                    "nodes": m.stats.nodes,
                    "leaves": m.stats.leaves,
                })
            })
            .collect();
        let m = models.last().map(|(_, m)| m);
        let stats = serde_json::json!({
            "vertices": m.map_or(0, Model::vertex_count),
            "triangles": m.map_or(0, Model::triangle_count),
            "nodes": m.map_or(0, |m| m.stats.nodes),
            "leaves": m.map_or(0, |m| m.stats.leaves),
            "modules": m.map_or(0, |m| m.stats.modules),
            "instances": m.map_or(0, |m| m.instances.len()),
            "seconds": t0.elapsed().as_secs_f64(),
            "stages": list,
            "output": output.display().to_string(),
        });
        println!("{stats}");
    }
    Ok(())
}

/// Runs `pge run`.
pub fn run(args: &RunArgs) -> anyhow::Result<()> {
    if let Some(stages) = &args.stages {
        let output = output_path(args)?;
        if output
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            != Some("glb".into())
        {
            anyhow::bail!(
                "{}: --stages writes one scene per stage, which needs a .glb output",
                output.display()
            );
        }
        return run_stages(args, stages, &output);
    }
    let t0 = Instant::now();
    let engine = args.script.engine()?;
    let session = engine.session(args.script.session_options(args.steps))?;
    let output = output_path(args)?;
    let ext = output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
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
    let meta = ExportMeta {
        seed: args.script.seed,
        params: generated
            .params
            .iter()
            .map(|p| (p.name.clone(), p.value.to_json()))
            .collect(),
    };
    if ext.as_deref() == Some("obj") {
        let stem = output
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let mtl = format!("{stem}.mtl");
        let files = obj_files(&generated.model, &mtl, &stem)?;
        let dir = output.parent().map(Path::to_path_buf).unwrap_or_default();
        for (name, png) in &files.textures {
            write_atomically(&dir.join(name), png)?;
        }
        write_atomically(&dir.join(&mtl), files.mtl.as_bytes())?;
        write_atomically(&output, files.obj.as_bytes())?;
    } else {
        write_atomically(&output, &glb_bytes(&generated.model, &meta)?)?;
    }
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
