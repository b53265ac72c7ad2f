//! `pge run --stages`: one individual at several growth stages, each a scene of one glb or a
//! variant of one USD layer.

use std::path::Path;
use std::time::Instant;

use indicatif::ProgressBar;
use pge::embed::Models;
use pge_engine::export::{Instancing, usd_stages_files};

use super::RunArgs;
use crate::common::progress_bar;
use crate::output::{usd_folder, usd_kind, write_atomically, write_usd};

/// `pge run --stages`: every stage a scene of one .glb (or a variant of one USD layer), grown by the library's
/// [`pge::Request::grow`].
pub fn run_stages(args: &RunArgs, stages: &[u32], output: &Path) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let bar = progress_bar(args.quiet).unwrap_or_else(ProgressBar::hidden);
    bar.set_message(args.script.script.display().to_string());
    let mut request = args.script.request(None);
    request.stages = Some(stages.to_vec());
    let mut progress = |taken: u32, planned: Option<u32>| {
        if let Some(n) = planned {
            bar.set_length(u64::from(n));
        }
        bar.set_position(u64::from(taken));
    };
    let grown = request
        .engine()
        .and_then(|engine| request.grow(&engine, None, &mut progress));
    bar.finish_and_clear();
    let grown = grown?;
    for w in grown.warnings() {
        eprintln!("{w}");
    }
    match &grown.models {
        Models::Stages(models) if usd_kind(output).is_some() => write_usd(
            &usd_stages_files(models, &grown.meta, &usd_folder(output))?,
            output,
        )?,
        _ => write_atomically(output, &grown.glb(Instancing::Gpu)?)?,
    }
    if args.stats {
        let mut stats = grown.stats(t0.elapsed().as_secs_f64());
        stats["output"] = output.display().to_string().into();
        crate::common::print_line(stats)?;
    }
    Ok(())
}
