//! Forests with foliage levels of detail, end to end: real forest scripts whose shrubs have
//! levels (from their species or from the forest's `lod`), written by `pge run` and read
//! back. Every variant keeps its vector V and LOD table; each instance's leaves for the
//! forest's camera, in the node extras, equal `pge_lod::assign` on the instances'
//! distances, never exceed the budget, never give a nearer shrub fewer leaves, agree between
//! tiles and the whole forest (and `pge merge` of the tiles), with one or two threads, and
//! match `forest:instances()`.
//! Bad options are `FILE:LINE:` errors naming the option.

mod common;

use std::collections::BTreeMap;
use std::path::Path;

use common::{pge, root};
use glam::Vec3;
use pge_engine::SessionOptions;
use pge_engine::mlua::{ObjectLike, Table, Value as LuaValue};
use pge_lod::{Budget, assign};
use serde_json::Value;

const FOREST: &str = "tests/scripts/forest_lod/forest.lua";
const PLAIN: &str = "tests/scripts/forest_lod/plain.lua";
/// The camera of forest.lua.
const CAMERA: [f32; 3] = [-30.0, 2.0, -5.0];
const NEAR: f32 = 4.0;
const FAR: f32 = 45.0;

/// Runs `pge run SCRIPT -o DIR/NAME.glb -q ARGS...`; the glb.
fn run(script: &str, dir: &Path, name: &str, args: &[&str]) -> Vec<u8> {
    let out = dir
        .join(format!("{name}.glb"))
        .to_string_lossy()
        .to_string();
    let mut all = vec!["run", script, "-o", &out, "-q"];
    all.extend_from_slice(args);
    let o = pge(&all);
    assert!(
        o.status.success(),
        "pge {all:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::read(&out).expect("the glb")
}

fn json(glb: &[u8]) -> Value {
    let len = u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize;
    serde_json::from_slice(&glb[20..20 + len]).expect("json chunk")
}

/// One shrub as the glb places it: its translation and its node extras' leaves and level.
#[derive(Clone, Debug, PartialEq)]
struct Placed {
    at: [f32; 3],
    leaves: u64,
    level: i64,
}

/// Every variant's placements, by mesh name, in the order of the glb, with their leaves.
fn placed(glb: &[u8]) -> BTreeMap<String, Vec<Placed>> {
    let (doc, buffers, _) = gltf::import_slice(glb).expect("a valid glb");
    let raw = json(glb);
    let floats = |accessor: u64| -> Vec<f32> {
        let a = doc.accessors().nth(accessor as usize).expect("accessor");
        gltf::accessor::Iter::<[f32; 3]>::new(a, |b| Some(&buffers[b.index()]))
            .expect("data")
            .flatten()
            .collect()
    };
    let mut out: BTreeMap<String, Vec<Placed>> = BTreeMap::new();
    for (k, node) in raw["nodes"].as_array().expect("nodes").iter().enumerate() {
        let Some(mesh) = node["mesh"].as_u64() else {
            continue;
        };
        let name = raw["meshes"][mesh as usize]["name"]
            .as_str()
            .expect("name")
            .to_string();
        if name == "terrain" {
            continue;
        }
        let lod = &node["extras"]["pge"]["lod"];
        let ext = &node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
        let list = out.entry(name.clone()).or_default();
        if ext.is_object() {
            let t = floats(ext["TRANSLATION"].as_u64().expect("t"));
            let leaves = lod["leaves"].as_array().expect("leaves");
            let levels = lod["level"].as_array().expect("level");
            assert_eq!(leaves.len() * 3, t.len(), "{name}: {k}");
            for (i, (n, l)) in leaves.iter().zip(levels).enumerate() {
                list.push(Placed {
                    at: [t[3 * i], t[3 * i + 1], t[3 * i + 2]],
                    leaves: n.as_u64().expect("count"),
                    level: l.as_i64().expect("level"),
                });
            }
        } else {
            let t = &node["translation"];
            list.push(Placed {
                at: [0, 1, 2].map(|c| t[c].as_f64().expect("translation") as f32),
                leaves: lod["leaves"].as_u64().expect("count"),
                level: lod["level"].as_i64().expect("level"),
            });
        }
    }
    out
}

/// Every variant mesh's `extras.pge.lod`, by name.
fn variant_tables(glb: &[u8]) -> BTreeMap<String, Value> {
    let raw = json(glb);
    raw["meshes"]
        .as_array()
        .expect("meshes")
        .iter()
        .filter(|m| m["name"] != "terrain")
        .map(|m| {
            (
                m["name"].as_str().expect("name").to_string(),
                m["extras"]["pge"]["lod"].clone(),
            )
        })
        .collect()
}

fn distance(at: [f32; 3]) -> f32 {
    Vec3::from_array(CAMERA).distance(Vec3::from_array(at))
}

/// The leaves `pge_lod::assign` gives each variant's placements (in the glb's order, which
/// is the layout's): the total shared among variants by their tentative leaves.
fn expected(
    placed: &BTreeMap<String, Vec<Placed>>,
    tables: &BTreeMap<String, Value>,
    total: u64,
) -> BTreeMap<String, Vec<u32>> {
    let lod = |name: &str| {
        let t = &tables[name];
        (
            t["leaves"].as_u64().expect("leaves") as u32,
            t["roots"].as_u64().expect("roots") as u32,
        )
    };
    let budget = Budget {
        near: NEAR,
        far: FAR,
        total,
    };
    let tentative: BTreeMap<&String, u128> = placed
        .iter()
        .map(|(name, list)| {
            let (o, r) = lod(name);
            let sum = list
                .iter()
                .map(|p| u128::from(budget.tentative(distance(p.at), o, r)))
                .sum();
            (name, sum)
        })
        .collect();
    let all: u128 = tentative.values().sum();
    placed
        .iter()
        .map(|(name, list)| {
            let (o, r) = lod(name);
            let share = (u128::from(total) * tentative[name] / all) as u64;
            let d: Vec<f32> = list.iter().map(|p| distance(p.at)).collect();
            let own = Budget {
                total: share,
                ..budget
            };
            (name.clone(), assign(&d, o, r, &own).expect("assign"))
        })
        .collect()
}

/// `forest:instances()` of a script through the library: position -> (leaves, level).
fn script_leaves(script: &str) -> BTreeMap<[u32; 3], (u32, i64)> {
    let engine = pge::default_engine().build().expect("engine");
    let session = engine.session(SessionOptions::default()).expect("session");
    let value = session
        .run_script(&root().join(script))
        .expect("script runs");
    let LuaValue::UserData(forest) = value else {
        panic!("not a forest")
    };
    let list: Table = forest.call_method("instances", ()).expect("instances");
    list.sequence_values::<Table>()
        .map(|t| {
            let t = t.expect("table");
            let p: pge_engine::lua::LuaVec3 = t.get("position").expect("position");
            let key = p.0.to_array().map(f32::to_bits);
            (
                key,
                (
                    t.get("leaves").expect("leaves"),
                    t.get("level").expect("level"),
                ),
            )
        })
        .collect()
}

#[test]
fn each_shrubs_leaves_are_the_budget_of_assign_within_the_total() {
    let dir = tempfile::tempdir().expect("tempdir");
    let glb = run(FOREST, dir.path(), "forest", &[]);
    let tables = variant_tables(&glb);
    assert_eq!(tables.len(), 5, "{:?}", tables.keys());
    // Every variant keeps V and its table: a + c = |R| + i, the ranges inside V.
    let (doc, buffers, _) = gltf::import_slice(&glb).expect("valid");
    for (name, lod) in &tables {
        let (o, r) = (
            lod["leaves"].as_u64().expect("leaves"),
            lod["roots"].as_u64().expect("roots"),
        );
        assert!(r >= 1 && r < o, "{name}: {lod}");
        let primitives = lod["primitives"].as_array().expect("primitives");
        assert_eq!(primitives.len(), 1, "{name}");
        let p = &primitives[0];
        assert_eq!(
            (p["leaves"].as_u64(), p["roots"].as_u64()),
            (Some(o), Some(r))
        );
        let table = p["table"].as_array().expect("table");
        assert_eq!(table.len() as u64, o - r + 1);
        let size = 2 * o - r;
        for (i, row) in table.iter().enumerate() {
            let [a, b, c] = [0, 1, 2].map(|k| row[k].as_u64().expect("entry"));
            assert_eq!(a + c, r + i as u64, "{name} row {i}");
            assert!(a <= b && b + c <= size, "{name} row {i}: {row}");
        }
        // The leaf primitive holds V (four vertices a leaf) and draws the finest level.
        let mesh = doc.meshes().find(|m| m.name() == Some(name)).expect("mesh");
        let prim = mesh
            .primitives()
            .nth(p["primitive"].as_u64().expect("primitive") as usize)
            .expect("the leaf primitive");
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        assert_eq!(
            reader.read_positions().expect("positions").count() as u64,
            4 * size
        );
        assert_eq!(
            reader.read_indices().expect("indices").into_u32().count() as u64,
            6 * o
        );
    }
    let placed = placed(&glb);
    let want = expected(&placed, &tables, 3000);
    let mut total = 0u64;
    for (name, list) in &placed {
        let got: Vec<u32> = list.iter().map(|p| p.leaves as u32).collect();
        assert_eq!(got, want[name], "{name}");
        let roots = tables[name]["roots"].as_i64().expect("roots");
        for p in list {
            total += p.leaves;
            let level = if p.leaves > 0 {
                p.leaves as i64 - roots
            } else {
                -1
            };
            assert_eq!(p.level, level);
            // A nearer shrub of the same variant never draws fewer leaves.
            for q in list {
                if distance(p.at) < distance(q.at) {
                    assert!(p.leaves >= q.leaves, "{name}: {p:?} {q:?}");
                }
            }
        }
    }
    assert!(total <= 3000 && total > 1500, "{total}");
    let drawn = placed.values().flatten().filter(|p| p.leaves > 0).count();
    let hidden = placed.values().flatten().filter(|p| p.leaves == 0).count();
    assert!(
        drawn > 5 && hidden > 5,
        "{drawn} drawn, {hidden} beyond far"
    );
    // forest:instances() gives the same leaves and levels.
    let from_lua = script_leaves(FOREST);
    assert_eq!(from_lua.len(), placed.values().map(Vec::len).sum::<usize>());
    for p in placed.values().flatten() {
        let key = p.at.map(f32::to_bits);
        assert_eq!(from_lua[&key], (p.leaves as u32, p.level), "{p:?}");
    }
    // One node per shrub carries the same numbers.
    let nodes = run(FOREST, dir.path(), "nodes", &["--instancing", "nodes"]);
    let mut by_node = self::placed(&nodes);
    let mut by_gpu = placed.clone();
    let key = |p: &Placed| p.at.map(f32::to_bits);
    for list in by_node.values_mut().chain(by_gpu.values_mut()) {
        list.sort_by_key(key);
    }
    assert_eq!(by_node, by_gpu);
    // A tighter budget draws fewer leaves, still within it.
    let tight = run(FOREST, dir.path(), "tight", &["--set", "total=400"]);
    let tight_total: u64 = self::placed(&tight)
        .values()
        .flatten()
        .map(|p| p.leaves)
        .sum();
    assert!(tight_total <= 400 && tight_total < total, "{tight_total}");
}

#[test]
fn tiles_and_thread_counts_agree_with_the_whole_forest() {
    let dir = tempfile::tempdir().expect("tempdir");
    let one = run(FOREST, dir.path(), "one", &["--threads", "1"]);
    let two = run(FOREST, dir.path(), "two", &["--threads", "2"]);
    assert!(one == two, "the glb differs between 1 and 2 threads");
    let whole: BTreeMap<[u32; 3], Placed> = placed(&one)
        .into_values()
        .flatten()
        .map(|p| (p.at.map(f32::to_bits), p))
        .collect();
    let mut union = BTreeMap::new();
    let world = dir.path().join("world");
    std::fs::create_dir_all(world.join("tiles")).expect("world folder");
    let mut entries = Vec::new();
    for (i, j) in [(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 1)] {
        let tile = format!("{i},{j}");
        let glb = run(
            FOREST,
            &world.join("tiles"),
            &format!("{i}_{j}"),
            &["--tile", &tile],
        );
        for p in placed(&glb).into_values().flatten() {
            union.insert(p.at.map(f32::to_bits), p);
        }
        let file = format!("tiles/{i}_{j}.glb");
        entries.push(serde_json::json!({ "i": i, "j": j, "file": file,
            "sha256": sha256(&world.join(&file)) }));
    }
    assert_eq!(union, whole);
    // `pge merge` keeps the variants' tables and every instance's leaves.
    let manifest = serde_json::json!({ "format": "pge-world/1", "seed": 9, "params": {},
        "complete": true, "tiles": entries });
    std::fs::write(world.join("world.json"), manifest.to_string()).expect("manifest");
    let merged = world.join("world.glb").to_string_lossy().to_string();
    let o = pge(&["merge", &world.to_string_lossy(), "-o", &merged]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let merged = std::fs::read(&merged).expect("merged");
    assert_eq!(variant_tables(&merged), variant_tables(&one));
    let merged: BTreeMap<[u32; 3], Placed> = placed(&merged)
        .into_values()
        .flatten()
        .map(|p| (p.at.map(f32::to_bits), p))
        .collect();
    assert_eq!(merged, whole);
}

#[test]
fn the_glb_is_valid_and_a_variant_cache_changes_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let gpu = run(FOREST, dir.path(), "gpu", &[]);
    let nodes = run(FOREST, dir.path(), "nodes", &["--instancing", "nodes"]);
    assert!(!gpu.is_empty() && !nodes.is_empty());
    let outputs = [dir.path().join("gpu.glb"), dir.path().join("nodes.glb")];
    let (passed, report) = common::run_validator(&outputs);
    assert!(passed, "the glTF validator found errors:\n{report}");
    // Cold and warm variant caches give the same bytes, for the species' own levels and the
    // forest's.
    let cache = dir.path().join("cache").to_string_lossy().to_string();
    for (script, set) in [(FOREST, "own=1"), (PLAIN, "own=0")] {
        let plain = run(script, dir.path(), "plain", &["--set", set]);
        for name in ["cold", "warm"] {
            let cached = run(
                script,
                dir.path(),
                name,
                &["--set", set, "--variant-cache", &cache],
            );
            assert!(
                cached == plain,
                "{script} {set}: the {name} cache changed the glb"
            );
        }
    }
}

fn sha256(path: &Path) -> String {
    let o = std::process::Command::new("sha256sum")
        .arg(path)
        .output()
        .expect("sha256sum runs");
    let text = String::from_utf8_lossy(&o.stdout);
    text.split_whitespace().next().expect("a hash").to_string()
}

#[test]
fn the_forests_lod_gives_variants_the_levels_their_species_would_have() {
    let dir = tempfile::tempdir().expect("tempdir");
    let own = run(PLAIN, dir.path(), "own", &["--set", "own=1"]);
    let given = run(PLAIN, dir.path(), "given", &["--set", "own=0"]);
    let tables = variant_tables(&own);
    assert_eq!(tables, variant_tables(&given));
    assert!(
        tables.values().all(|t| t["primitives"].is_array()),
        "{tables:?}"
    );
    let vertices = |glb: &[u8]| -> BTreeMap<String, Vec<[f32; 3]>> {
        let (doc, buffers, _) = gltf::import_slice(glb).expect("valid");
        doc.meshes()
            .map(|m| {
                let p: Vec<[f32; 3]> = m
                    .primitives()
                    .flat_map(|p| {
                        let r = p.reader(|b| Some(&buffers[b.index()]));
                        r.read_positions().expect("positions").collect::<Vec<_>>()
                    })
                    .collect();
                (m.name().unwrap_or_default().to_string(), p)
            })
            .collect()
    };
    assert_eq!(vertices(&own), vertices(&given));
    // Without a camera no node has counts.
    let raw = json(&own);
    assert!(
        raw["nodes"]
            .as_array()
            .expect("nodes")
            .iter()
            .all(|n| n["extras"]["pge"]["lod"].is_null())
    );
}

/// Runs a forest script written to a temporary folder beside a stick species; its stderr,
/// after checking exit 1 and no output.
fn error_of(body: &str) -> String {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("stick.lua"),
        "return pge.mesh{ positions = {0,0,0, 0.2,0,0, 0,2,0}, indices = {0,1,2} }\n",
    )
    .expect("species");
    let script = dir.path().join("forest.lua");
    std::fs::write(&script, body).expect("script");
    let out = dir.path().join("out.glb");
    let (script, out_s) = (
        script.to_string_lossy().to_string(),
        out.to_string_lossy().to_string(),
    );
    let o = pge(&["run", &script, "-o", &out_s, "-q"]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "{body}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists(), "an output file was left behind");
    err
}

#[test]
fn bad_lod_options_are_file_line_errors_naming_the_option() {
    let with = |lod: &str| {
        format!(
            "local f = pge.Forest{{ size = 40,\n  lod = {lod} }}\n\
             f:scatter{{ species = \"stick.lua\", minDistance = 4 }}\nreturn f\n"
        )
    };
    let camera = "camera = {0, 1, 0}, total = 100";
    for (lod, needles) in [
        (
            "{ sectors = 0 }",
            vec!["lod.sectors", "between 1 and 64, got 0"],
        ),
        ("{ sectors = 65 }", vec!["lod.sectors", "got 65"]),
        ("{ atlas = 1 }", vec!["lod.atlas"]),
        (
            &*format!("{{ {camera}, near = -1, far = 10 }}"),
            vec!["lod.near", ">= 0, got -1"],
        ),
        (
            &*format!("{{ {camera}, near = 0/0, far = 10 }}"),
            vec!["lod.near", "NaN"],
        ),
        (
            &*format!("{{ {camera}, near = 1, far = -2 }}"),
            vec!["lod.far", "got -2"],
        ),
        (
            &*format!("{{ {camera}, near = 20, far = 10 }}"),
            vec!["lod.near must be at most lod.far", "near = 20 and far = 10"],
        ),
        (
            &*format!("{{ {camera}, near = 1 }}"),
            vec![
                "lod.far is required",
                "camera, total, near and far go together",
            ],
        ),
        (
            "{ total = 10, near = 1, far = 2 }",
            vec!["lod.camera is required"],
        ),
        (
            "{ camara = {0, 1, 0} }",
            vec!["unknown option 'lod.camara'"],
        ),
        ("{ total = -5 }", vec!["lod.total"]),
        ("3", vec!["lod must be a table"]),
    ] {
        let err = error_of(&with(lod));
        assert!(err.contains("forest.lua:1:"), "{lod}: {err}");
        assert!(err.contains("pge.Forest"), "{lod}: {err}");
        for n in needles {
            assert!(err.contains(n), "{lod}: '{n}' not in: {err}");
        }
    }
    // A camera cannot budget "unique" trees: a tile could not know the others' leaves.
    let err = error_of(
        "local f = pge.Forest{ size = 40,\n  lod = { camera = {0, 1, 0}, total = 9, near = 1, far = 9 } }\n\
         f:scatter{ species = \"stick.lua\", minDistance = 4, variants = \"unique\" }\nreturn f\n",
    );
    assert!(err.contains("forest.lua:1:"), "{err}");
    assert!(
        err.contains("pge.Forest: lod.camera cannot budget layer 1 (stick)"),
        "{err}"
    );
}
