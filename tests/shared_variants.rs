//! Tiles that share their variants: `pge run SCRIPT --variants-out DIR` writes the forest's
//! variants once (`variants.bin` and its glTF description `variants.json`), `pge run SCRIPT
//! --tile I,J --variants DIR` writes a small tile that refers to them. Both are the same bytes
//! for any thread count, the tile places the same trees as the standalone tile, the Khronos
//! validator accepts it (with the shared file loaded), and a description that is missing or
//! of another script, seed or parameters is a one-line error, exit 1, nothing written.

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
