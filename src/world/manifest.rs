//! The world manifest (`DIR/world.json`): one type, written by `pge world` and read by
//! `pge world` and `pge merge`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use sha2::{Digest, Sha256};

use crate::output::write_atomically;

/// The manifest's `format`.
pub const FORMAT: &str = "pge-world/1";
/// The manifest's file in the world directory.
pub const MANIFEST: &str = "world.json";
/// The shared variants' binary file in the world directory.
pub const VARIANTS_BIN: &str = "variants.bin";
/// The shared variants' description in the world directory.
pub const VARIANTS_JSON: &str = "variants.json";

/// What makes two runs the same world: the script's SHA-256, the seed, the `--set` values
/// as given (not the script's path: the same script elsewhere is the same world).
#[derive(Clone, Debug, PartialEq)]
pub struct Identity {
    pub script_sha256: String,
    pub seed: u64,
    pub set: BTreeMap<String, String>,
}

/// `DIR/world.json`: the world's identity, its parameters, the shared variants (when the
/// tiles refer to them) and the tiles written so far. Fields that `pge merge` does not need
/// default when missing (a manifest written by hand); `pge world verify` checks them all.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Manifest {
    pub format: String,
    #[serde(default)]
    pub script: String,
    #[serde(default)]
    pub script_sha256: Option<String>,
    pub seed: u64,
    #[serde(default)]
    pub set: BTreeMap<String, String>,
    /// Every declared parameter's value (a tile's `extras.pge.params`).
    #[serde(default)]
    pub params: Map<String, Value>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variants: Option<VariantsEntry>,
    /// Whether every tile of the world is listed.
    pub complete: bool,
    /// The tiles' instances, summed.
    #[serde(default)]
    pub instances: u64,
    /// In (i, j) order.
    pub tiles: Vec<TileEntry>,
}

/// A tile written: its index, bounds (x, z in metres), file, SHA-256, length, instances.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TileEntry {
    pub i: u64,
    pub j: u64,
    #[serde(default)]
    pub min: [f64; 2],
    #[serde(default)]
    pub max: [f64; 2],
    pub file: String,
    pub sha256: String,
    #[serde(default)]
    pub bytes: u64,
    #[serde(default)]
    pub instances: u64,
}

/// The shared variants: the binary file and its description, each with SHA-256 and length.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct VariantsEntry {
    pub file: String,
    pub sha256: String,
    #[serde(default)]
    pub bytes: u64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description_sha256: Option<String>,
    #[serde(default)]
    pub description_bytes: u64,
}

/// The file of tile (i, j), relative to the world directory.
pub fn tile_file(i: u64, j: u64) -> String {
    format!("tiles/{i}_{j}.glb")
}

/// The SHA-256 of `data` as 64 lowercase hex digits.
pub(crate) fn sha256_hex(data: &[u8]) -> String {
    use std::fmt::Write;
    let mut hex = String::with_capacity(64);
    for byte in Sha256::digest(data) {
        let _ = write!(hex, "{byte:02x}");
    }
    hex
}

/// The bytes of the regular file `path`; `None` when there is none (missing, a link, a
/// folder, a device): a world's files are plain files, never followed elsewhere.
pub fn read_plain(path: &Path) -> anyhow::Result<Option<Vec<u8>>> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_file() => std::fs::read(path)
            .map(Some)
            .with_context(|| format!("cannot read {}", path.display())),
        Ok(_) => Ok(None),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e).with_context(|| format!("cannot read {}", path.display())),
    }
}

impl Manifest {
    /// An empty manifest of the world `ident`, grown from `script`.
    pub fn new(script: &Path, ident: &Identity) -> Manifest {
        Manifest {
            format: FORMAT.into(),
            script: script.display().to_string(),
            script_sha256: Some(ident.script_sha256.clone()),
            seed: ident.seed,
            set: ident.set.clone(),
            params: Map::new(),
            variants: None,
            complete: false,
            instances: 0,
            tiles: Vec::new(),
        }
    }

