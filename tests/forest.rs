//! Forests end to end: real scripts in, glb out. Instances read back from the glb match
//! `forest:instances()`; tiles add up to the whole forest; the bytes do not depend on the
//! thread count; every bad input is a `FILE:LINE:` error with exit 1 and no output file.

mod common;
#[path = "../examples/forest_host.rs"]
mod forest_host;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use common::{pge, root};
use pge_engine::SessionOptions;
use pge_engine::mlua::{ObjectLike, Table, Value};

/// Small settings so a forest grows in a debug build in seconds.
const SMALL: &[&str] = &["--set", "points=150"];

fn run_ok(args: &[&str]) -> std::process::Output {
    let o = pge(args);
    assert!(
        o.status.success(),
        "pge {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn out_path(dir: &Path, name: &str) -> String {
    dir.join(name).to_string_lossy().to_string()
}

/// Every placement in a glb, per mesh name: (translation, rotation, scale), read from the
/// EXT_mesh_gpu_instancing accessors or from plain nodes.
/// Translation, rotation and scale of one placement.
type Placement = ([f32; 3], [f32; 4], [f32; 3]);

fn placements(glb: &[u8]) -> BTreeMap<String, Vec<Placement>> {
    let gltf = gltf::Gltf::from_slice(glb).expect("a glb");
    let blob = gltf.blob.as_ref().expect("binary chunk");
    let json = gltf.document.as_json();
    let floats = |accessor: usize| -> Vec<f32> {
        let a = &json.accessors[accessor];
        let view = &json.buffer_views[a.buffer_view.expect("a view").value()];
        let start = view.byte_offset.map_or(0, |o| o.0 as usize);
        blob[start..start + view.byte_length.0 as usize]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    };
    let raw: serde_json::Value = serde_json::from_slice(
        &glb[20..20 + u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize],
    )
    .expect("json chunk");
    let mut out: BTreeMap<String, Vec<_>> = BTreeMap::new();
    for (k, node) in json.nodes.iter().enumerate() {
        let Some(mesh) = node.mesh else { continue };
        let name = json.meshes[mesh.value()].name.clone().unwrap_or_default();
        let ext = &raw["nodes"][k]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
        if ext.is_object() {
            let t = floats(ext["TRANSLATION"].as_u64().expect("t") as usize);
            let r = floats(ext["ROTATION"].as_u64().expect("r") as usize);
            let s = floats(ext["SCALE"].as_u64().expect("s") as usize);
            let list = out.entry(name).or_default();
            for i in 0..t.len() / 3 {
                list.push((
                    [t[3 * i], t[3 * i + 1], t[3 * i + 2]],
                    [r[4 * i], r[4 * i + 1], r[4 * i + 2], r[4 * i + 3]],
                    [s[3 * i], s[3 * i + 1], s[3 * i + 2]],
                ));
            }
        } else {
            out.entry(name).or_default().push((
                node.translation.unwrap_or([0.0; 3]),
                node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |q| q.0),
                node.scale.unwrap_or([1.0; 3]),
            ));
        }
    }
    out
}

fn root_extras(glb: &[u8]) -> serde_json::Value {
    let gltf = gltf::Gltf::from_slice(glb).expect("a glb");
    serde_json::from_str(
        gltf.document
            .as_json()
            .extras
            .as_ref()
            .expect("extras")
            .get(),
    )
    .expect("json")
}

/// `forest:instances()` of a script, through the library.
fn script_instances(script: &str, set: &[(&str, &str)]) -> Vec<(String, u32, [f32; 3], f64, f64)> {
    let engine = pge::default_engine().build().expect("engine");
    let session = engine
        .session(SessionOptions {
            params: set
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
            ..SessionOptions::default()
        })
        .expect("session");
    let value = session
        .run_script(&root().join(script))
        .expect("script runs");
    let Value::UserData(forest) = value else {
        panic!("not a forest")
    };
    let list: Table = forest.call_method("instances", ()).expect("instances");
    list.sequence_values::<Table>()
        .map(|t| {
            let t = t.expect("table");
            let p: pge_engine::lua::LuaVec3 = t.get("position").expect("position");
            (
                t.get("species").expect("species"),
                t.get("variant").expect("variant"),
                p.0.to_array(),
                t.get("yaw").expect("yaw"),
                t.get("scale").expect("scale"),
            )
        })
        .collect()
}

