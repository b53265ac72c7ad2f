//! `pge run --variant-cache DIR`: a forest (whole or one tile) written with a cold cache, a
//! warm cache and no cache is the same bytes; a warm run reads the entries instead of growing
//! again; a changed module, a damaged entry or a cache that cannot be written still gives
//! the right output (with a warning where the cache was unusable).

mod common;

use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use common::pge_in;

/// A small tiled forest: two layers of one species script, which reads a module.
fn fixture(dir: &Path) {
    std::fs::write(
        dir.join("forest.lua"),
        r#"local forest = pge.Forest{ size = {40, 40}, seed = 5, tile = 20 }
forest:terrain{ height = 2, scale = 40, octaves = 2 }
forest:scatter{ species = "shrub.lua", minDistance = 4, variants = 2 }
forest:scatter{ species = "shrub.lua", params = { points = 20 }, minDistance = 6, variants = 2 }
return forest
"#,
    )
    .expect("forest.lua");
    std::fs::write(
        dir.join("shrub.lua"),
        r##"local shape = require("shape")
local p = pge.params{ points = {40, min = 10, max = 1000, doc = "attraction points"} }
return pge.SpaceColonization{
  envelope = pge.shape.ellipsoid{ center = {0, 0.8, 0}, radii = shape.radii },
  points = p.points, step = 0.15, influence = 0.8, kill = 0.25, roots = {{0, 0, 0}},
  mesh = { sides = 4, color = "#5e4b3b" },
  leaves = { perTip = {1, 2}, size = 0.15, maxDepth = 1, colors = {"#3d6b25"} },
}
"##,
    )
    .expect("shrub.lua");
    shape(dir, "{0.8, 0.6, 0.8}");
}

fn shape(dir: &Path, radii: &str) {
    std::fs::write(
        dir.join("shape.lua"),
        format!("return {{ radii = {radii} }}\n"),
    )
    .expect("shape.lua");
}

/// Runs `pge run forest.lua` with `extra` arguments in `dir`; the glb's bytes and stderr.
fn run(dir: &Path, out: &str, extra: &[&str]) -> (Vec<u8>, String) {
    let mut args = vec!["run", "forest.lua", "-q", "-o", out];
    args.extend_from_slice(extra);
    let o = pge_in(&args, dir);
    let stderr = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "pge {args:?}: {stderr}");
    (std::fs::read(dir.join(out)).expect("the glb"), stderr)
}

fn entries(cache: &Path) -> Vec<PathBuf> {
    let mut list: Vec<PathBuf> = std::fs::read_dir(cache)
        .expect("the cache folder")
        .map(|e| e.expect("an entry").path())
        .collect();
    list.sort();
    list
}

#[test]
fn cold_warm_and_no_cache_write_the_same_bytes() {
    let dir = tempfile::tempdir().expect("tempdir");
    fixture(dir.path());
    let cache = dir.path().join("cache");
    let flag = cache.to_string_lossy().to_string();
    for tile in [None, Some("1,0"), Some("0,1")] {
        let mut extra = vec![];
        if let Some(t) = tile {
            extra.extend_from_slice(&["--tile", t]);
        }
        let (plain, _) = run(dir.path(), "plain.glb", &extra);
        let mut cached = extra.clone();
        cached.extend_from_slice(&["--variant-cache", &flag]);
        let (first, _) = run(dir.path(), "first.glb", &cached);
        // Two layers of two variants: four entries, whatever the tile.
        let found = entries(&cache);
        assert_eq!(found.len(), 4, "{found:?}");
        let inodes: Vec<u64> = found
            .iter()
            .map(|f| std::fs::metadata(f).expect("metadata").ino())
            .collect();
        let (warm, stderr) = run(dir.path(), "warm.glb", &cached);
        assert!(
            plain == first,
            "tile {tile:?}: a cold cache changed the bytes"
        );
        assert!(
            plain == warm,
            "tile {tile:?}: a warm cache changed the bytes"
        );
        assert!(!stderr.contains("variant cache"), "{stderr}");
        // A warm run reads the entries: none was written again.
        let again: Vec<u64> = entries(&cache)
            .iter()
            .map(|f| std::fs::metadata(f).expect("metadata").ino())
            .collect();
        assert_eq!(
            inodes, again,
            "tile {tile:?}: the variants were grown again"
        );
        // Any thread count reads the same entries into the same bytes.
        let mut one = cached.clone();
        one.extend_from_slice(&["--threads", "1"]);
        assert!(run(dir.path(), "one.glb", &one).0 == plain);
    }
}

#[test]
fn a_changed_module_or_a_damaged_entry_grows_the_variant_again() {
    let dir = tempfile::tempdir().expect("tempdir");
    fixture(dir.path());
    let cache = dir.path().join("cache");
    let flag = cache.to_string_lossy().to_string();
    let cached = ["--tile", "1,1", "--variant-cache", flag.as_str()];
    let (before, _) = run(dir.path(), "before.glb", &cached);

    // The species' module changes: the entries no longer fit and are replaced.
    shape(dir.path(), "{1.0, 0.9, 1.0}");
    let (plain, _) = run(dir.path(), "plain.glb", &["--tile", "1,1"]);
    assert!(plain != before, "the module changes the shrubs");
    let (after, stderr) = run(dir.path(), "after.glb", &cached);
    assert!(after == plain, "a stale entry was used");
    assert!(!stderr.contains("variant cache"), "{stderr}");

    // Damaged entries: a warning each, the variant grown again, the same bytes.
    let found = entries(&cache);
    assert_eq!(found.len(), 4, "{found:?}");
    let whole = std::fs::read(&found[0]).expect("entry");
    std::fs::write(&found[0], &whole[..whole.len() / 2]).expect("truncate");
    std::fs::write(&found[1], b"not an entry").expect("garbage");
    let (repaired, stderr) = run(dir.path(), "repaired.glb", &cached);
    assert!(repaired == plain, "a damaged entry changed the output");
    assert_eq!(
        stderr.matches("warning: variant cache entry").count(),
        2,
        "{stderr}"
    );
    // Each warning names the scatter line of its layer (3 or 4): which entries were
    // damaged depends on their names, which hash the `pge` binary.
    assert!(
        stderr
            .lines()
            .filter(|l| l.contains("warning: variant cache entry"))
            .all(|l| l.starts_with("forest.lua:3: warning")
                || l.starts_with("forest.lua:4: warning")),
        "{stderr}"
    );
    assert!(stderr.contains("damaged"), "{stderr}");
    assert!(stderr.contains("not a variant"), "{stderr}");
    let (_, stderr) = run(dir.path(), "again.glb", &cached);
    assert!(
        !stderr.contains("variant cache"),
        "the damaged entries were replaced: {stderr}"
    );
}

#[test]
fn a_cache_that_cannot_be_written_is_a_warning_not_an_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    fixture(dir.path());
    // A file where the cache folder should be.
    std::fs::write(dir.path().join("taken"), "a file").expect("file");
    let (plain, _) = run(dir.path(), "plain.glb", &["--tile", "0,0"]);
    let (cached, stderr) = run(
        dir.path(),
        "cached.glb",
        &["--tile", "0,0", "--variant-cache", "taken"],
    );
    assert!(cached == plain);
    assert!(
        stderr.contains("warning: cannot write the variant cache entry taken/"),
        "{stderr}"
    );
}
