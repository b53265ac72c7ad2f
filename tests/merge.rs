//! `pge merge`: a world directory (the layout `pge-world` writes, built here with local
//! `pge run --tile` runs) joins into one glb that writes every variant mesh once, places
//! every instance of every tile, equals the whole forest tree for tree, and passes the
//! Khronos validator; bad directories are one-line errors with nothing written.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::{pge, pge_ok as run_ok, ray_forest as forest, run_validator};
use serde_json::{Value, json};

fn sha256(path: &Path) -> String {
    let o = Command::new("sha256sum")
        .arg(path)
        .output()
        .expect("sha256sum runs");
    let text = String::from_utf8_lossy(&o.stdout);
    text.split_whitespace().next().expect("a hash").to_string()
}

fn root_extras(glb: &Path) -> Value {
    let gltf = gltf::Gltf::open(glb).expect("a glb");
    let raw = gltf.document.as_json().extras.as_ref().expect("extras");
    serde_json::from_str::<Value>(raw.get()).expect("json")["pge"].clone()
}

/// A world directory as `pge-world` writes it: every tile by `pge run --tile`, recorded by
/// `pge world`.
fn world(dir: &Path) {
    world_of(dir, false);
}

/// [`world`], with tiles that refer to the world's shared variants when `shared`
/// (`pge run --variants-out DIR`, then `pge run --tile I,J --variants DIR`).
fn world_of(dir: &Path, shared: bool) {
    let script = forest();
    let tiles: Value = serde_json::from_slice(&run_ok(&["tiles", &script])).expect("json");
    let d = dir.to_string_lossy().to_string();
    let mut init = vec!["world", "init", &script, "--out", &d];
    if !shared {
        init.push("--standalone-tiles");
    }
    run_ok(&init);
    std::fs::create_dir_all(dir.join("tiles")).expect("tiles folder");
    if shared {
        run_ok(&["run", &script, "--variants-out", &d, "-q"]);
        run_ok(&["world", "variants", &d]);
    }
    for t in tiles.as_array().expect("tiles") {
        let (i, j) = (t["i"].as_u64().expect("i"), t["j"].as_u64().expect("j"));
        let out = dir.join(format!("tiles/{i}_{j}.glb"));
        let tile = format!("{i},{j}");
        let o = out.to_string_lossy().to_string();
        let mut args = vec!["run", &script, "--tile", &tile, "-o", &o, "-q"];
        if shared {
            args.extend_from_slice(&["--variants", &d]);
        }
        run_ok(&args);
        run_ok(&["world", "add", &d, &tile]);
    }
    run_ok(&["world", "finish", &d]);
}

/// Per mesh name: how many glTF meshes have it, and the placements (translations as bits,
/// sorted) of the instancing nodes that draw it.
struct Content {
    meshes: BTreeMap<String, usize>,
    placements: BTreeMap<String, Vec<[u32; 3]>>,
    positions: BTreeMap<String, Vec<[u32; 3]>>,
}

fn content(path: &Path) -> Content {
    let (doc, buffers, _) = gltf::import(path).expect("the glb imports");
    let mut meshes = BTreeMap::new();
    let mut positions = BTreeMap::new();
    for m in doc.meshes() {
        let name = m.name().unwrap_or_default().to_string();
        *meshes.entry(name.clone()).or_insert(0) += 1;
        let prim = m.primitives().next().expect("a primitive");
        let reader = prim.reader(|b| Some(&buffers[b.index()].0[..]));
        let p: Vec<[u32; 3]> = reader
            .read_positions()
            .expect("positions")
            .map(|p| p.map(f32::to_bits))
            .collect();
        positions.insert(name, p);
    }
    // gltf-json keeps no unknown extension: the instancing accessors come from the raw JSON.
    let mut placements: BTreeMap<String, Vec<[u32; 3]>> = BTreeMap::new();
    let raw: Value = {
        let bytes = std::fs::read(path).expect("read");
        let glb = gltf::binary::Glb::from_slice(&bytes).expect("glb");
        serde_json::from_slice(&glb.json).expect("json chunk")
    };
    for (k, node) in raw["nodes"].as_array().expect("nodes").iter().enumerate() {
        let Some(t) = node.pointer("/extensions/EXT_mesh_gpu_instancing/attributes/TRANSLATION")
        else {
            continue;
        };
        let accessor = doc
            .accessors()
            .nth(t.as_u64().expect("index") as usize)
            .expect("accessor");
        let data: Vec<[u32; 3]> =
            gltf::accessor::Iter::<[f32; 3]>::new(accessor, |b| Some(&buffers[b.index()].0[..]))
                .expect("data")
                .map(|p| p.map(f32::to_bits))
                .collect();
        let mesh = doc
            .nodes()
            .nth(k)
            .and_then(|n| n.mesh())
            .expect("an instanced mesh");
        placements
            .entry(mesh.name().unwrap_or_default().to_string())
            .or_default()
            .extend(data);
    }
    for p in placements.values_mut() {
        p.sort_unstable();
    }
    Content {
        meshes,
        placements,
        positions,
    }
}