#[test]
fn instance_transforms_in_the_glb_match_forest_instances() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = out_path(dir.path(), "mixed.glb");
    let args = [
        "run",
        "scripts/forests/mixed.lua",
        "-o",
        &out,
        "-q",
        "--set",
        "points=150",
        "--set",
        "size=120",
        "--set",
        "variants=2",
    ];
    run_ok(&args);
    let glb = std::fs::read(&out).expect("written");
    let placed = placements(&glb);
    let expected = script_instances(
        "scripts/forests/mixed.lua",
        &[("points", "150"), ("size", "120"), ("variants", "2")],
    );
    assert!(expected.len() > 20, "{}", expected.len());
    let mut seen = 0;
    for (name, list) in &placed {
        if name == "terrain" {
            continue;
        }
        let (species, variant) = name.split_once('/').expect("SPECIES/VARIANT");
        let want: Vec<_> = expected
            .iter()
            .filter(|e| e.0 == species && e.1.to_string() == variant)
            .collect();
        assert_eq!(list.len(), want.len(), "{name}");
        for ((t, r, s), e) in list.iter().zip(want) {
            assert_eq!(*t, e.2);
            let yaw = e.3.to_radians() as f32;
            let q = glam::Quat::from_rotation_y(yaw);
            assert!(
                glam::Quat::from_array(*r).abs_diff_eq(q, 1e-5),
                "{r:?} {q:?}"
            );
            assert!((f64::from(s[0]) - e.4).abs() < 1e-5 && s[0] == s[1] && s[1] == s[2]);
        }
        seen += list.len();
    }
    assert_eq!(seen, expected.len());
    let extras = root_extras(&glb);
    let forest = &extras["pge"]["forest"];
    assert_eq!(forest["instances"], expected.len());
    assert_eq!(forest["tile"], 100.0);
    assert_eq!(forest["species"][0]["name"], "oak");
    assert_eq!(forest["species"][2]["variants"], 2);
    let text = String::from_utf8_lossy(&glb);
    // Instancing first; the leaves' KHR_materials_diffuse_transmission may follow.
    assert!(text.contains("\"extensionsUsed\":[\"EXT_mesh_gpu_instancing\""));

    // One node per instance with --instancing nodes, the same placements.
    let out2 = out_path(dir.path(), "nodes.glb");
    let mut args2 = args.to_vec();
    args2[3] = &out2;
    args2.extend(["--instancing", "nodes"]);
    run_ok(&args2);
    let glb2 = std::fs::read(&out2).expect("written");
    assert_eq!(placements(&glb2), placed);
    let gltf = gltf::Gltf::from_slice(&glb2).expect("glb");
    assert_eq!(gltf.nodes().count(), expected.len() + 1);
    assert!(!String::from_utf8_lossy(&glb2).contains("EXT_mesh_gpu_instancing"));
}

#[test]
fn output_is_byte_identical_for_one_and_two_threads() {
    let dir = tempfile::tempdir().expect("tempdir");
    let a = out_path(dir.path(), "a.glb");
    let b = out_path(dir.path(), "b.glb");
    let common = ["--set", "points=150", "-q"];
    let mut one = vec![
        "run",
        "scripts/forests/plantation.lua",
        "-o",
        &a,
        "--threads",
        "1",
    ];
    one.extend(common);
    let mut two = vec![
        "run",
        "scripts/forests/plantation.lua",
        "-o",
        &b,
        "--threads",
        "2",
    ];
    two.extend(common);
    run_ok(&one);
    run_ok(&two);
    let (a, b) = (std::fs::read(a).expect("a"), std::fs::read(b).expect("b"));
    assert!(a.len() > 1000);
    assert!(a == b, "the glb differs between 1 and 2 threads");
}