    /// The manifest in `dir`; `None` when there is no `world.json`; an error when it is not a
    /// `pge-world/1` manifest.
    pub fn read(dir: &Path) -> anyhow::Result<Option<Manifest>> {
        let path = dir.join(MANIFEST);
        let Some(text) = read_plain(&path)? else {
            if path.symlink_metadata().is_ok() {
                bail!("{}: not a regular file", path.display());
            }
            return Ok(None);
        };
        let value: Value = serde_json::from_slice(&text)
            .with_context(|| format!("{}: not a world manifest", path.display()))?;
        if value.get("format").and_then(Value::as_str) != Some(FORMAT) {
            bail!("{}: not a {FORMAT} manifest", path.display());
        }
        let manifest = serde_json::from_value(value)
            .with_context(|| format!("{}: not a {FORMAT} manifest", path.display()))?;
        Ok(Some(manifest))
    }

    /// The manifest in `dir`, which must be there.
    pub fn read_existing(dir: &Path) -> anyhow::Result<Manifest> {
        Manifest::read(dir)?.with_context(|| {
            format!(
                "{}: no world here (run pge-world first)",
                dir.join(MANIFEST).display()
            )
        })
    }

    /// Writes the manifest into `dir` atomically, the tiles in (i, j) order and the
    /// instances summed.
    pub fn write(&mut self, dir: &Path) -> anyhow::Result<()> {
        self.tiles.sort_by_key(|t| (t.i, t.j));
        self.instances = self.tiles.iter().map(|t| t.instances).sum();
        let mut text = serde_json::to_vec_pretty(self)?;
        text.push(b'\n');
        write_atomically(&dir.join(MANIFEST), &text)
    }

    /// Whether the manifest was written for the world `ident`.
    pub fn is_world(&self, ident: &Identity) -> bool {
        self.script_sha256.as_deref() == Some(ident.script_sha256.as_str())
            && self.seed == ident.seed
            && self.set == ident.set
    }

    /// Records `entry`, replacing the tile of the same index.
    pub fn put_tile(&mut self, entry: TileEntry) {
        self.tiles.retain(|t| (t.i, t.j) != (entry.i, entry.j));
        self.tiles.push(entry);
    }

    /// Whether `dir` holds the tile `entry` records: its file, of that length and hash.
    pub fn tile_intact(dir: &Path, entry: &TileEntry) -> anyhow::Result<bool> {
        if entry.file != tile_file(entry.i, entry.j) {
            return Ok(false);
        }
        Ok(read_plain(&dir.join(&entry.file))?
            .is_some_and(|d| d.len() as u64 == entry.bytes && sha256_hex(&d) == entry.sha256))
    }
}

impl VariantsEntry {
    /// The record of the shared variants in `dir` (`pge run --variants-out DIR`'s two
    /// files), `None` when either is missing.
    pub fn of(dir: &Path) -> anyhow::Result<Option<VariantsEntry>> {
        let (Some(bin), Some(json)) = (
            read_plain(&dir.join(VARIANTS_BIN))?,
            read_plain(&dir.join(VARIANTS_JSON))?,
        ) else {
            return Ok(None);
        };
        Ok(Some(VariantsEntry {
            file: VARIANTS_BIN.into(),
            sha256: sha256_hex(&bin),
            bytes: bin.len() as u64,
            description: Some(VARIANTS_JSON.into()),
            description_sha256: Some(sha256_hex(&json)),
            description_bytes: json.len() as u64,
        }))
    }
}

