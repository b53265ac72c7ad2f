//! `pge run`: run a script and write its model.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use pge_engine::export::Instancing;
use pge_engine::{Generated, Session};
use pge_forest::{ForestPlugin, ForestRun, VariantCache, VariantSharing};

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
    #[arg(long, value_name = "N", conflicts_with = "stages")]
    pub steps: Option<u32>,
    /// Write these growth stages (increasing step counts of a step-wise algorithm) as
    /// scenes named `step A`, `step B`, ... of one .glb; stage k is the model of --steps k.
    #[arg(long, value_name = "A,B,...", value_delimiter = ',', num_args = 1.., conflicts_with = "tile")]
    pub stages: Option<Vec<u32>>,
    /// Print statistics as one JSON object on stdout.
    #[arg(long)]
    pub stats: bool,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
    /// Write only tile I,J of a forest with `tile = T` (I along x, J along z, from 0 at the
    /// -x, -z corner). Repeatable with --out-dir: several tiles by one process.
    #[arg(long, value_name = "I,J", value_parser = parse_tile, action = clap::ArgAction::Append)]
    pub tile: Vec<(usize, usize)>,
    /// Write each --tile I,J to DIR/I_J.glb (the script's engine and the shared variants'
    /// description are read once for every tile; the files are those of --tile I,J -o
    /// DIR/I_J.glb).
    #[arg(long, value_name = "DIR", requires = "tile", conflicts_with = "output")]
    pub out_dir: Option<PathBuf>,
    /// Worker threads for parallel work (forest variants); default: every core. The output
    /// is byte-identical for any N.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// How instanced objects (a forest's trees) are written: gpu (EXT_mesh_gpu_instancing)
    /// or nodes (one node per instance).
    #[arg(long, value_enum, default_value_t = InstancingArg::Gpu)]
    pub instancing: InstancingArg,
    /// Keep the variants a forest's species scripts grow in DIR and read them back on the
    /// next run (the tiles of a world grow each variant once); the output is the same.
    #[arg(long, value_name = "DIR")]
    pub variant_cache: Option<PathBuf>,
    /// Write the variants of the forest's layers of a few variants once, into
    /// DIR/variants.bin and its glTF description DIR/variants.json, for tiles that refer to
    /// them (--variants DIR); no trees are placed.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["tile", "variants", "stages", "output"])]
    pub variants_out: Option<PathBuf>,
    /// Refer to the variants written by --variants-out DIR instead of growing them: the glb
    /// holds the terrain and the trees' placements, its variant meshes are in DIR/variants.bin
    /// (a second buffer, by a URI relative to the output). Only DIR/variants.json is read.
    #[arg(long, value_name = "DIR", conflicts_with = "stages")]
    pub variants: Option<PathBuf>,
}

/// `--instancing`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum InstancingArg {
    /// One node per variant with EXT_mesh_gpu_instancing.
    Gpu,
    /// One node per instance.
    Nodes,
}

fn parse_tile(s: &str) -> Result<(usize, usize), String> {
    let bad = || format!("'{s}' is not I,J (two integers >= 0)");
    let (i, j) = s.split_once(',').ok_or_else(bad)?;
    Ok((
        i.trim().parse().map_err(|_| bad())?,
        j.trim().parse().map_err(|_| bad())?,
    ))
}

/// Sets the global rayon pool to `threads` workers (every core when `None`) and starts them
/// now, while the session is made, rather than when the first parallel work would wait for
/// them (a few hundred microseconds).
pub fn set_threads(threads: Option<usize>) -> anyhow::Result<()> {
    match threads {
        Some(0) => crate::common::usage!("--threads must be at least 1"),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .context("cannot start the worker threads")?,
        // The default pool, started by a thread of its own: this one goes on making the
        // session while the pool counts the cores and starts its workers. Should no thread
        // start now, the pool starts on first use.
        None => {
            let _ = std::thread::Builder::new().spawn(|| rayon::spawn(|| {}));
        }
    }
    Ok(())
}

