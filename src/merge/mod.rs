//! `pge merge`: the tiles of a world directory (written by `pge-world`) as one glb, every
//! variant mesh written once and instanced across the tiles. Tiles may be standalone glbs or
//! refer to the world's shared variants (`variants.bin`, by a relative URI): those are read
//! once, however many tiles place them.

mod world;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, bail};
use clap::Args;
use pge_engine::export::{ExportMeta, Instancing};
use serde_json::{Map, Value};

use crate::output::write_atomically;
use crate::run::InstancingArg;
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
    let mut world = World::default();
    if let Some(shared) = &variants {
        let (file, sha256, description) = (&shared.file, &shared.sha256, &shared.description);
        let path = args.dir.join(file);
        let bytes =
            std::fs::read(&path).with_context(|| format!("cannot read {}", path.display()))?;
        if sha256_hex(&bytes) != *sha256 {
            bail!(
                "{}: the file does not match world.json (run pge-world again to rewrite it)",
                path.display()
            );
        }
        let key = normal_path(&path)?;
        world.external.insert(key.clone(), Arc::new(bytes));
        // The variant meshes' extras (skeletons) are in the description, not in the tiles.
        if let Some(description) = description {
            let path = args.dir.join(description);
            let text =
                std::fs::read(&path).with_context(|| format!("cannot read {}", path.display()))?;
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
        let path = args.dir.join(&t.file);
        let bytes =
            std::fs::read(&path).with_context(|| format!("cannot read {}", path.display()))?;
        if sha256_hex(&bytes) != t.sha256 {
            bail!(
                "{}: the file does not match world.json (run pge-world again to regrow it)",
                path.display()
            );
        }
        let folder = path.parent().unwrap_or(Path::new("."));
        world
            .add_tile(&bytes, (t.i, t.j), folder)
            .with_context(|| path.display().to_string())?;
    }
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

/// `path` made absolute, `.` and `..` folded (lexically), so one file has one key.
fn normal_path(path: &Path) -> anyhow::Result<PathBuf> {
    let absolute =
        std::path::absolute(path).with_context(|| format!("cannot resolve {}", path.display()))?;
    let mut out = PathBuf::new();
    for c in absolute.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    Ok(out)
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
