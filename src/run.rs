//! `pge run`: run a script and write its model.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use pge_engine::export::Prepared;
use pge_engine::{Algorithm, Generated, GrowOptions, Session};
use pge_forest::{ForestPlugin, ForestRun, VariantCache, VariantSharing};

use crate::common::{InstancingArg, ScriptArgs, progress_bar};
use crate::output::{export_meta, write_model};

mod plan;
mod report;
mod stages;

use plan::{Plan, Product, Target, Targets};
use report::Report;

/// Arguments of `pge run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    pub script: ScriptArgs,
    /// Output file: .glb (default: the script's name with .glb), .obj, .usda or .usdz.
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
    #[arg(long, value_name = "DIR", conflicts_with_all = ["tile", "variants", "stages", "steps", "output"])]
    pub variants_out: Option<PathBuf>,
    /// Refer to the variants written by --variants-out DIR instead of growing them: the glb
    /// holds the terrain and the trees' placements, its variant meshes are in DIR/variants.bin
    /// (a second buffer, by a URI relative to the output). Only DIR/variants.json is read.
    #[arg(long, value_name = "DIR", conflicts_with = "stages")]
    pub variants: Option<PathBuf>,
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

/// Runs the script and grows what it returns: for a run that needs a forest (`flag`), the
/// forest (an error naming the flag when it returns something else) or its tile `(i, j)`,
/// the shared variants' parameters checked before anything grows.
fn grow(
    session: &Session,
    path: &Path,
    product: &Product,
    tile: Option<(usize, usize)>,
    progress: &mut dyn FnMut(u32, Option<u32>),
) -> anyhow::Result<Generated> {
    let started = session.start(path)?;
    let Some(option) = product.forest_flag(tile) else {
        return Ok(started.grow(GrowOptions::default(), progress)?);
    };
    // The shared variants place nothing: they are not an empty model.
    let options = match product {
        Product::SharedVariants(_) => GrowOptions::default().empty_expected(),
        _ => GrowOptions::default(),
    };
    // The forest is reached through its typed handle, before anything grows.
    let prepare = |algorithm: &mut dyn Algorithm| -> anyhow::Result<()> {
        let Some(forest) = ForestRun::of(algorithm) else {
            let tiled = if tile.is_some() { " with tile = T" } else { "" };
            anyhow::bail!(
                "{}: {option} needs a script that returns a forest (pge.Forest{tiled})",
                path.display()
            );
        };
        if let Product::Referring { dir, shared } = product {
            crate::shared::check_params(shared, dir, path, &session.declared_params())?;
        }
        if let Some((i, j)) = tile
            && let Err(e) = forest.select_tile(i, j)
        {
            return Err(forest.engine_error(e).into());
        }
        Ok(())
    };
    started.grow_with(options, prepare, progress)
}

/// Runs `pge run`.
pub fn run(args: &RunArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    set_threads(args.threads)?;
    match Plan::decide(args)? {
        Plan::Stages { stages, output } => self::stages::run_stages(args, &stages, &output),
        Plan::Runs { product, targets } => {
            let engine = engine(args, &product)?;
            match targets {
                Targets::One(target) => run_one(args, &engine, &product, &target, t0, None),
                // The tiles one after the other in this process, each in a session of its
                // own (so each file is the one `--tile I,J -o DIR/I_J.glb` writes), the
                // engine and the shared variants' description made and read once. A tile
                // that fails stops the run with `tile I,J: ` before its error; the tiles
                // written before it stay (each file is whole). The skeletons' texts are
                // formatted once for every tile that writes the same variants.
                Targets::Tiles { dir, tiles } => {
                    std::fs::create_dir_all(&dir)
                        .with_context(|| format!("cannot create {}", dir.display()))?;
                    let mut prepared = Prepared::default();
                    for (i, j) in tiles {
                        let target = Target {
                            tile: Some((i, j)),
                            output: dir.join(format!("{i}_{j}.glb")),
                        };
                        let t = Instant::now();
                        run_one(args, &engine, &product, &target, t, Some(&mut prepared))
                            .with_context(|| format!("tile {i},{j}"))?;
                    }
                    Ok(())
                }
            }
        }
    }
}