#[test]
fn tiles_add_up_to_the_whole_forest_and_share_terrain_borders() {
    let o = run_ok(&["tiles", "scripts/forests/plantation.lua"]);
    let tiles: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let tiles = tiles.as_array().expect("an array").clone();
    assert_eq!(tiles.len(), 6, "{tiles:?}");
    assert_eq!(tiles[0]["min"], serde_json::json!([-60.0, -40.0]));
    assert_eq!(tiles[5]["max"], serde_json::json!([60.0, 40.0]));
    let dir = tempfile::tempdir().expect("tempdir");
    let whole = out_path(dir.path(), "whole.glb");
    let mut args = vec!["run", "scripts/forests/plantation.lua", "-o", &whole];
    args.extend(SMALL);
    args.push("-q");
    run_ok(&args);
    let whole = placements(&std::fs::read(&whole).expect("whole"));
    let mut union: BTreeMap<String, Vec<_>> = BTreeMap::new();
    let mut terrain_edges: Vec<(usize, usize, Vec<[f32; 3]>)> = Vec::new();
    for t in &tiles {
        let (i, j) = (t["i"].as_u64().expect("i"), t["j"].as_u64().expect("j"));
        let out = out_path(dir.path(), &format!("{i}_{j}.glb"));
        let tile = format!("{i},{j}");
        let mut args = vec![
            "run",
            "scripts/forests/plantation.lua",
            "-o",
            &out,
            "--tile",
            &tile,
        ];
        args.extend(SMALL);
        args.push("-q");
        run_ok(&args);
        let glb = std::fs::read(&out).expect("tile written");
        for (name, list) in placements(&glb) {
            if name != "terrain" {
                union.entry(name).or_default().extend(list);
            }
        }
        let (doc, buffers, _) = gltf::import_slice(&glb).expect("imports");
        let mesh = doc
            .meshes()
            .find(|m| m.name() == Some("terrain"))
            .expect("terrain");
        let prim = mesh.primitives().next().expect("primitive");
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        let pos: Vec<[f32; 3]> = reader.read_positions().expect("positions").collect();
        terrain_edges.push((i as usize, j as usize, pos));
    }
    let key = |p: &([f32; 3], [f32; 4], [f32; 3])| (p.0[0].to_bits(), p.0[2].to_bits());
    let mut whole_sorted = whole.clone();
    whole_sorted.remove("terrain");
    for list in whole_sorted.values_mut() {
        list.sort_by_key(key);
    }
    for list in union.values_mut() {
        list.sort_by_key(key);
    }
    assert_eq!(union, whole_sorted);
    // Neighbouring patches share the vertices of their common edge exactly.
    let at = |i: usize, j: usize| {
        &terrain_edges
            .iter()
            .find(|e| e.0 == i && e.1 == j)
            .expect("tile")
            .2
    };
    let edge_x = -20.0f32;
    let left: Vec<_> = at(0, 0)
        .iter()
        .filter(|p| p[0] == edge_x)
        .copied()
        .collect();
    let right: Vec<_> = at(1, 0)
        .iter()
        .filter(|p| p[0] == edge_x)
        .copied()
        .collect();
    assert!(left.len() > 5);
    assert_eq!(left, right);
}

/// A forest script in a temporary folder, with a species script beside it.
fn bad_script(body: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("stick.lua"),
        "return pge.mesh{ positions = {0,0,0, 0.2,0,0, 0,2,0}, indices = {0,1,2} }\n",
    )
    .expect("species");
    std::fs::write(
        dir.path().join("broken.lua"),
        "local x = 1\nerror('no sap')\n",
    )
    .expect("broken");
    let script = dir.path().join("forest.lua");
    std::fs::write(&script, body).expect("script");
    (dir, script)
}

