//! `pge run --stages`: one individual at several growth stages, each a scene of one glb.

use std::path::Path;
use std::time::Instant;

use indicatif::ProgressBar;
use pge_engine::export::{glb_stages_bytes, usd_stages_files};
use pge_engine::geometry::Model;
use pge_engine::{Error, Location, Step};

use crate::output::{export_meta, usd_folder, usd_kind, write_atomically, write_usd};
use crate::run::{RunArgs, progress_bar};

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
    let mut algorithm = session.start(script)?.algorithm()?;
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
        let mut model = algorithm.finish(&ctx)?;
        model.remove_unusable_triangles();
        model.warn_if_empty(&args.script.script);
        models.push((format!("step {stage}"), model));
    }
    Ok((models, session.declared_params()))
}

/// `pge run --stages`: every stage a scene of one .glb, or a variant of one USD layer.
pub fn run_stages(args: &RunArgs, stages: &[u32], output: &Path) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let bar = progress_bar(args.quiet).unwrap_or_else(ProgressBar::hidden);
    bar.set_message(args.script.script.display().to_string());
    let generated = generate_stages(args, stages, &bar);
    bar.finish_and_clear();
    let (models, params) = generated?;
    let meta = export_meta(args.script.seed, &params);
    for (_, m) in &models {
        for w in &m.stats.warnings {
            eprintln!("{w}");
        }
    }
    if usd_kind(output).is_some() {
        write_usd(
            &usd_stages_files(&models, &meta, &usd_folder(output))?,
            output,
        )?;
    } else {
        write_atomically(output, &glb_stages_bytes(&models, &meta)?)?;
    }
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