/// The engine of every run of a plan, its forest plugin keeping variants in `--variant-cache`
/// and writing or referring to shared variants as `product` asks.
fn engine(args: &RunArgs, product: &Product) -> anyhow::Result<pge_engine::Engine> {
    let mut forest = match &args.variant_cache {
        Some(dir) => ForestPlugin::with_variant_cache(VariantCache::new(dir)),
        None => ForestPlugin::default(),
    };
    match product {
        Product::Model => {}
        Product::SharedVariants(_) => forest = forest.sharing(VariantSharing::Write),
        Product::Referring { .. } => forest = forest.sharing(VariantSharing::Refer),
    }
    args.script.engine_with_forest(forest)
}

/// Runs the script once (the tile of `target`, when given) and writes `target.output`, with
/// the skeletons' texts of `prepared` when given (which keeps the texts of this model's for
/// the next run).
fn run_one(
    args: &RunArgs,
    engine: &pge_engine::Engine,
    product: &Product,
    target: &Target,
    t0: Instant,
    prepared: Option<&mut Prepared>,
) -> anyhow::Result<()> {
    let Target { tile, output } = target;
    // The run's deadline and memory limit, which the export keeps to as well (at the line
    // that returned what grew): an export's own buffers (an .obj's text) must fit beside
    // the model.
    let limit = pge_engine::export::ExportLimit {
        ctx: pge_engine::RunContext {
            deadline: Some(
                pge_engine::clock::Instant::now()
                    + std::time::Duration::from_secs_f64(args.script.time_limit),
            ),
            budget: pge_engine::Budget::new(args.script.memory_limit.saturating_mul(1 << 20)),
            ..pge_engine::RunContext::default()
        },
        at: pge::Script::File(args.script.script.clone()).return_location(),
    };
    // Files a script writes (`img:save`) go beside the output.
    let folder = output.parent().unwrap_or(std::path::Path::new(""));
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
    let grown = match (product, tile) {
        // The single model: the library's entry point, which hosts call too.
        (Product::Model, None) => args
            .script
            .request(args.steps)
            .grow_model(engine, Some(folder), &mut progress)
            .map_err(anyhow::Error::from),
        _ => (|| {
            let session = engine.session(args.script.session_options(args.steps))?;
            session.set_output_folder(folder)?;
            let generated = grow(&session, script, product, *tile, &mut progress)?;
            let meta = export_meta(args.script.seed, &generated.params);
            Ok((generated.model, meta))
        })(),
    };
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let (mut model, meta) = grown?;
    for w in &model.stats.warnings {
        eprintln!("{w}");
    }
    let te = Instant::now();
    // The model's meshes, held while it is written out.
    let held = model.mesh_bytes();
    let _held = limit.ctx.budget.charge(held, &limit.at, || {
        format!("the model's meshes ({} MiB)", held.div_ceil(1 << 20))
    })?;
    let instancing = args.instancing.into();
    let mut summary = None;
    let written = match product {
        Product::SharedVariants(dir) => {
            limit.check()?;
            let info = crate::shared::identity(script, &meta)?;
            crate::shared::write_variants(dir, &model, info)?;
            summary = Some(crate::shared::summary(&model));
            dir.join(crate::shared::DESCRIPTION)
        }
        Product::Referring { dir, shared } => {
            let uri = crate::shared::relative_uri(dir, output)?;
            limit.check()?;
            let bytes =
                pge_engine::export::glb_bytes_shared(&model, &meta, instancing, shared, &uri)?;
            limit.check()?;
            crate::output::write_atomically(output, &bytes)?;
            output.clone()
        }
        Product::Model => {
            let none = Prepared::default();
            let prepared = match prepared {
                Some(prepared) => {
                    prepared.extend(&model)?;
                    &*prepared
                }
                None => &none,
            };
            write_model(&model, prepared, &meta, output, instancing, &limit)?;
            output.clone()
        }
    };
    model.stats.add_phase("export", te.elapsed().as_secs_f64());
    if let Some(summary) = &summary
        && !args.quiet
        && !args.stats
    {
        for line in crate::shared::summary_lines(summary) {
            crate::common::print_line(line)?;
        }
    }
    if args.stats {
        // The run ends with its file written: what follows only reports on it.
        let seconds = t0.elapsed().as_secs_f64();
        let shared = match product {
            Product::Referring { shared, .. } => Some(&**shared),
            _ => None,
        };
        let report = Report {
            model: &model,
            seconds,
            output: &written,
            tile: *tile,
            shared,
            summary,
        };
        crate::common::print_line(report.json())?;
    }
    Ok(())
}
