//! Tiles that share their variants: `pge run SCRIPT --variants-out DIR` writes the forest's
//! variants once (`variants.bin` and its glTF description `variants.json`), `pge run SCRIPT
//! --tile I,J --variants DIR` writes a small tile that refers to them. Both are the same bytes
//! for any thread count, the tile places the same trees as the standalone tile, the Khronos
//! validator accepts it (with the shared file loaded), and a description that is missing or
//! of another script, seed or parameters is a one-line error, exit 1, nothing written. One
//! `pge run --tile ... --tile ... --out-dir` writes the files of the single runs; a shared
//! tile's `--stats` count and name the variants it refers to; `--variants-out` sums up each
//! variant with its levels of detail (as the standalone tile's meshes carry them).

mod common;

use std::path::{Path, PathBuf};

use common::{pge, pge_ok as run_ok, ray_forest as forest, root, run_validator};
use serde_json::Value;

fn s(p: &Path) -> String {
    p.to_string_lossy().to_string()
}

/// The glb's JSON chunk.
fn json_chunk(path: &Path) -> Value {
    let bytes = std::fs::read(path).expect("read");
    let glb = gltf::binary::Glb::from_slice(&bytes).expect("glb");
    serde_json::from_slice(&glb.json).expect("json chunk")
}

/// Writes the variants into `dir` and tile `tile` into `dir/tiles/I_J.glb`.
fn shared_tile(dir: &Path, tile: &str, threads: &str, extra: &[&str]) -> PathBuf {
    let script = forest();
    let mut args = vec![
        "run",
        &script,
        "--variants-out",
        dir.to_str().expect("utf-8"),
    ];
    args.extend_from_slice(&["-q", "--threads", threads]);
    args.extend_from_slice(extra);
    run_ok(&args);
    let out = dir
        .join("tiles")
        .join(format!("{}.glb", tile.replace(',', "_")));
    std::fs::create_dir_all(out.parent().expect("folder")).expect("tiles folder");
    let (d, o) = (s(dir), s(&out));
    let mut args = vec![
        "run",
        &script,
        "--tile",
        tile,
        "--variants",
        &d,
        "-o",
        &o,
        "-q",
    ];
    args.extend_from_slice(&["--threads", threads]);
    args.extend_from_slice(extra);
    run_ok(&args);
    out
}

#[test]
fn shared_variants_are_written_once_and_tiles_refer_to_them_byte_for_byte() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    let a = shared_tile(&one, "1,2", "1", &[]);
    let b = shared_tile(&two, "1,2", "2", &[]);
    for name in ["variants.bin", "variants.json"] {
        assert_eq!(
            std::fs::read(one.join(name)).expect("one"),
            std::fs::read(two.join(name)).expect("two"),
            "{name} differs between 1 and 2 threads"
        );
    }
    assert_eq!(std::fs::read(&a).expect("a"), std::fs::read(&b).expect("b"));

    // The tile: its own buffer and the shared file by a relative URI.
    let tile = json_chunk(&a);
    assert_eq!(tile["buffers"][1]["uri"], "../variants.bin");
    assert_eq!(
        tile["buffers"][1]["byteLength"].as_u64(),
        Some(
            std::fs::metadata(one.join("variants.bin"))
                .expect("bin")
                .len()
        )
    );
    assert!(tile["buffers"][0].get("uri").is_none());

    // The same trees, stats and extras as the standalone tile; far fewer bytes.
    let standalone = dir.path().join("standalone.glb");
    run_ok(&[
        "run",
        &forest(),
        "--tile",
        "1,2",
        "-o",
        &s(&standalone),
        "-q",
    ]);
    let alone = json_chunk(&standalone);
    assert_eq!(tile["extras"], alone["extras"]);
    let placed = |j: &Value| -> Vec<(String, Value)> {
        let mut v: Vec<(String, Value)> = j["nodes"]
            .as_array()
            .expect("nodes")
            .iter()
            .filter_map(|n| {
                let mesh = n["mesh"].as_u64()? as usize;
                let name = j["meshes"][mesh]["name"].as_str()?.to_string();
                let count = n
                    .pointer("/extensions/EXT_mesh_gpu_instancing/attributes/TRANSLATION")
                    .and_then(Value::as_u64)
                    .map(|t| j["accessors"][t as usize]["count"].clone())
                    .unwrap_or(Value::Null);
                Some((name, count))
            })
            .collect();
        v.sort_by(|x, y| x.0.cmp(&y.0));
        v
    };
    assert_eq!(placed(&tile), placed(&alone));
    let (small, big) = (
        std::fs::metadata(&a).expect("tile").len(),
        std::fs::metadata(&standalone).expect("standalone").len(),
    );
    assert!(small * 10 < big, "{small} bytes against {big}");

    // The tile, whole with its shared file, and the description (a glTF of its own) pass.
    let description = dir.path().join("one").join("description.gltf");
    std::fs::copy(one.join("variants.json"), &description).expect("copy");
    let (passed, report) = run_validator(&[a.clone(), description]);
    println!("{report}");
    assert!(passed, "the glTF validator found errors:\n{report}");
    assert!(report.contains(" 0 errors"), "{report}");
}