/// Like [`Session::generate`], for the forest the script returns (an error naming `option`
/// when it returns something else), or its tile `(i, j)`; `check` sees the declared
/// parameters before anything grows.
fn generate_forest(
    session: &Session,
    path: &Path,
    tile: Option<(usize, usize)>,
    option: &str,
    check: &dyn Fn(&[pge_engine::ParamInfo]) -> anyhow::Result<()>,
    progress: &mut dyn FnMut(u32, Option<u32>),
) -> anyhow::Result<Generated> {
    let t0 = Instant::now();
    let value = session.run_script(path)?;
    let mut algorithm = session.algorithm_from(value)?;
    let Some(forest) = ForestRun::of(&mut *algorithm) else {
        let tiled = if tile.is_some() { " with tile = T" } else { "" };
        anyhow::bail!(
            "{}: {option} needs a script that returns a forest (pge.Forest{tiled})",
            path.display()
        );
    };
    check(&session.declared_params())?;
    if let Some((i, j)) = tile
        && let Err(e) = forest.select_tile(i, j)
    {
        return Err(forest.engine_error(e).into());
    }
    let ctx = session.context();
    let planned = ctx.steps.or(algorithm.planned_steps());
    let mut model =
        pge_engine::algorithm::run(&mut *algorithm, &ctx, &mut |s| progress(s, planned))?;
    // The shared variants place nothing: they are not an empty model.
    if option != "--variants-out" {
        model.warn_if_empty(path);
    }
    Ok(Generated {
        model,
        params: session.declared_params(),
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The progress bar of a run, drawn on stderr; none with `--quiet`, or when stderr is not a
/// terminal (where indicatif would draw nothing either: a hidden bar still costs a short run
/// tens of microseconds to make and a clock read at every step).
pub(crate) fn progress_bar(quiet: bool) -> Option<ProgressBar> {
    if quiet || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} step {pos}{len_suffix} [{elapsed}]")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    Some(bar)
}

/// Runs `pge run`.
pub fn run(args: &RunArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    set_threads(args.threads)?;
    if let Some(dir) = &args.out_dir {
        return run_tiles(args, dir);
    }
    if args.tile.len() > 1 {
        crate::common::usage!(
            "{} tiles need --out-dir DIR (each is written to DIR/I_J.glb)",
            args.tile.len()
        );
    }
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
        crate::common::usage!("{}: the output must end in .glb or .obj", output.display());
    }
    if let Some(stages) = &args.stages {
        if ext.as_deref() != Some("glb") {
            crate::common::usage!(
                "{}: --stages writes one scene per stage, which needs a .glb output",
                output.display()
            );
        }
        return crate::stages::run_stages(args, stages, &output);
    }
    if args.variants.is_some() && ext.as_deref() != Some("glb") {
        crate::common::usage!(
            "{}: --variants writes a glb that refers to the shared variants, which needs a .glb \
             output",
            output.display()
        );
    }
    let prepared = prepare(args)?;
    run_one(args, &prepared, args.tile.first().copied(), &output, t0)
}

/// `pge run SCRIPT --tile I,J [--tile I,J]... --out-dir DIR`: the tiles one after the other
/// in this process, each in a session of its own (so each file is the one `--tile I,J -o
/// DIR/I_J.glb` writes), the engine and the shared variants' description made and read
/// once. A tile that fails stops the run with `tile I,J: ` before its error; the tiles
/// written before it stay (each file is whole).
fn run_tiles(args: &RunArgs, dir: &Path) -> anyhow::Result<()> {
    let prepared = prepare(args)?;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    for &(i, j) in &args.tile {
        let output = dir.join(format!("{i}_{j}.glb"));
        run_one(args, &prepared, Some((i, j)), &output, Instant::now())
            .with_context(|| format!("tile {i},{j}"))?;
    }
    Ok(())
}

/// What every tile of a run shares: the engine (with its forest plugin) and the shared
/// variants' description (`--variants DIR`), checked before anything runs.
struct Prepared {
    engine: pge_engine::Engine,
    shared: Option<pge_engine::export::SharedVariants>,
}

fn prepare(args: &RunArgs) -> anyhow::Result<Prepared> {
    let mut forest = match &args.variant_cache {
        Some(dir) => ForestPlugin::with_variant_cache(VariantCache::new(dir)),
        None => ForestPlugin::default(),
    };
    if args.variants_out.is_some() {
        forest = forest.sharing(VariantSharing::Write);
    }
    let shared = match &args.variants {
        Some(dir) => {
            forest = forest.sharing(VariantSharing::Refer);
            Some(crate::shared::read_variants(
                dir,
                &args.script.script,
                args.script.seed,
            )?)
        }
        None => None,
    };
    Ok(Prepared {
        engine: args.script.engine_with_forest(forest)?,
        shared,
    })
}

/// Runs the script once (tile `tile` of its forest, when given) and writes `output`.
fn run_one(
    args: &RunArgs,
    prepared: &Prepared,
    tile: Option<(usize, usize)>,
    output: &Path,
    t0: Instant,
) -> anyhow::Result<()> {
    let shared = &prepared.shared;
    let session = prepared
        .engine
        .session(args.script.session_options(args.steps))?;
    // Files a script writes (`img:save`) go beside the output.
    session.set_output_folder(output.parent().unwrap_or(std::path::Path::new("")))?;
    let bar = progress_bar(args.quiet);
    if let Some(bar) = &bar {
        bar.set_message(args.script.script.display().to_string());
    }
    let mut progress = |taken: u32, planned: Option<u32>| {
        if let Some(bar) = &bar {
            if let Some(n) = planned {
                bar.set_length(n as u64);
            }
            bar.set_position(taken as u64);
        }
    };
    let script = &args.script.script;
    let check_params = |params: &[pge_engine::ParamInfo]| match (&shared, &args.variants) {
        (Some(shared), Some(dir)) => crate::shared::check_params(shared, dir, script, params),
        _ => Ok(()),
    };
    let generated = match (tile, &args.variants_out, &args.variants) {
        (None, None, None) => session
            .generate(script, &mut progress)
            .map_err(anyhow::Error::from),
        (tile, None, None) => generate_forest(
            &session,
            script,
            tile,
            "--tile",
            &check_params,
            &mut progress,
        ),
        (tile, Some(_), _) => generate_forest(
            &session,
            script,
            tile,
            "--variants-out",
            &check_params,
            &mut progress,
        ),
        (tile, None, Some(_)) => generate_forest(
            &session,
            script,
            tile,
            "--variants",
            &check_params,
            &mut progress,
        ),
    };
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let mut generated = generated?;
    for w in &generated.model.stats.warnings {
        eprintln!("{w}");
    }
    let te = Instant::now();
    let meta = export_meta(args.script.seed, &generated.params);
    let instancing = match args.instancing {
        InstancingArg::Gpu => Instancing::Gpu,
        InstancingArg::Nodes => Instancing::Nodes,
    };
    let mut summary = None;
    let output = match (&args.variants_out, shared, &args.variants) {
        (Some(dir), _, _) => {
            let info = crate::shared::identity(script, &meta)?;
            crate::shared::write_variants(dir, &generated.model, info)?;
            summary = Some(crate::shared::summary(&generated.model));
            dir.join(crate::shared::DESCRIPTION)
        }
        (None, Some(shared), Some(dir)) => {
            let uri = crate::shared::relative_uri(dir, output)?;
            let bytes = pge_engine::export::glb_bytes_shared(
                &generated.model,
                &meta,
                instancing,
                shared,
                &uri,
            )?;
            crate::output::write_atomically(output, &bytes)?;
            output.to_path_buf()
        }
        _ => {
            write_model(&generated.model, &meta, output, instancing)?;
            output.to_path_buf()
        }
    };
    generated
        .model
        .stats
        .add_phase("export", te.elapsed().as_secs_f64());
    if let Some(summary) = &summary
        && !args.quiet
        && !args.stats
    {
        for line in crate::shared::summary_lines(summary) {
            println!("{line}");
        }
    }
    if args.stats {
        // The run ends with its file written: what follows only reports on it.
        let seconds = t0.elapsed().as_secs_f64();
        let m = &generated.model;
        let phases: serde_json::Map<String, serde_json::Value> = m
            .stats
            .phases
            .iter()
            .map(|(k, v)| (k.clone(), (*v).into()))
            .collect();
        // A tile that refers to shared variants counts what their instances draw and stand
        // for, as its glb's extras.pge.stats do, and names them.
        let (referred, [sv, st, sn, sl]) = match shared {
            Some(shared) => crate::shared::referred(m, shared),
            None => (Vec::new(), [0; 4]),
        };
        let mut stats = serde_json::json!({
            "vertices": m.vertex_count() as u64 + sv,
            "triangles": m.triangle_count() as u64 + st,
            "nodes": m.stats.nodes + sn,
            "leaves": m.stats.leaves + sl,
            "modules": m.stats.modules,
            "meshes": m.meshes.len(),
            "instances": m.forest.as_ref().map_or(m.instances.len() as u64, |f| f.instances),
            "seconds": seconds,
            "phases": phases,
            "warnings": m.stats.warnings,
            "output": output.display().to_string(),
        });
        if let Some((i, j)) = tile {
            stats["tile"] = serde_json::json!([i, j]);
        }
        if shared.is_some() {
            stats["variants"] = referred.into();
        }
        if let Some(summary) = summary {
            stats["variants"] = summary.into();
        }
        println!("{stats}");
    }
    Ok(())
}
