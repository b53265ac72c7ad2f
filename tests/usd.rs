//! USD export end to end: real scripts written as `.usda` and `.usdz` hold as many meshes,
//! points and instances as the same run's glb; textures sit beside the layer (or inside the
//! package, 64-byte aligned); stages are variants; the bytes do not depend on the threads.
//! (`.ci/usd` checks the same files with usd-core's validators.)

mod common;

use std::path::Path;

use common::pge;

const SMALL_FOREST: &[&str] = &["--set", "points=150", "--set", "size=100"];

fn run_ok(args: &[&str]) {
    let o = pge(args);
    assert!(
        o.status.success(),
        "pge {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

fn run(script: &str, out: &Path, extra: &[&str]) {
    let out = out.to_string_lossy().to_string();
    let mut args = vec!["run", script, "-o", &out, "-q"];
    args.extend_from_slice(extra);
    run_ok(&args);
}

/// Meshes, their points and the instances of a `.usda` text (each prototype once).
fn usda_counts(text: &str) -> (usize, usize, usize) {
    let mut counts = (0, 0, 0);
    for line in text.lines().map(str::trim_start) {
        if line.starts_with("def Mesh ") {
            counts.0 += 1;
        } else if let Some(points) = line.strip_prefix("point3f[] points = [") {
            counts.1 += points.matches('(').count();
        } else if let Some(indices) = line.strip_prefix("int[] protoIndices = [") {
            counts.2 += indices.split(',').count();
        }
    }
    counts
}

/// The same counts of a glb's default scene: triangle primitives of the nodes' meshes, their
/// vertices, and the placements of the nodes with `EXT_mesh_gpu_instancing`.
fn glb_counts(glb: &[u8]) -> (usize, usize, usize) {
    let len = u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize;
    let gltf: serde_json::Value = serde_json::from_slice(&glb[20..20 + len]).expect("json");
    let scene = &gltf["scenes"][gltf["scene"].as_u64().unwrap_or(0) as usize];
    let mut stack: Vec<u64> = scene["nodes"]
        .as_array()
        .expect("nodes")
        .iter()
        .filter_map(serde_json::Value::as_u64)
        .collect();
    let count = |accessor: &serde_json::Value| {
        gltf["accessors"][accessor.as_u64().expect("an accessor") as usize]["count"]
            .as_u64()
            .expect("a count") as usize
    };
    let mut counts = (0, 0, 0);
    while let Some(n) = stack.pop() {
        let node = &gltf["nodes"][n as usize];
        if let Some(children) = node["children"].as_array() {
            stack.extend(children.iter().filter_map(serde_json::Value::as_u64));
        }
        let Some(mesh) = node["mesh"].as_u64() else {
            continue;
        };
        for p in gltf["meshes"][mesh as usize]["primitives"]
            .as_array()
            .expect("primitives")
        {
            if p["mode"].as_u64().unwrap_or(4) == 4 {
                counts.0 += 1;
                counts.1 += count(&p["attributes"]["POSITION"]);
            }
        }
        let instancing = &node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
        if instancing.is_object() {
            counts.2 += count(&instancing["TRANSLATION"]);
        }
    }
    counts
}

/// The files of a stored zip in order: (name, data offset, data).
fn zip_entries(zip: &[u8]) -> Vec<(String, usize, Vec<u8>)> {
    let u16_at = |at: usize| usize::from(u16::from_le_bytes([zip[at], zip[at + 1]]));
    let u32_at =
        |at: usize| u32::from_le_bytes([zip[at], zip[at + 1], zip[at + 2], zip[at + 3]]) as usize;
    let mut at = 0;
    let mut out = Vec::new();
    while u32_at(at) == 0x0403_4b50 {
        assert_eq!(u16_at(at + 8), 0, "stored, not compressed");
        let size = u32_at(at + 18);
        let (name_len, extra_len) = (u16_at(at + 26), u16_at(at + 28));
        let name = String::from_utf8(zip[at + 30..at + 30 + name_len].to_vec()).expect("utf-8");
        let start = at + 30 + name_len + extra_len;
        out.push((name, start, zip[start..start + size].to_vec()));
        at = start + size;
    }
    out
}

#[test]
fn the_oak_as_usda_has_the_glbs_meshes_and_its_textures_beside_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (usda, glb) = (dir.path().join("oak.usda"), dir.path().join("oak.glb"));
    run("scripts/species/oak.lua", &usda, &[]);
    run("scripts/species/oak.lua", &glb, &[]);
    let text = std::fs::read_to_string(&usda).expect("the layer");
    let glb = std::fs::read(&glb).expect("the glb");
    let counts = usda_counts(&text);
    assert_eq!(counts, glb_counts(&glb));
    assert!(counts.0 >= 2 && counts.1 > 1000, "{counts:?}");
    assert!(text.contains("upAxis = \"Y\"") && text.contains("defaultPrim = \"PGE\""));
    assert!(
        text.contains("dictionary skeleton = {"),
        "the skeleton as customData"
    );
    // Every texture the layer names is in the folder named after it.
    let mut textures = 0;
    for line in text.lines() {
        if let Some(file) = line.trim().strip_prefix("asset inputs:file = @./") {
            let file = file.trim_end_matches('@');
            assert!(file.starts_with("oak/"), "{file}");
            assert!(dir.path().join(file).is_file(), "{file}");
            textures += 1;
        }
    }
    assert!(
        textures >= 4,
        "colour, normal and roughness maps: {textures}"
    );
}

#[test]
fn a_forest_is_instanced_as_in_the_glb_and_the_same_for_any_thread_count() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = |name: &str| dir.path().join(name);
    let script = "scripts/forests/mixed.lua";
    let mut one = SMALL_FOREST.to_vec();
    one.extend(["--threads", "1"]);
    run(script, &p("mixed.glb"), SMALL_FOREST);
    run(script, &p("mixed.usda"), &one);
    std::fs::create_dir(p("two")).expect("mkdir");
    run(
        script,
        &p("two/mixed.usda"),
        &[SMALL_FOREST, &["--threads", "2"]].concat(),
    );
    run(script, &p("mixed.usdz"), SMALL_FOREST);
    let text = std::fs::read_to_string(p("mixed.usda")).expect("the layer");
    let two = std::fs::read_to_string(p("two/mixed.usda")).expect("the layer");
    assert!(text == two, "the layer differs between 1 and 2 threads");
    let counts = usda_counts(&text);
    assert_eq!(
        counts,
        glb_counts(&std::fs::read(p("mixed.glb")).expect("glb"))
    );
    assert!(counts.2 > 10, "{counts:?}");
    assert!(text.contains("def PointInstancer "));
    // Every prototype is a prim of the layer under its instancer.
    for line in text.lines().map(str::trim_start) {
        let Some(targets) = line.strip_prefix("rel prototypes = [") else {
            continue;
        };
        for target in targets.trim_end_matches(']').split(", ") {
            let path = target.trim_matches(|c| c == '<' || c == '>');
            let (instancer, prototype) = path.rsplit_once("/Prototypes/").expect("a prototype");
            assert!(instancer.starts_with("/PGE/"), "{path}");
            assert!(
                text.contains(&format!("def Xform \"{prototype}\"")),
                "{path}"
            );
        }
    }
    // The package: the layer first, every file stored and 64-byte aligned, the same layer
    // and textures as the folder's.
    let zip = std::fs::read(p("mixed.usdz")).expect("usdz");
    let entries = zip_entries(&zip);
    assert_eq!(entries[0].0, "mixed.usda");
    assert_eq!(entries[0].2, text.as_bytes());
    assert!(entries.len() > 2);
    for (name, start, data) in &entries {
        assert_eq!(start % 64, 0, "{name} at {start}");
        if name != "mixed.usda" {
            assert_eq!(data, &std::fs::read(p(name)).expect("texture"), "{name}");
        }
    }
}

