//! End-to-end tests of the `pge` command: scripts in, files and messages out.

mod common;

use common::{pge, root};
use std::path::Path;
use std::process::{Command, Output};

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// A failing run: exit 1, one `FILE:LINE: message` line mentioning `needle`, no panic and
/// no output file.
fn assert_script_error(script: &str, extra: &[&str], file_line: &str, needle: &str) {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out.glb");
    let out_s = out.to_string_lossy().to_string();
    let mut args = vec!["run", script, "-o", out_s.as_str(), "-q"];
    args.extend_from_slice(extra);
    let o = pge(&args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "exit code for {script}: {err}");
    assert!(!err.contains("panicked"), "panic for {script}: {err}");
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "one line for {script}: {err}"
    );
    assert!(
        err.starts_with(file_line),
        "{script}: expected '{file_line}...', got: {err}"
    );
    assert!(
        err.contains(needle),
        "{script}: expected '{needle}' in: {err}"
    );
    assert!(!out.exists(), "{script} left an output file");
    assert_eq!(
        std::fs::read_dir(dir.path()).expect("dir").count(),
        0,
        "{script} left files"
    );
}

macro_rules! script_error {
    ($name:ident, $script:expr, $extra:expr, $file_line:expr, $needle:expr) => {
        #[test]
        fn $name() {
            assert_script_error($script, $extra, $file_line, $needle);
        }
    };
}

const E: &str = "tests/scripts/errors";

script_error!(
    syntax_error,
    &format!("{E}/syntax.lua"),
    &[],
    &format!("{E}/syntax.lua:3: "),
    "unexpected symbol"
);
script_error!(
    runtime_error_deep_in_a_required_module,
    &format!("{E}/deep_require.lua"),
    &[],
    &format!("{E}/lib/deep.lua:4: "),
    "attempt to index a nil value"
);
script_error!(
    os_is_absent,
    &format!("{E}/os_execute.lua"),
    &[],
    &format!("{E}/os_execute.lua:2: "),
    "global 'os'"
);
script_error!(
    io_is_absent,
    &format!("{E}/io_open.lua"),
    &[],
    &format!("{E}/io_open.lua:2: "),
    "global 'io'"
);
script_error!(
    debug_is_absent,
    &format!("{E}/debug_getinfo.lua"),
    &[],
    &format!("{E}/debug_getinfo.lua:2: "),
    "global 'debug'"
);
script_error!(
    require_outside_the_allowed_folders,
    &format!("{E}/require_outside.lua"),
    &[],
    &format!("{E}/require_outside.lua:2: "),
    "outside the script's folder"
);
script_error!(
    endless_loop_hits_the_time_limit,
    &format!("{E}/infinite_loop.lua"),
    &["--time-limit", "1"],
    &format!("{E}/infinite_loop.lua:"),
    "time limit"
);
script_error!(
    endless_growth_hits_the_memory_limit,
    &format!("{E}/memory.lua"),
    &["--memory-limit", "64"],
    &format!("{E}/memory.lua:"),
    "memory limit of 64 MiB"
);
script_error!(
    mesh_index_out_of_range,
    &format!("{E}/mesh_index.lua"),
    &[],
    &format!("{E}/mesh_index.lua:2: "),
    "indices[3] = 3 is out of range"
);
script_error!(
    mesh_arrays_of_the_wrong_length,
    &format!("{E}/mesh_arrays.lua"),
    &[],
    &format!("{E}/mesh_arrays.lua:2: "),
    "positions has 8 numbers"
);
script_error!(
    nan_in_a_vector,
    &format!("{E}/nan_vector.lua"),
    &[],
    &format!("{E}/nan_vector.lua:3: "),
    "NaN"
);
script_error!(
    a_value_that_is_not_a_model,
    &format!("{E}/returns_number.lua"),
    &[],
    &format!("{E}/returns_number.lua: "),
    "the script returned an integer"
);
script_error!(
    unknown_set_name_lists_the_declared_ones,
    "scripts/examples/spiral.lua",
    &["--set", "nope=1"],
    "scripts/examples/spiral.lua:",
    "unknown parameter nope given with --set; declared parameters: count, jitter, radius, rise, turns"
);
script_error!(
    set_value_of_the_wrong_type,
    "scripts/examples/spiral.lua",
    &["--set", "count=many"],
    "scripts/examples/spiral.lua:",
    "'many' is not a number"
);
script_error!(
    set_value_out_of_range,
    "scripts/examples/spiral.lua",
    &["--set", "count=0"],
    "scripts/examples/spiral.lua:",
    "out of its range [1, 2000]"
);
script_error!(
    missing_script_file,
    "scripts/nope/missing.lua",
    &[],
    "scripts/nope/missing.lua: ",
    "cannot read script"
);