fn expect_error(body: &str, extra: &[&str], needles: &[&str]) {
    let (dir, script) = bad_script(body);
    let out = dir.path().join("out.glb");
    let script_s = script.to_string_lossy().to_string();
    let out_s = out.to_string_lossy().to_string();
    let mut args = vec!["run", &script_s, "-o", &out_s, "-q"];
    args.extend(extra);
    let o = pge(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{body}: {err}");
    assert!(err.contains("forest.lua:"), "{err}");
    for n in needles {
        assert!(err.contains(n), "'{n}' not in: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists(), "an output file was left behind");
}

const HEAD: &str = "local f = pge.Forest{ size = {60, 60}, tile = 30 }\n";

#[test]
fn bad_input_is_a_file_line_error_with_no_output() {
    let scatter =
        |opts: &str| format!("{HEAD}f:scatter{{ species = \"stick.lua\", {opts} }}\nreturn f\n");
    expect_error(
        &format!("{HEAD}f:scatter{{ species = \"missing.lua\", minDistance = 3 }}\nreturn f\n"),
        &[],
        &["forest.lua:2:", "missing.lua"],
    );
    expect_error(
        &format!("{HEAD}f:scatter{{ species = \"broken.lua\", minDistance = 3 }}\nreturn f\n"),
        &[],
        &["forest.lua:2:", "broken.lua:2:", "no sap"],
    );
    expect_error(
        &scatter("minDistance = 0"),
        &[],
        &["forest.lua:2:", "minDistance", "> 0"],
    );
    expect_error(
        "local f = pge.Forest{ size = {0, 10} }\nreturn f\n",
        &[],
        &["forest.lua:1:", "size"],
    );
    expect_error(
        &scatter("minDistance = 3, density = 1.5"),
        &[],
        &["forest.lua:2:", "density", "between 0 and 1"],
    );
    expect_error(
        &scatter("minDistance = 3, density = 'nothing.png'"),
        &[],
        &["forest.lua:2:", "density", "nothing.png"],
    );
    expect_error(
        &scatter("minDistance = 3, slope = {30, 10}"),
        &[],
        &["forest.lua:2:", "slope", "min <= max"],
    );
    expect_error(
        &scatter("minDistance = 3, altitude = {5, -5}"),
        &[],
        &["forest.lua:2:", "altitude", "min <= max"],
    );
    expect_error(
        &scatter("minDistance = 3"),
        &["--tile", "2,0"],
        &["forest.lua:1:", "out of range"],
    );
    expect_error(
        "local f = pge.Forest{ size = 60 }\nf:scatter{ species = \"stick.lua\", minDistance = 3 }\nreturn f\n",
        &["--tile", "0,0"],
        &["forest.lua:1:", "tile = T"],
    );
    expect_error(
        "local f = pge.Forest{ size = 20000 }\nf:scatter{ species = \"stick.lua\", minDistance = 1 }\nreturn f\n",
        &[],
        // At the layer whose minDistance makes the trees too many.
        &["forest.lua:2:", "10000000", "minDistance"],
    );
    expect_error(
        "local f = pge.Forest{ size = 60, tile = 0 }\nreturn f\n",
        &[],
        &["forest.lua:1:", "tile", "> 0"],
    );
    expect_error(
        &scatter("minDistance = 3, scale = {0, 1}"),
        &[],
        &["forest.lua:2:", "scale"],
    );
    expect_error(
        &format!(
            "{HEAD}f:scatter{{ species = function() return pge.mesh{{ positions = {{0,0,0}}, indices = {{0,0,0}} }} end, minDistance = 3, density = function(x, z) return 2 end }}\nreturn f\n"
        ),
        &[],
        &["density", "between 0 and 1"],
    );
}

#[test]
fn the_host_example_writes_the_instances_it_laid_out() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("host.glb");
    let instances = forest_host::run(&out).expect("the example runs");
    assert!(instances.len() > 1000, "{}", instances.len());
    let glb = std::fs::read(&out).expect("written");
    let placed = placements(&glb);
    let names = ["fir", "birch"];
    let mut expected: BTreeMap<String, Vec<[f32; 3]>> = BTreeMap::new();
    let mut expected_leaves: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    for (i, leaves) in &instances {
        let name = format!("{}/{}", names[i.layer as usize], i.variant);
        expected.entry(name.clone()).or_default().push(i.position);
        expected_leaves
            .entry(name)
            .or_default()
            .push(u64::from(*leaves));
    }
    let got: BTreeMap<String, Vec<[f32; 3]>> = placed
        .into_iter()
        .filter(|(name, _)| name != "terrain")
        .map(|(name, list)| (name, list.into_iter().map(|p| p.0).collect()))
        .collect();
    assert_eq!(got, expected);
    // Each tree's leaves for the host's camera are in its node's extras, within the budget.
    assert_eq!(node_leaves(&glb), expected_leaves);
    let total: u64 = expected_leaves.values().flatten().sum();
    let budget = forest_host::CAMERA.budget.total;
    assert!(total <= budget && total > budget / 2, "{total}");
    assert!(instances.iter().any(|(_, n)| *n == 0), "trees beyond far");
}

/// The leaves of every instance of every variant node, from its `extras.pge.lod.leaves`.
fn node_leaves(glb: &[u8]) -> BTreeMap<String, Vec<u64>> {
    let gltf = gltf::Gltf::from_slice(glb).expect("a glb");
    let json = gltf.document.as_json();
    let mut out = BTreeMap::new();
    for node in &json.nodes {
        let (Some(mesh), Some(extras)) = (node.mesh, &node.extras) else {
            continue;
        };
        let name = json.meshes[mesh.value()].name.clone().unwrap_or_default();
        let extras: serde_json::Value = serde_json::from_str(extras.get()).expect("json");
        let leaves = extras["pge"]["lod"]["leaves"].as_array().expect("leaves");
        out.insert(
            name,
            leaves.iter().map(|n| n.as_u64().expect("count")).collect(),
        );
    }
    out
}

#[test]
fn unique_trees_keep_their_identity_in_every_tile() {
    let (dir, script) = bad_script(
        "local f = pge.Forest{ size = {60, 40}, tile = 20, seed = 3 }\n\
         f:scatter{ species = \"stick.lua\", minDistance = 5, variants = \"unique\" }\n\
         return f\n",
    );
    let script = script.to_string_lossy().to_string();
    let whole = out_path(dir.path(), "whole.glb");
    run_ok(&["run", &script, "-o", &whole, "-q"]);
    let whole = placements(&std::fs::read(&whole).expect("whole"));
    // One mesh per tree, named after the tree's identity.
    let trees: Vec<_> = whole
        .iter()
        .filter(|(name, _)| *name != "terrain")
        .collect();
    assert!(trees.len() > 20, "{}", trees.len());
    assert!(trees.iter().all(|(_, list)| list.len() == 1));
    let mut union: BTreeMap<String, Vec<Placement>> = BTreeMap::new();
    for (i, j) in [(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 1)] {
        let out = out_path(dir.path(), &format!("{i}_{j}.glb"));
        let tile = format!("{i},{j}");
        run_ok(&["run", &script, "-o", &out, "-q", "--tile", &tile]);
        for (name, list) in placements(&std::fs::read(&out).expect("tile")) {
            if name != "terrain" {
                assert!(!union.contains_key(&name), "{name} in two tiles");
                union.insert(name, list);
            }
        }
    }
    let whole: BTreeMap<String, Vec<Placement>> = trees
        .into_iter()
        .map(|(n, l)| (n.clone(), l.clone()))
        .collect();
    assert_eq!(union, whole);
}

#[test]
fn a_layer_that_fits_nowhere_is_a_warning_in_the_stats() {
    let (dir, script) = bad_script(&format!(
        "{HEAD}f:scatter{{ species = \"stick.lua\", minDistance = 3, altitude = {{100, 200}} }}\nreturn f\n"
    ));
    let out = dir.path().join("out.glb").to_string_lossy().to_string();
    let script = script.to_string_lossy().to_string();
    let o = run_ok(&["run", &script, "-o", &out, "-q", "--stats"]);
    let stats: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(stats["instances"], 0);
    let warnings = stats["warnings"].as_array().expect("warnings");
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().is_some_and(|w| w.contains("fits no tree"))),
        "{warnings:?}"
    );
}