fn merge(args: &[&str]) -> std::process::Output {
    let mut all = vec!["merge"];
    all.extend_from_slice(args);
    pge(&all)
}

#[test]
fn a_merged_world_is_the_whole_forest_with_each_variant_written_once() {
    let dir = tempfile::tempdir().expect("tempdir");
    let w = dir.path().join("world");
    world(&w);
    let merged = dir.path().join("merged.glb");
    let o = merge(&[&w.to_string_lossy(), "-o", &merged.to_string_lossy()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let whole = dir.path().join("whole.glb");
    run_ok(&["run", &forest(), "-o", &whole.to_string_lossy(), "-q"]);
    let (m, f) = (content(&merged), content(&whole));
    // Each variant once, as in the whole forest; one terrain patch per tile.
    let variants = |c: &Content| {
        c.meshes
            .iter()
            .filter(|(n, _)| *n != "terrain")
            .map(|(n, k)| (n.clone(), *k))
            .collect::<Vec<_>>()
    };
    assert_eq!(variants(&m), variants(&f));
    assert!(variants(&m).iter().all(|(_, k)| *k == 1), "{:?}", m.meshes);
    assert!(variants(&m).len() >= 4, "{:?}", m.meshes);
    assert_eq!(m.meshes["terrain"], 16);
    for (name, _) in variants(&m) {
        assert_eq!(m.positions[&name], f.positions[&name], "{name}");
    }
    // Every tree of every tile, where the whole forest has it.
    assert_eq!(m.placements, f.placements);
    let manifest: Value =
        serde_json::from_str(&std::fs::read_to_string(w.join("world.json")).expect("manifest"))
            .expect("json");
    let sum: u64 = manifest["tiles"]
        .as_array()
        .expect("tiles")
        .iter()
        .map(|t| t["instances"].as_u64().expect("count"))
        .sum();
    let placed: usize = m.placements.values().map(Vec::len).sum();
    assert_eq!(placed as u64, sum);
    let extras = root_extras(&merged);
    assert_eq!(extras["forest"]["instances"], sum);
    assert_eq!(extras["forest"]["tiles"].as_array().map(Vec::len), Some(16));
    assert_eq!(extras["params"], manifest["params"]);
    assert_eq!(
        extras["forest"]["species"],
        root_extras(&whole)["forest"]["species"]
    );

    // A rectangle of tiles: its terrain patches and its trees only.
    let part = dir.path().join("part.glb");
    let o = merge(&[
        &w.to_string_lossy(),
        "-o",
        &part.to_string_lossy(),
        "--rect",
        "1,1,2,3",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let p = content(&part);
    assert_eq!(p.meshes["terrain"], 6);
    let in_rect: u64 = manifest["tiles"]
        .as_array()
        .expect("tiles")
        .iter()
        .filter(|t| (1..=2).contains(&t["i"].as_u64().expect("i")))
        .filter(|t| (1..=3).contains(&t["j"].as_u64().expect("j")))
        .map(|t| t["instances"].as_u64().expect("count"))
        .sum();
    assert_eq!(
        p.placements.values().map(Vec::len).sum::<usize>() as u64,
        in_rect
    );
    assert!(p.meshes.values().all(|k| *k == 1 || *k == 6));

    let nodes = dir.path().join("nodes.glb");
    let o = merge(&[
        &w.to_string_lossy(),
        "-o",
        &nodes.to_string_lossy(),
        "--instancing",
        "nodes",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc = gltf::Gltf::open(&nodes).expect("glb");
    assert_eq!(doc.nodes().count() as u64, sum + 16);

    let (passed, report) = run_validator(&[merged, part, nodes]);
    println!("{report}");
    assert!(passed, "the glTF validator found errors:\n{report}");
}

fn expect_error(args: &[&str], needles: &[&str], out: &Path) {
    let o = merge(args);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    for n in needles {
        assert!(err.contains(n), "'{n}' not in: {err}");
    }
    assert!(!out.exists(), "{} was written", out.display());
}

#[test]
fn a_directory_that_is_not_a_complete_world_is_a_one_line_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let w: PathBuf = dir.path().join("world");
    let out = dir.path().join("out.glb");
    let (ws, os) = (w.to_string_lossy(), out.to_string_lossy());
    expect_error(&[&ws, "-o", &os], &["world.json", "pge-world"], &out);

    // Two tiles written by hand, the manifest saying the world is not finished.
    std::fs::create_dir_all(w.join("tiles")).expect("folders");
    let tile = w.join("tiles/0_0.glb");
    run_ok(&[
        "run",
        &forest(),
        "--tile",
        "0,0",
        "-o",
        &tile.to_string_lossy(),
        "-q",
    ]);
    let entry = json!({"i": 0, "j": 0, "file": "tiles/0_0.glb", "sha256": sha256(&tile),
        "instances": 1});
    let manifest = |complete: bool| {
        json!({"format": "pge-world/1", "seed": 1, "params": {}, "complete": complete,
            "tiles": [entry]})
        .to_string()
    };
    std::fs::write(w.join("world.json"), manifest(false)).expect("manifest");
    expect_error(
        &[&ws, "-o", &os],
        &["not complete", "pge-world again"],
        &out,
    );

    std::fs::write(w.join("world.json"), manifest(true)).expect("manifest");
    expect_error(
        &[&ws, "-o", &os, "--rect", "1,1,2,2"],
        &["no tile", "rectangle"],
        &out,
    );
    let mut bytes = std::fs::read(&tile).expect("tile");
    bytes[100] ^= 1;
    std::fs::write(&tile, bytes).expect("damaged");
    expect_error(&[&ws, "-o", &os], &["0_0.glb", "does not match"], &out);

    std::fs::write(w.join("world.json"), "{\"format\": \"other\"}").expect("manifest");
    expect_error(&[&ws, "-o", &os], &["world.json", "pge-world/1"], &out);

    let o = merge(&[&ws, "--rect", "2,0,1,1"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn a_world_of_tiles_that_share_their_variants_merges_into_the_same_glb() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (alone, shared) = (dir.path().join("alone"), dir.path().join("shared"));
    world_of(&alone, false);
    world_of(&shared, true);
    let merged = |w: &Path| {
        let out = w.join("merged.glb");
        let o = merge(&[&w.to_string_lossy(), "-o", &out.to_string_lossy()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    };
    let (a, b) = (merged(&alone), merged(&shared));
    // Every variant read once from variants.bin, with its extras from variants.json: the
    // same glb as the standalone tiles give, byte for byte.
    assert_eq!(std::fs::read(&a).expect("a"), std::fs::read(&b).expect("b"));
    let c = content(&b);
    assert_eq!(c.meshes["terrain"], 16);

    // A damaged shared file is refused, nothing written.
    std::fs::write(shared.join("variants.bin"), b"damaged").expect("damaged");
    let out = dir.path().join("out.glb");
    expect_error(
        &[&shared.to_string_lossy(), "-o", &out.to_string_lossy()],
        &["variants.bin", "does not match"],
        &out,
    );
}