#[test]
fn usage_errors_exit_2() {
    assert_eq!(pge(&["run"]).status.code(), Some(2));
    assert_eq!(pge(&["frobnicate"]).status.code(), Some(2));
    assert_eq!(
        pge(&["run", "x.lua", "--set", "novalue"]).status.code(),
        Some(2)
    );
    let help = pge(&["--help"]);
    assert_eq!(help.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&help.stdout).contains("run"));
}

fn run_to(script: &str, out: &Path, extra: &[&str]) -> Output {
    let out_s = out.to_string_lossy().to_string();
    let mut args = vec!["run", script, "-o", out_s.as_str(), "-q"];
    args.extend_from_slice(extra);
    let o = pge(&args);
    assert_eq!(o.status.code(), Some(0), "{script}: {}", stderr(&o));
    o
}

#[test]
fn glb_parses_back_and_carries_the_extras() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("spiral.glb");
    let o = run_to(
        "scripts/examples/spiral.lua",
        &out,
        &["--stats", "--seed", "5", "--set", "count=10"],
    );
    let stats: serde_json::Value =
        serde_json::from_slice(&o.stdout).expect("one JSON object on stdout");
    for key in [
        "vertices",
        "triangles",
        "nodes",
        "leaves",
        "modules",
        "seconds",
    ] {
        assert!(stats.get(key).is_some(), "--stats lacks {key}: {stats}");
    }
    assert_eq!(stats["triangles"], 10 * 12);
    let (doc, buffers, _) = gltf::import(&out).expect("the glb imports");
    assert_eq!(doc.nodes().count(), 10);
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            let n = reader.read_positions().expect("positions").count();
            let idx: Vec<u32> = reader.read_indices().expect("indices").into_u32().collect();
            assert!(idx.iter().all(|i| (*i as usize) < n));
            assert!(reader.read_normals().expect("normals").all(|v| {
                let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                (l - 1.0).abs() < 1e-4
            }));
            // Front faces (counter-clockwise) agree with the vertex normals.
            let p: Vec<[f32; 3]> = reader.read_positions().expect("positions").collect();
            let nr: Vec<[f32; 3]> = reader.read_normals().expect("normals").collect();
            let sub = |a: [f32; 3], b: [f32; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
            for t in idx.chunks_exact(3) {
                let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
                let (u, v) = (sub(p[b], p[a]), sub(p[c], p[a]));
                let face = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                let n = [
                    nr[a][0] + nr[b][0] + nr[c][0],
                    nr[a][1] + nr[b][1] + nr[c][1],
                    nr[a][2] + nr[b][2] + nr[c][2],
                ];
                assert!(
                    face[0] * n[0] + face[1] * n[1] + face[2] * n[2] > 0.0,
                    "triangle {t:?} faces away from its normals"
                );
            }
        }
    }
    let extras: serde_json::Value =
        serde_json::from_str(doc.as_json().extras.as_ref().expect("root extras").get())
            .expect("json");
    assert_eq!(extras["pge"]["seed"], 5);
    assert_eq!(extras["pge"]["params"]["count"], 10);
    assert_eq!(extras["pge"]["stats"]["triangles"], 120);
}

#[test]
fn same_seed_same_bytes_other_seed_other_bytes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let [a, b, c] = ["a.glb", "b.glb", "c.glb"].map(|n| dir.path().join(n));
    run_to("scripts/examples/spiral.lua", &a, &["--seed", "3"]);
    run_to("scripts/examples/spiral.lua", &b, &["--seed", "3"]);
    run_to("scripts/examples/spiral.lua", &c, &["--seed", "4"]);
    let (a, b, c) = (
        std::fs::read(a).expect("a"),
        std::fs::read(b).expect("b"),
        std::fs::read(c).expect("c"),
    );
    assert_eq!(a, b);
    assert_ne!(a, c);
}

#[test]
fn obj_output_writes_obj_and_mtl() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("t.obj");
    run_to("scripts/examples/terrain.lua", &out, &["--set", "cells=8"]);
    let obj = std::fs::read_to_string(&out).expect("obj");
    assert_eq!(obj.lines().filter(|l| l.starts_with("v ")).count(), 81);
    assert_eq!(obj.lines().filter(|l| l.starts_with("f ")).count(), 128);
    assert!(dir.path().join("t.mtl").exists());
}

#[test]
fn script_algorithms_run_step_by_step() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("a.glb");
    let o = run_to("tests/scripts/algorithm.lua", &out, &["--stats"]);
    let stats: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(stats["triangles"], 5 * 12);
    let o = run_to(
        "tests/scripts/algorithm.lua",
        &out,
        &["--stats", "--steps", "2"],
    );
    let stats: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(stats["triangles"], 2 * 12);
}