/// Runs `pge` expecting a one-line error, exit 1, and `out` not written.
fn expect_error(args: &[&str], needles: &[&str], out: &Path) {
    let o = pge(args);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    for n in needles {
        assert!(err.contains(n), "'{n}' not in: {err}");
    }
    assert!(!out.exists(), "{} was written", out.display());
}

#[test]
fn variants_that_are_missing_or_of_another_run_are_one_line_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let v = dir.path().join("v");
    run_ok(&["run", &forest(), "--variants-out", &s(&v), "-q"]);
    let out = dir.path().join("tile.glb");
    let (vs, os, script) = (s(&v), s(&out), forest());
    let tile = |extra: &[&str]| {
        let mut a = vec!["run", script.as_str(), "--tile", "0,0", "-o", &os, "-q"];
        a.extend_from_slice(extra);
        a.iter().map(|x| x.to_string()).collect::<Vec<_>>()
    };
    let call = |extra: &[&str], needles: &[&str]| {
        let args = tile(extra);
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        expect_error(&refs, needles, &out);
    };
    let missing = s(&dir.path().join("nothing"));
    call(
        &["--variants", &missing],
        &["variants.json", "no shared variants", "--variants-out"],
    );
    call(
        &["--variants", &vs, "--seed", "2"],
        &["another seed", "--variants-out"],
    );
    call(
        &["--variants", &vs, "--set", "spin=3"],
        &["other parameters", "--variants-out"],
    );
    // Another script: the same forest with one more line.
    let other = dir.path().join("other.lua");
    let text = std::fs::read_to_string(forest()).expect("script");
    std::fs::write(&other, format!("-- another\n{text}")).expect("script");
    std::fs::copy(
        root().join("integrations/ray/tests/shrub.lua"),
        dir.path().join("shrub.lua"),
    )
    .expect("shrub");
    let o = s(&other);
    expect_error(
        &[
            "run",
            &o,
            "--tile",
            "0,0",
            "--variants",
            &vs,
            "-o",
            &os,
            "-q",
        ],
        &["another script", "--variants-out"],
        &out,
    );
    // A damaged description, and a binary file of the wrong length.
    let description = v.join("variants.json");
    let good = std::fs::read(&description).expect("description");
    std::fs::write(&description, &good[..good.len() / 2]).expect("damaged");
    call(&["--variants", &vs], &["not a shared variants description"]);
    std::fs::write(&description, &good).expect("restored");
    std::fs::write(v.join("variants.bin"), b"short").expect("damaged");
    call(&["--variants", &vs], &["variants.bin", "bytes"]);
    // A script that returns no forest.
    let spiral = s(&root().join("scripts/examples/spiral.lua"));
    let w = s(&dir.path().join("w"));
    expect_error(
        &["run", &spiral, "--variants-out", &w, "-q"],
        &["--variants-out needs a script that returns a forest"],
        &dir.path().join("w").join("variants.json"),
    );
    // --variants with an .obj output is a usage error.
    let obj = s(&dir.path().join("tile.obj"));
    let o = pge(&[
        "run",
        &script,
        "--tile",
        "0,0",
        "--variants",
        &vs,
        "-o",
        &obj,
    ]);
    assert_eq!(o.status.code(), Some(2));
}

