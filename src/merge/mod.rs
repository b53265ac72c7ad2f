//! `pge merge`: the tiles of a world directory (written by `pge-world`) as one glb, every
//! variant mesh written once and instanced across the tiles. Tiles may be standalone glbs or
//! refer to the world's shared variants (`variants.bin`, by a relative URI): those are read
//! once, however many tiles place them.

mod world;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use clap::Args;
use pge_engine::export::{ExportMeta, Instancing};
use serde_json::{Map, Value};

use crate::common::InstancingArg;
use crate::output::write_atomically;
use crate::world::{Manifest, TileEntry, sha256_hex};
use world::World;

/// Arguments of `pge merge`.
#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The world directory: `DIR/world.json` and `DIR/tiles/I_J.glb`.
    pub dir: PathBuf,
    /// The .glb to write (default: DIR/world.glb), or a .usda or .usdz.
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Only the tiles of this rectangle, corners included: I0,J0 to I1,J1.
    #[arg(long, value_name = "I0,J0,I1,J1", value_parser = parse_rect)]
    pub rect: Option<[u64; 4]>,
    /// How the trees are written: gpu (EXT_mesh_gpu_instancing) or nodes.
    #[arg(long, value_enum, default_value_t = InstancingArg::Gpu)]
    pub instancing: InstancingArg,
    /// Wall-clock limit of the merge, in seconds (> 0).
    #[arg(long, value_name = "SECONDS", default_value_t = 300.0, value_parser = crate::common::parse_seconds)]
    pub time_limit: f64,
    /// Memory limit of the merge, in MiB (>= 1): the files it reads are charged to it.
    #[arg(long, value_name = "MIB", default_value_t = 4096, value_parser = crate::common::parse_mib)]
    pub memory_limit: usize,
}

fn parse_rect(s: &str) -> Result<[u64; 4], String> {
    let bad = || format!("'{s}' is not I0,J0,I1,J1 (four integers >= 0, I0 <= I1, J0 <= J1)");
    let v: Vec<u64> = s
        .split(',')
        .map(|x| x.trim().parse().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [i0, j0, i1, j1] if i0 <= i1 && j0 <= j1 => Ok([i0, j0, i1, j1]),
        _ => Err(bad()),
    }
}
/// Runs `pge merge`.
pub fn merge(args: &MergeArgs) -> anyhow::Result<()> {
    let Manifest {
        seed,
        params,
        tiles,
        variants,
        complete,
        ..
    } = Manifest::read_existing(&args.dir)?;
    if !complete {
        bail!(
            "{}: the world is not complete: run pge-world again on this directory to finish it",
            args.dir.join("world.json").display()
        );
    }
    let params: Vec<(String, Value)> = params.into_iter().collect();
    let chosen: Vec<&TileEntry> = tiles
        .iter()
        .filter(|t| match args.rect {
            Some([i0, j0, i1, j1]) => (i0..=i1).contains(&t.i) && (j0..=j1).contains(&t.j),
            None => true,
        })
        .collect();
    if chosen.is_empty() {
        bail!(
            "{}: no tile of the world is in the rectangle",
            args.dir.display()
        );
    }
    let mut files = Files::new(&args.dir, args.time_limit, args.memory_limit)?;
    let mut seen = std::collections::HashSet::new();
    if let Some(t) = tiles.iter().find(|t| !seen.insert((t.i, t.j))) {
        bail!(
            "{}: tile {},{} is listed twice (run pge-world again to rewrite it)",
            args.dir.join("world.json").display(),
            t.i,
            t.j
        );
    }
    let mut world = World::default();
    if let Some(shared) = &variants {
        let (file, sha256, description) = (&shared.file, &shared.sha256, &shared.description);
        let (key, bytes) = files.read(&args.dir.join(file))?;
        if sha256_hex(&bytes) != *sha256 {
            bail!(
                "{}: the file does not match world.json (run pge-world again to rewrite it)",
                key.display()
            );
        }
        world.external.insert(key.clone(), Arc::new(bytes));
        // The variant meshes' extras (skeletons) are in the description, not in the tiles.
        if let Some(description) = description {
            let (path, text) = files.read(&args.dir.join(description))?;
            let json: Value = serde_json::from_slice(&text)
                .with_context(|| format!("{}: not a variants description", path.display()))?;
            let extras = json
                .get("meshes")
                .and_then(Value::as_array)
                .map(|meshes| {
                    meshes
                        .iter()
                        .map(|m| match m.pointer("/extras/pge") {
                            Some(Value::Object(e)) => e.clone(),
                            _ => Map::new(),
                        })
                        .collect()
                })
                .unwrap_or_default();
            world.shared_extras.insert(key, extras);
        }
    }
    for t in &chosen {
        let (path, bytes) = files.read(&args.dir.join(&t.file))?;
        if sha256_hex(&bytes) != t.sha256 {
            bail!(
                "{}: the file does not match world.json (run pge-world again to regrow it)",
                path.display()
            );
        }
        world
            .add_tile(&bytes, (t.i, t.j), &mut files, &path)
            .with_context(|| path.display().to_string())?;
    }
    files.check_time(&args.dir.join("world.json"))?;
    let model = world.finish();
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| args.dir.join("world.glb"));
    let instancing: Instancing = args.instancing.into();
    let meta = ExportMeta { seed, params };
    if crate::output::usd_kind(&output).is_some() {
        let folder = crate::output::usd_folder(&output);
        let files = pge_engine::export::usd_files(&model, &meta, &folder)?;
        return crate::output::write_usd(&files, &output);
    }
    let bytes = pge_engine::export::glb_bytes_with(&model, &meta, instancing)?;
    write_atomically(&output, &bytes)
}

