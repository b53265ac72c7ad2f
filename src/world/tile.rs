//! What `pge world` reads in a tile's .glb (its JSON chunk): the seed, parameters and
//! forest it was grown with, and whether it refers to the world's shared variants.

use std::path::Path;

use anyhow::{Context, bail};
use serde_json::{Map, Value};

use super::manifest::{Manifest, TileEntry, VARIANTS_BIN, sha256_hex, tile_file};

/// A tile of a world's grid: `(i, j, min, max)`, the bounds (x, z) in metres.
pub type GridTile = (u64, u64, [f64; 2], [f64; 2]);

/// A tile file as `pge run --tile I,J` wrote it.
pub struct TileFile {
    pub seed: u64,
    pub params: Map<String, Value>,
    /// The world's size (x, z) and tile side, in metres.
    pub size: [f64; 2],
    pub tile: f64,
    pub index: (u64, u64),
    pub instances: u64,
    /// Whether it refers to `../variants.bin` rather than carries its variants.
    pub shared: bool,
}

impl TileFile {
    /// The tile in `bytes` (read from `path`, named in errors).
    pub fn parse(bytes: &[u8], path: &Path) -> anyhow::Result<TileFile> {
        let not_a_tile = || format!("{}: not a tile of a forest", path.display());
        let glb = gltf::binary::Glb::from_slice(bytes).with_context(not_a_tile)?;
        let json: Value = serde_json::from_slice(&glb.json).with_context(not_a_tile)?;
        let pge = json.pointer("/extras/pge").with_context(not_a_tile)?;
        let forest = pge.get("forest").with_context(not_a_tile)?;
        let pair = |v: Option<&Value>| -> Option<[f64; 2]> {
            let a = v?.as_array()?;
            Some([a.first()?.as_f64()?, a.get(1)?.as_f64()?])
        };
        let index = forest
            .get("tileIndex")
            .and_then(Value::as_array)
            .and_then(|a| Some((a.first()?.as_u64()?, a.get(1)?.as_u64()?)));
        let (Some(seed), Some(size), Some(tile), Some(index)) = (
            pge.get("seed").and_then(Value::as_u64),
            pair(forest.get("size")),
            forest.get("tile").and_then(Value::as_f64),
            index,
        ) else {
            bail!(not_a_tile());
        };
        let shared = json
            .get("buffers")
            .and_then(Value::as_array)
            .is_some_and(|b| {
                b.iter().any(|b| {
                    b.get("uri").and_then(Value::as_str) == Some(&format!("../{VARIANTS_BIN}"))
                })
            });
        Ok(TileFile {
            seed,
            params: pge
                .get("params")
                .and_then(Value::as_object)
                .cloned()
                .unwrap_or_default(),
            size,
            tile,
            index,
            instances: forest.get("instances").and_then(Value::as_u64).unwrap_or(0),
            shared,
        })
    }

    /// Every tile of its world, `(i, j, min, max)`, `i` fastest (the forest's own grid).
    pub fn grid(&self) -> anyhow::Result<Vec<GridTile>> {
        let forest = pge_forest::Forest::new(self.size, 0, Some(self.tile))?;
        let tiles = forest.tiles().context("a forest without tiles")?;
        Ok(tiles
            .iter()
            .map(|t| (t.i as u64, t.j as u64, t.rect.min, t.rect.max))
            .collect())
    }
}

/// Whether a parameter's recorded `value` is what `--set NAME=text` gives it.
pub fn matches(value: Option<&Value>, text: &str) -> bool {
    match value {
        Some(Value::Bool(b)) => text.trim().eq_ignore_ascii_case(&b.to_string()),
        Some(Value::Number(n)) => text.trim().parse::<f64>().ok() == n.as_f64(),
        Some(Value::String(s)) => s == text,
        _ => false,
    }
}

/// The manifest entry of tile `(i, j)`, read from its file in `dir`, after checking that it
/// is a tile of the world `manifest` records: its index, seed, `--set` values, parameters
/// (when known) and form (referring to the shared variants when the world has them).
/// `Ok(None)` when there is no file.
pub fn entry_of(
    dir: &Path,
    manifest: &Manifest,
    (i, j): (u64, u64),
) -> anyhow::Result<Option<(TileEntry, Map<String, Value>)>> {
    let file = tile_file(i, j);
    let path = dir.join(&file);
    let Some(bytes) = super::manifest::read_plain(&path)? else {
        if path.symlink_metadata().is_ok() {
            bail!(
                "{}: not a regular file; delete it to grow it again",
                path.display()
            );
        }
        return Ok(None);
    };
    let tile = TileFile::parse(&bytes, &path)?;
    let shared = manifest.variants.is_some();
    if tile.shared != shared {
        let (form, other) = if tile.shared {
            ("refers to shared variants", "without")
        } else {
            ("carries its variants", "with")
        };
        bail!(
            "{}: the tile {form}; run pge-world {other} --standalone-tiles, or delete it to grow \
             it again",
            path.display()
        );
    }
    let same = tile.index == (i, j)
        && tile.seed == manifest.seed
        && manifest
            .set
            .iter()
            .all(|(k, v)| matches(tile.params.get(k), v))
        && (manifest.params.is_empty() || tile.params == manifest.params);
    if !same {
        bail!(
            "{}: written with another seed, parameters or tile; delete it to grow it again, or \
             choose another --out",
            path.display()
        );
    }
    let (_, _, min, max) = tile
        .grid()?
        .into_iter()
        .find(|t| (t.0, t.1) == (i, j))
        .with_context(|| format!("{}: tile {i},{j} is outside its world", path.display()))?;
    let entry = TileEntry {
        i,
        j,
        min,
        max,
        file,
        sha256: sha256_hex(&bytes),
        bytes: bytes.len() as u64,
        instances: tile.instances,
    };
    Ok(Some((entry, tile.params)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_recorded_parameter_matches_its_set_text() {
        for (value, text, same) in [
            (json!(true), "true", true),
            (json!(false), " FALSE", true),
            (json!(false), "0", false),
            (json!(3), "3.0", true),
            (json!(0.5), "0.5", true),
            (json!(3), "x", false),
            (json!("oak"), "oak", true),
            (json!("oak"), "Oak", false),
        ] {
            assert_eq!(matches(Some(&value), text), same, "{value} {text}");
        }
        assert!(!matches(None, "1"));
    }
}