/// The JSON lines `pge` printed on stdout.
fn json_lines(stdout: &[u8]) -> Vec<Value> {
    String::from_utf8_lossy(stdout)
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect()
}

#[test]
fn one_process_writes_several_tiles_and_their_stats_name_the_shared_variants() {
    let dir = tempfile::tempdir().expect("tempdir");
    let world = dir.path().join("world");
    let one = shared_tile(&world, "1,2", "1", &[]);
    let script = forest();
    let w = s(&world);
    let other = world.join("tiles").join("0_3.glb");
    run_ok(&[
        "run",
        &script,
        "--tile",
        "0,3",
        "--variants",
        &w,
        "-o",
        &s(&other),
        "-q",
    ]);

    // --tile twice, --out-dir: the files of the single runs, one stats line per tile.
    let batch = world.join("batch");
    let stdout = run_ok(&[
        "run",
        &script,
        "--tile",
        "1,2",
        "--tile",
        "0,3",
        "--variants",
        &w,
        "--out-dir",
        &s(&batch),
        "-q",
        "--stats",
        "--threads",
        "1",
    ]);
    for (file, single) in [("1_2.glb", &one), ("0_3.glb", &other)] {
        assert_eq!(
            std::fs::read(batch.join(file)).expect("batch tile"),
            std::fs::read(single).expect("single tile"),
            "{file}"
        );
    }
    let stats = json_lines(&stdout);
    assert_eq!(stats.len(), 2, "{stats:?}");
    assert_eq!(stats[0]["tile"], serde_json::json!([1, 2]));
    assert_eq!(stats[1]["tile"], serde_json::json!([0, 3]));

    // A shared tile's stats count what its glb's extras.pge.stats count (the shared
    // variants' instances too) and list the variants it refers to, from variants.json.
    let description: Value =
        serde_json::from_slice(&std::fs::read(world.join("variants.json")).expect("json"))
            .expect("description");
    let groups = description["extras"]["pge"]["variants"]["groups"]
        .as_array()
        .expect("groups");
    for (line, file) in stats.iter().zip(["1_2.glb", "0_3.glb"]) {
        let extras = json_chunk(&batch.join(file))["extras"]["pge"]["stats"].clone();
        for key in ["vertices", "triangles", "nodes", "leaves"] {
            assert_eq!(line[key], extras[key], "{file}: {key}");
        }
        assert!(line["nodes"].as_u64() > Some(0), "{line}");
        let referred = line["variants"].as_array().expect("variants");
        assert!(!referred.is_empty(), "{line}");
        let mut nodes = 0;
        for v in referred {
            let g = groups
                .iter()
                .find(|g| g["name"] == v["name"])
                .expect("a variant of the description");
            assert_eq!((&v["nodes"], &v["leaves"]), (&g["nodes"], &g["leaves"]));
            assert!(v["instances"].as_u64() > Some(0));
            nodes += v["instances"].as_u64().expect("n") * v["nodes"].as_u64().expect("nodes");
        }
        // The unique trees (the function species) are the tile's own.
        assert!(nodes <= line["nodes"].as_u64().expect("nodes"), "{line}");
    }

    // Several tiles without --out-dir, and --out-dir without --tile, are usage errors.
    for args in [
        vec!["run", &script, "--tile", "0,0", "--tile", "1,1", "-q"],
        vec!["run", &script, "--out-dir", &w, "-q"],
    ] {
        assert_eq!(pge(&args).status.code(), Some(2), "{args:?}");
    }
    // A tile that fails stops the run naming it; the tiles before it are written.
    let failing = dir.path().join("failing");
    let o = pge(&[
        "run",
        &script,
        "--tile",
        "0,0",
        "--tile",
        "9,9",
        "--variants",
        &w,
        "--out-dir",
        &s(&failing),
        "-q",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with("tile 9,9: ") && err.trim().lines().count() == 1,
        "{err}"
    );
    assert!(failing.join("0_0.glb").exists() && !failing.join("9_9.glb").exists());
}

#[test]
fn the_variants_written_are_summed_up_with_their_levels_of_detail() {
    let dir = tempfile::tempdir().expect("tempdir");
    let script = dir.path().join("leafy.lua");
    std::fs::write(
        &script,
        r##"local forest = pge.Forest{ size = {40, 40}, seed = 2, tile = 20 }
forest:scatter{ species = function(params, seed)
                  return pge.SpaceColonization{
                    envelope = pge.shape.ellipsoid{ center = {0, 0.8, 0}, radii = {0.8, 0.6, 0.8} },
                    points = 40, step = 0.15, influence = 0.8, kill = 0.25, roots = {{0, 0, 0}},
                    mesh = { sides = 4, color = "#5e4b3b" },
                    leaves = { perTip = {1, 2}, size = 0.15, maxDepth = 1, colors = {"#3d6b25"} },
                    lod = true }
                end, minDistance = 4, variants = 2 }
return forest
"##,
    )
    .expect("script");
    let script = s(&script);
    let world = dir.path().join("world");
    let stdout = run_ok(&[
        "run",
        &script,
        "--variants-out",
        &s(&world),
        "-q",
        "--stats",
    ]);
    let stats = json_lines(&stdout);
    let summary = stats[0]["variants"].as_array().expect("variants");
    assert_eq!(summary.len(), 2, "{summary:?}");
    let description: Value =
        serde_json::from_slice(&std::fs::read(world.join("variants.json")).expect("json"))
            .expect("description");
    // The standalone tile's variant meshes carry the same levels as the description's.
    let tile = dir.path().join("tile.glb");
    run_ok(&["run", &script, "--tile", "0,0", "-o", &s(&tile), "-q"]);
    let standalone = json_chunk(&tile);
    for (k, v) in summary.iter().enumerate() {
        assert!(
            v["name"]
                .as_str()
                .is_some_and(|n| n.ends_with(&format!("/{k}"))),
            "{v}"
        );
        let lod = &v["lod"];
        let (leaves, roots) = (
            lod["leaves"].as_u64().expect("leaves"),
            lod["roots"].as_u64().expect("roots"),
        );
        assert!(roots > 0 && leaves > roots, "{v}");
        assert_eq!(lod["levels"].as_u64(), Some(leaves - roots + 1));
        let mesh = description["extras"]["pge"]["variants"]["groups"][k]["mesh"]
            .as_u64()
            .expect("mesh") as usize;
        let described = &description["meshes"][mesh]["extras"]["pge"]["lod"];
        assert_eq!(described["leaves"].as_u64(), Some(leaves), "{described}");
        assert!(described["primitives"].is_array(), "{described}");
        let name = v["name"].as_str().expect("name");
        if let Some(own) = standalone["meshes"]
            .as_array()
            .expect("meshes")
            .iter()
            .find(|m| m["name"] == name)
        {
            assert_eq!(&own["extras"]["pge"]["lod"], described, "{name}");
        }
    }
    // Without --stats, one line per variant on stdout.
    let again = dir.path().join("again");
    let text =
        String::from_utf8(run_ok(&["run", &script, "--variants-out", &s(&again)])).expect("utf-8");
    assert_eq!(text.lines().count(), 2, "{text}");
    assert!(text.contains("LOD levels"), "{text}");
}