/// How `pge merge` reads the world's files (the manifest's entries, the buffers the tiles
/// name): each path resolved first (its links and `..` followed), then required to be a
/// regular file inside the world directory, read within the run's time, and charged to its
/// memory limit (the merged model holds about what the files hold).
pub(super) struct Files {
    /// The world directory, resolved.
    root: PathBuf,
    start: Instant,
    time_limit: Duration,
    /// Bytes left of the memory limit.
    left: u64,
    limit: usize,
}

impl Files {
    fn new(dir: &Path, seconds: f64, mib: usize) -> anyhow::Result<Files> {
        let root = std::fs::canonicalize(dir)
            .with_context(|| format!("cannot resolve {}", dir.display()))?;
        let limit = mib.saturating_mul(1 << 20);
        Ok(Files {
            root,
            start: Instant::now(),
            time_limit: Duration::from_secs_f64(seconds),
            left: limit as u64,
            limit,
        })
    }

    /// The resolved path of `path` and its bytes.
    pub(super) fn read(&mut self, path: &Path) -> anyhow::Result<(PathBuf, Vec<u8>)> {
        self.check_time(path)?;
        let resolved = std::fs::canonicalize(path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        if !resolved.starts_with(&self.root) {
            bail!(
                "{}: leads outside the world directory {}",
                path.display(),
                self.root.display()
            );
        }
        // Checked before opening too: opening a FIFO would wait for a writer.
        let regular = |meta: std::io::Result<std::fs::Metadata>| -> anyhow::Result<u64> {
            let meta = meta.with_context(|| format!("cannot read {}", path.display()))?;
            if !meta.is_file() {
                bail!("{}: not a regular file", path.display());
            }
            Ok(meta.len())
        };
        regular(std::fs::metadata(&resolved))?;
        let mut file = std::fs::File::open(&resolved)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let len = regular(file.metadata())?;
        if len > self.left {
            return Err(pge_engine::Error::MemoryLimit {
                location: location(path),
                limit: self.limit,
                what: Some(format!(
                    "reading {} needs {} MiB more",
                    path.display(),
                    len.div_ceil(1 << 20)
                )),
            }
            .into());
        }
        self.left -= len;
        let mut bytes = Vec::with_capacity(len as usize);
        std::io::Read::read_to_end(&mut std::io::Read::take(&mut file, len), &mut bytes)
            .with_context(|| format!("cannot read {}", path.display()))?;
        Ok((resolved, bytes))
    }

    /// A time limit error at `path` when the run's time is up.
    pub(super) fn check_time(&self, path: &Path) -> anyhow::Result<()> {
        if self.start.elapsed() > self.time_limit {
            return Err(pge_engine::Error::TimeLimit {
                location: location(path),
            }
            .into());
        }
        Ok(())
    }
}

fn location(path: &Path) -> pge_engine::Location {
    pge_engine::Location {
        file: path.display().to_string(),
        line: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rectangle_is_four_ordered_integers() {
        assert_eq!(parse_rect("0,1,2,3"), Ok([0, 1, 2, 3]));
        assert!(parse_rect("2,0,1,3").is_err());
        assert!(parse_rect("0,0,1").is_err());
        assert!(parse_rect("a,0,1,1").is_err());
    }
}