#[test]
fn support_library_and_params() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("s.glb");
    run_to(
        "tests/scripts/support.lua",
        &out,
        &["--set", "a=7", "--set", "flag=true", "--set", "word=elm"],
    );
    let (doc, _, _) = gltf::import(&out).expect("imports");
    let name = doc
        .meshes()
        .next()
        .and_then(|m| m.name().map(str::to_string))
        .expect("named mesh");
    assert!(
        name.starts_with("a=7 b=2.5 flag=true word=elm r="),
        "{name}"
    );
    // pge.random draws from the run's seed: the same seed gives the same number.
    let out2 = dir.path().join("s2.glb");
    run_to(
        "tests/scripts/support.lua",
        &out2,
        &["--set", "a=7", "--set", "flag=true", "--set", "word=elm"],
    );
    let (doc2, _, _) = gltf::import(&out2).expect("imports");
    assert_eq!(
        doc2.meshes()
            .next()
            .and_then(|m| m.name().map(str::to_string)),
        Some(name)
    );
}

#[test]
fn pairs_order_is_the_same_on_every_run() {
    let dir = tempfile::tempdir().expect("tempdir");
    let outs: Vec<Vec<u8>> = (0..3)
        .map(|i| {
            let out = dir.path().join(format!("{i}.glb"));
            run_to("tests/scripts/pairs_order.lua", &out, &[]);
            std::fs::read(out).expect("written")
        })
        .collect();
    assert_eq!(outs[0], outs[1]);
    assert_eq!(outs[1], outs[2]);
    let (doc, _, _) = gltf::import(dir.path().join("0.glb")).expect("imports");
    assert_eq!(
        doc.meshes()
            .next()
            .and_then(|m| m.name().map(str::to_string)),
        Some("alpha,beta,delta,epsilon,eta,gamma,iota,kappa,theta,zeta".to_string())
    );
}

#[test]
fn material_texture_from_an_image_object() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("t.glb");
    run_to("tests/scripts/texture_object.lua", &out, &[]);
    let (doc, _, images) = gltf::import(&out).expect("imports");
    assert_eq!(doc.images().count(), 1);
    assert_eq!((images[0].width, images[0].height), (4, 4));
}

#[test]
fn an_empty_model_writes_a_glb_that_parses() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("e.glb");
    run_to("tests/scripts/outside.lua", &out, &[]);
    let (doc, _, _) = gltf::import(&out).expect("imports");
    // Only the empty node the scene needs.
    assert_eq!(doc.nodes().count(), 1);
    assert!(doc.nodes().all(|n| n.mesh().is_none()));
    assert_eq!(doc.meshes().count(), 0);
}
script_error!(
    a_failing_model_method_shows_its_own_error,
    &format!("{E}/model_fails.lua"),
    &[],
    &format!("{E}/model_fails.lua:4: "),
    "the roof has no walls"
);

#[test]
fn turtle_textures_are_found_next_to_the_script_from_any_folder() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("t.glb");
    let script = root().join("tests/scripts/textured/turtle.lua");
    let o = Command::new(env!("CARGO_BIN_EXE_pge"))
        .arg("run")
        .arg(&script)
        .arg("-o")
        .arg(&out)
        .arg("-q")
        .current_dir(dir.path())
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", stderr(&o));
    let (doc, _, images) = gltf::import(&out).expect("imports");
    assert_eq!(doc.images().count(), 1);
    assert_eq!((images[0].width, images[0].height), (64, 64));
}
script_error!(
    an_unbalanced_bracket_names_the_lsystem,
    &format!("{E}/unbalanced.lua"),
    &[],
    &format!("{E}/unbalanced.lua:2: "),
    "L-system 'x': turtle: ']' (pop) without a matching '['"
);
script_error!(
    a_nan_turtle_option,
    &format!("{E}/turtle_nan.lua"),
    &[],
    &format!("{E}/turtle_nan.lua:2: "),
    "'angle' must be a finite number, got NaN"
);

#[test]
fn a_model_with_nothing_in_it_gets_a_scene_and_a_warning() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("city.glb");
    let out_s = out.to_string_lossy().to_string();
    let o = pge(&[
        "run",
        "scripts/lsystems/city.lua",
        "--set",
        "size=400",
        "--set",
        "lot=4",
        "-o",
        &out_s,
        "-q",
        "--stats",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("city.lua: warning: the model is empty"),
        "a warning on stderr: {err}"
    );
    let stats: serde_json::Value =
        serde_json::from_slice(&o.stdout).expect("one JSON object on stdout");
    assert_eq!(stats["triangles"], 0);
    let warnings = stats["warnings"].as_array().expect("warnings");
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().is_some_and(|w| w.contains("the model is empty"))),
        "the warning in --stats: {stats}"
    );
    let (doc, _, _) = gltf::import(&out).expect("the glb imports");
    let scene = doc.default_scene().expect("a default scene");
    assert_eq!(scene.nodes().count(), 1, "one empty node");
    assert!(scene.nodes().all(|n| n.mesh().is_none()));
    let extras = scene
        .extras()
        .as_ref()
        .expect("the run's extras on the scene");
    let extras: serde_json::Value = serde_json::from_str(extras.get()).expect("json");
    assert_eq!(extras["pge"]["params"]["size"], 400.0);
    assert_eq!(extras["pge"]["stats"]["triangles"], 0);
}