#[test]
fn stages_are_the_variants_of_the_root() {
    let dir = tempfile::tempdir().expect("tempdir");
    let usda = dir.path().join("grow.usda");
    run("scripts/species/oak.lua", &usda, &["--stages", "3,6"]);
    let text = std::fs::read_to_string(&usda).expect("the layer");
    assert!(text.contains("prepend variantSets = \"stage\""));
    assert!(
        text.contains("string stage = \"step_6\""),
        "the last stage selected"
    );
    assert!(text.contains("\"step_3\" {") && text.contains("\"step_6\" {"));
    assert_eq!(
        text.matches("def Material ").count(),
        2,
        "shared by the stages"
    );
}

#[test]
fn a_bad_extension_is_a_usage_error() {
    let o = pge(&["run", "scripts/species/oak.lua", "-o", "oak.usdc"]);
    assert_eq!(o.status.code(), Some(2), "a usage error");
    assert!(String::from_utf8_lossy(&o.stderr).contains(".usda or .usdz"));
}

#[test]
fn a_merged_world_has_the_merged_glbs_meshes_and_instances() {
    // A world of tiles sharing their variants, as `pge-world` writes it.
    let dir = tempfile::tempdir().expect("tempdir");
    let w = dir.path().join("world");
    let d = w.to_string_lossy().to_string();
    let script = common::ray_forest();
    let tiles: serde_json::Value =
        serde_json::from_slice(&common::pge_ok(&["tiles", &script])).expect("json");
    run_ok(&["world", "init", &script, "--out", &d]);
    std::fs::create_dir_all(w.join("tiles")).expect("tiles folder");
    run_ok(&["run", &script, "--variants-out", &d, "-q"]);
    run_ok(&["world", "variants", &d]);
    for t in tiles.as_array().expect("tiles") {
        let tile = format!("{},{}", t["i"], t["j"]);
        let out = w.join(format!("tiles/{}_{}.glb", t["i"], t["j"]));
        let o = out.to_string_lossy().to_string();
        run_ok(&[
            "run",
            &script,
            "--tile",
            &tile,
            "-o",
            &o,
            "-q",
            "--variants",
            &d,
        ]);
        run_ok(&["world", "add", &d, &tile]);
    }
    run_ok(&["world", "finish", &d]);
    let (usda, glb) = (dir.path().join("world.usda"), dir.path().join("world.glb"));
    run_ok(&["merge", &d, "-o", &usda.to_string_lossy()]);
    run_ok(&["merge", &d, "-o", &glb.to_string_lossy()]);
    let text = std::fs::read_to_string(&usda).expect("the layer");
    let counts = usda_counts(&text);
    assert_eq!(counts, glb_counts(&std::fs::read(&glb).expect("glb")));
    assert!(counts.2 > 0, "{counts:?}");
}

#[test]
fn a_tile_has_the_tiles_glb_meshes_and_instances() {
    // Tile 0,0 has a layer that places nothing there: like the glb, the layer leaves it out.
    let dir = tempfile::tempdir().expect("tempdir");
    let script = common::ray_forest();
    let (usda, glb) = (dir.path().join("tile.usda"), dir.path().join("tile.glb"));
    run(&script, &usda, &["--tile", "0,0"]);
    run(&script, &glb, &["--tile", "0,0"]);
    let text = std::fs::read_to_string(&usda).expect("the layer");
    let counts = usda_counts(&text);
    assert_eq!(counts, glb_counts(&std::fs::read(&glb).expect("glb")));
    assert!(!text.contains("int[] protoIndices = []"));
}
