//! The world directory's manifest (`world.json`) as `pge merge` reads it, and the SHA-256
//! its files are checked with.

use std::path::Path;

use anyhow::Context;
use serde_json::Value;
use sha2::{Digest, Sha256};

/// A tile as the manifest lists it.
pub(super) struct TileEntry {
    pub(super) i: u64,
    pub(super) j: u64,
    pub(super) file: String,
    pub(super) sha256: String,
}

/// What `pge merge` reads from `world.json`.
pub(super) struct Manifest {
    pub(super) seed: u64,
    pub(super) params: Vec<(String, Value)>,
    pub(super) tiles: Vec<TileEntry>,
    /// The shared variants' binary file, its SHA-256 and their description, when the tiles
    /// refer to them.
    pub(super) variants: Option<(String, String, Option<String>)>,
}

/// The manifest of `dir`; an error saying what to do when it is not a complete world.
pub(super) fn read_manifest(dir: &Path) -> anyhow::Result<Manifest> {
    let path = dir.join("world.json");
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("{}: no world here (run pge-world first)", path.display()))?;
    let world: Value = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a world manifest", path.display()))?;
    let bad = |what: &str| anyhow::anyhow!("{}: {what}", path.display());
    if world.get("format").and_then(Value::as_str) != Some("pge-world/1") {
        return Err(bad("not a pge-world/1 manifest"));
    }
    if world.get("complete").and_then(Value::as_bool) != Some(true) {
        return Err(bad(
            "the world is not complete: run pge-world again on this directory to finish it",
        ));
    }
    let seed = world
        .get("seed")
        .and_then(Value::as_u64)
        .ok_or_else(|| bad("no seed"))?;
    let params = match world.get("params") {
        Some(Value::Object(m)) => m.iter().map(|(k, v)| (k.clone(), v.clone())).collect(),
        _ => Vec::new(),
    };
    let mut tiles = Vec::new();
    for t in world
        .get("tiles")
        .and_then(Value::as_array)
        .ok_or_else(|| bad("no tiles"))?
    {
        let field = |k: &str| t.get(k).ok_or_else(|| bad(&format!("a tile without {k}")));
        let number = |k: &str| {
            field(k)?
                .as_u64()
                .ok_or_else(|| bad(&format!("a tile's {k} is not an integer")))
        };
        let text = |k: &str| {
            field(k)?
                .as_str()
                .map(str::to_string)
                .ok_or_else(|| bad(&format!("a tile's {k} is not a string")))
        };
        tiles.push(TileEntry {
            i: number("i")?,
            j: number("j")?,
            file: text("file")?,
            sha256: text("sha256")?,
        });
    }
    let variants = match world.get("variants") {
        None | Some(Value::Null) => None,
        Some(v) => {
            let text = |k: &str| {
                v.get(k)
                    .and_then(Value::as_str)
                    .map(str::to_string)
                    .ok_or_else(|| bad(&format!("the variants' {k} is not a string")))
            };
            Some((text("file")?, text("sha256")?, text("description").ok()))
        }
    };
    Ok(Manifest {
        seed,
        params,
        tiles,
        variants,
    })
}

/// The SHA-256 of `data` as 64 lowercase hex digits, as `pge-world` records it.
pub(crate) fn sha256_hex(data: &[u8]) -> String {
    use std::fmt::Write;
    let mut hex = String::with_capacity(64);
    for byte in Sha256::digest(data) {
        let _ = write!(hex, "{byte:02x}");
    }
    hex
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
}