/// `dir/tiles`.
pub fn tiles_folder(dir: &Path) -> PathBuf {
    dir.join("tiles")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sha256_matches_the_standard_vectors() {
        assert_eq!(
            sha256_hex(b""),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
        );
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        let long = b"abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
        assert_eq!(
            sha256_hex(long),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"
        );
    }

    fn ident(seed: u64) -> Identity {
        Identity {
            script_sha256: "ab".repeat(32),
            seed,
            set: [("spin".to_string(), "0".to_string())].into(),
        }
    }

    #[test]
    fn a_manifest_is_written_in_order_and_read_back_the_same() {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut m = Manifest::new(Path::new("/w/forest.lua"), &ident(3));
        for (i, j, n) in [(1, 0, 4), (0, 1, 6)] {
            m.put_tile(TileEntry {
                i,
                j,
                min: [0.0, 0.0],
                max: [20.0, 20.0],
                file: tile_file(i, j),
                sha256: "0".repeat(64),
                bytes: 9,
                instances: n,
            });
        }
        m.write(dir.path()).expect("written");
        let text = std::fs::read_to_string(dir.path().join(MANIFEST)).expect("text");
        let keys: Vec<String> = serde_json::from_str::<Map<String, Value>>(&text)
            .expect("object")
            .keys()
            .cloned()
            .collect();
        // The format's key order (people diff manifests); no variants without shared ones.
        let order = [
            "format",
            "script",
            "scriptSha256",
            "seed",
            "set",
            "params",
            "complete",
            "instances",
            "tiles",
        ];
        assert_eq!(keys, order);
        let back = Manifest::read(dir.path()).expect("reads").expect("there");
        assert_eq!(back, m);
        assert_eq!(back.instances, 10);
        assert_eq!(
            back.tiles.iter().map(|t| (t.i, t.j)).collect::<Vec<_>>(),
            [(0, 1), (1, 0)]
        );
        // Written through a temporary file renamed over it: nothing else is left.
        let names: Vec<_> = std::fs::read_dir(dir.path()).expect("dir").collect();
        assert_eq!(names.len(), 1);
    }

    #[test]
    fn the_same_world_is_the_same_script_seed_and_set() {
        let m = Manifest::new(Path::new("/a.lua"), &ident(3));
        assert!(m.is_world(&ident(3)));
        assert!(!m.is_world(&ident(4)));
        let mut other = ident(3);
        other.set.insert("spin".into(), "1".into());
        assert!(!m.is_world(&other));
        other = ident(3);
        other.script_sha256 = "cd".repeat(32);
        assert!(!m.is_world(&other));
    }

    #[test]
    fn a_manifest_of_another_kind_is_refused_and_none_is_none() {
        let dir = tempfile::tempdir().expect("tempdir");
        assert!(Manifest::read(dir.path()).expect("reads").is_none());
        for (text, needle) in [
            ("{", "not a world manifest"),
            ("[]", "not a pge-world/1 manifest"),
            (
                "{\"format\": \"pge-world/0\"}",
                "not a pge-world/1 manifest",
            ),
            (
                "{\"format\": \"pge-world/1\"}",
                "not a pge-world/1 manifest",
            ),
        ] {
            std::fs::write(dir.path().join(MANIFEST), text).expect("write");
            let e = Manifest::read(dir.path()).expect_err(text);
            assert!(format!("{e:#}").contains(needle), "{e:#}");
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_tile_is_intact_only_as_a_plain_file_of_its_name_length_and_hash() {
        let dir = tempfile::tempdir().expect("tempdir");
        std::fs::create_dir_all(tiles_folder(dir.path())).expect("tiles");
        std::fs::write(dir.path().join("tiles/0_0.glb"), b"tile").expect("tile");
        let entry = TileEntry {
            i: 0,
            j: 0,
            min: [0.0; 2],
            max: [1.0; 2],
            file: tile_file(0, 0),
            sha256: sha256_hex(b"tile"),
            bytes: 4,
            instances: 1,
        };
        assert!(Manifest::tile_intact(dir.path(), &entry).expect("checks"));
        let elsewhere = TileEntry {
            file: "../0_0.glb".into(),
            ..entry.clone()
        };
        assert!(!Manifest::tile_intact(dir.path(), &elsewhere).expect("checks"));
        let longer = TileEntry {
            bytes: 5,
            ..entry.clone()
        };
        assert!(!Manifest::tile_intact(dir.path(), &longer).expect("checks"));
        std::fs::rename(dir.path().join("tiles/0_0.glb"), dir.path().join("real")).expect("mv");
        std::os::unix::fs::symlink(dir.path().join("real"), dir.path().join("tiles/0_0.glb"))
            .expect("link");
        assert!(!Manifest::tile_intact(dir.path(), &entry).expect("checks"));
    }
}
