//! Hostile and careless inputs to the commands that read files PGE wrote (tiles, shared
//! variants, world directories) and to their outputs: each is a one-line error with exit 1
//! and nothing written, never a panic, a hang or a read outside the world directory.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{BUSH, one_line_error, pge, pge_ok, ray_forest as forest, script_fails};
use serde_json::{Value, json};

fn s(p: &Path) -> String {
    p.to_string_lossy().to_string()
}

fn sha256(path: &Path) -> String {
    use sha2::Digest;
    let bytes = std::fs::read(path).expect("read");
    sha2::Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// A glb's JSON chunk changed by `edit`, written back with the same binary chunk.
fn edit_glb(path: &Path, edit: impl FnOnce(&mut Value)) {
    let bytes = std::fs::read(path).expect("read");
    let glb = gltf::binary::Glb::from_slice(&bytes).expect("glb");
    let mut json: Value = serde_json::from_slice(&glb.json).expect("json");
    edit(&mut json);
    let text = serde_json::to_vec(&json).expect("json");
    let out = gltf::binary::Glb {
        header: glb.header,
        json: text.into(),
        bin: glb.bin.clone(),
    };
    std::fs::write(path, out.to_vec().expect("glb")).expect("write");
}

/// A JSON file changed by `edit`.
fn edit_json(path: &Path, edit: impl FnOnce(&mut Value)) {
    let mut json: Value =
        serde_json::from_slice(&std::fs::read(path).expect("read")).expect("json");
    edit(&mut json);
    std::fs::write(path, json.to_string()).expect("write");
}

/// The ways a glTF is tampered with: a `byteStride` smaller than the element, and an
/// attribute naming an accessor that does not exist.
/// A change made to a glTF's JSON.
type Tamper = fn(&mut Value);

fn tampered() -> [(&'static str, Tamper); 2] {
    [
        ("byteStride", |j: &mut Value| {
            j["bufferViews"][0]["byteStride"] = json!(4);
        }),
        ("accessor 999", |j: &mut Value| {
            j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(999);
        }),
    ]
}

#[test]
fn a_tampered_shared_variants_description_is_an_error_not_a_tile() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (needle, tamper) in tampered() {
        let v = dir.path().join(needle.replace(' ', "_"));
        pge_ok(&["run", &forest(), "--variants-out", &s(&v), "-q"]);
        edit_json(&v.join("variants.json"), tamper);
        let out = v.join("tile.glb");
        let o = pge(&[
            "run",
            &forest(),
            "--tile",
            "0,0",
            "--variants",
            &s(&v),
            "-o",
            &s(&out),
            "-q",
        ]);
        one_line_error(&o, &["variants.json", needle]);
        assert!(!out.exists(), "a tile was written on tampered variants");
    }
}

#[test]
fn a_mesh_shape_from_a_tampered_gltf_is_a_located_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tile = dir.path().join("tile.glb");
    pge_ok(&["run", &forest(), "--tile", "0,0", "-o", &s(&tile), "-q"]);
    for (needle, tamper) in tampered() {
        let path = dir.path().join("shape.glb");
        std::fs::copy(&tile, &path).expect("copy");
        edit_glb(&path, tamper);
        std::fs::write(
            dir.path().join("main.lua"),
            "local s = pge.shape.mesh{path = \"shape.glb\"}\nreturn pge.Lines()\n",
        )
        .expect("script");
        let o = common::pge_in(&["run", "main.lua", "-o", "out.glb", "-q"], dir.path());
        let err = one_line_error(&o, &[needle]);
        assert!(err.starts_with("main.lua:1: "), "{err}");
    }
}

/// A world directory of the test forest's tiles `tiles` (standalone, or referring to the
/// world's shared variants when `shared`), with its manifest.
fn world(dir: &Path, tiles: &[(u64, u64)], shared: bool) {
    std::fs::create_dir_all(dir.join("tiles")).expect("tiles folder");
    if shared {
        pge_ok(&["run", &forest(), "--variants-out", &s(dir), "-q"]);
    }
    let script = forest();
    for &(i, j) in tiles {
        let out = dir.join(format!("tiles/{i}_{j}.glb"));
        let tile = format!("{i},{j}");
        let (d, o) = (s(dir), s(&out));
        let mut args = vec!["run", &script, "--tile", &tile, "-o", &o, "-q"];
        if shared {
            args.extend_from_slice(&["--variants", &d]);
        }
        pge_ok(&args);
    }
    write_manifest(dir, tiles, shared);
}

/// The manifest of `dir` for tiles `tiles/I_J.glb` as they are now.
fn write_manifest(dir: &Path, tiles: &[(u64, u64)], shared: bool) {
    let entries: Vec<Value> = tiles
        .iter()
        .map(|&(i, j)| {
            let file = format!("tiles/{i}_{j}.glb");
            json!({"i": i, "j": j, "file": file, "sha256": sha256(&dir.join(&file))})
        })
        .collect();
    let mut manifest = json!({"format": "pge-world/1", "seed": 1, "params": {},
        "complete": true, "tiles": entries});
    if shared {
        manifest["variants"] = json!({"file": "variants.bin",
            "sha256": sha256(&dir.join("variants.bin")), "description": "variants.json"});
    }
    std::fs::write(dir.join("world.json"), manifest.to_string()).expect("manifest");
}

fn merge(dir: &Path, extra: &[&str]) -> (Output, PathBuf) {
    let out = dir.parent().expect("parent").join("merged.glb");
    let _ = std::fs::remove_file(&out);
    let (d, o) = (s(dir), s(&out));
    let mut args = vec!["merge", &d, "-o", &o];
    args.extend_from_slice(extra);
    (pge(&args), out)
}

fn merge_fails(dir: &Path, extra: &[&str], needles: &[&str]) {
    let (o, out) = merge(dir, extra);
    one_line_error(&o, needles);
    assert!(!out.exists(), "merge wrote {}", out.display());
}

#[test]
fn merge_reads_nothing_outside_the_world_directory() {
    let dir = tempfile::tempdir().expect("tempdir");
    let w = dir.path().join("world");
    world(&w, &[(0, 0)], true);
    assert!(merge(&w, &[]).0.status.success());

    // A manifest entry leading out: by `..`, by an absolute path, by a link in the folder.
    std::fs::copy(w.join("tiles/0_0.glb"), dir.path().join("outside.glb")).expect("copy");
    let tile = |file: &str, sha: &str| {
        edit_json(&w.join("world.json"), |m| {
            m["tiles"][0]["file"] = json!(file);
            m["tiles"][0]["sha256"] = json!(sha);
        });
    };
    let sha = sha256(&w.join("tiles/0_0.glb"));
    tile("../outside.glb", &sha);
    merge_fails(
        &w,
        &[],
        &["outside.glb", "leads outside the world directory"],
    );
    tile("/dev/zero", &sha);
    merge_fails(&w, &[], &["/dev/zero", "leads outside the world directory"]);
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("/dev/zero", w.join("tiles/zero.glb")).expect("link");
        tile("tiles/zero.glb", &sha);
        merge_fails(&w, &[], &["zero.glb", "leads outside the world directory"]);
        std::fs::remove_file(w.join("tiles/zero.glb")).expect("unlink");
        // A FIFO inside the folder is not read (a read would wait forever).
        let fifo = w.join("tiles/fifo.glb");
        assert!(
            std::process::Command::new("mkfifo")
                .arg(&fifo)
                .status()
                .expect("mkfifo")
                .success()
        );
        tile("tiles/fifo.glb", &sha);
        merge_fails(&w, &[], &["fifo.glb", "not a regular file"]);
    }
    tile("tiles/0_0.glb", &sha);
    assert!(merge(&w, &[]).0.status.success());

    // A tile's buffer URI: percent-encoded to an absolute path, or `..` out of the world.
    std::fs::copy(w.join("variants.bin"), dir.path().join("variants.bin")).expect("copy");
    for (uri, needle) in [
        ("%2Fdev%2Fzero", "is not a relative file"),
        (
            "..%2F..%2Fvariants.bin",
            "leads outside the world directory",
        ),
        ("../../variants.bin", "leads outside the world directory"),
    ] {
        let path = w.join("tiles/0_0.glb");
        let kept = std::fs::read(&path).expect("tile");
        edit_glb(&path, |j| j["buffers"][1]["uri"] = json!(uri));
        write_manifest(&w, &[(0, 0)], true);
        merge_fails(&w, &[], &["0_0.glb", needle]);
        std::fs::write(&path, kept).expect("restore");
    }
}

#[test]
fn merge_of_tampered_tiles_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().expect("tempdir");
    let w = dir.path().join("world");
    world(&w, &[(0, 0)], false);
    let path = w.join("tiles/0_0.glb");
    let kept = std::fs::read(&path).expect("tile");
    // Types glTF forbids, which the gltf crate's readers meet with `unreachable!`.
    let types: [(&str, Tamper); 2] = [
        (
            "(indices) must be an unsigned integer SCALAR",
            |j: &mut Value| {
                let a = j["meshes"][0]["primitives"][0]["indices"]
                    .as_u64()
                    .expect("indices");
                let t = &mut j["accessors"][a as usize]["componentType"];
                // Signed or float of the same size: inside its view, of a forbidden type.
                *t = json!(match t.as_u64() {
                    Some(5121) => 5120,
                    Some(5123) => 5122,
                    _ => 5126,
                });
            },
        ),
        ("(TEXCOORD_0) must be", |j: &mut Value| {
            let i = j["meshes"][0]["primitives"][0]["indices"].clone();
            j["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = i;
        }),
    ];
    for (needle, tamper) in tampered().into_iter().chain(types) {
        edit_glb(&path, tamper);
        write_manifest(&w, &[(0, 0)], false);
        merge_fails(&w, &[], &["0_0.glb", needle]);
        std::fs::write(&path, &kept).expect("restore");
    }
}

#[test]
fn merge_refuses_a_tile_listed_twice_and_keeps_to_its_limits() {
    let dir = tempfile::tempdir().expect("tempdir");
    let w = dir.path().join("world");
    world(&w, &[(0, 0), (1, 0), (2, 0)], false);
    let (o, _) = merge(&w, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The files weigh more than 1 MiB: the memory limit is met on the way, nothing written.
    let bytes: u64 = (0..3)
        .map(|i| {
            std::fs::metadata(w.join(format!("tiles/{i}_0.glb")))
                .expect("tile")
                .len()
        })
        .sum();
    assert!(bytes > 1 << 20, "{bytes} bytes");
    merge_fails(&w, &["--memory-limit", "1"], &["memory limit of 1 MiB"]);
    merge_fails(&w, &["--time-limit", "0.000000001"], &["time limit"]);
    let (o, _) = merge(&w, &["--memory-limit", "0"]);
    assert_eq!(o.status.code(), Some(2));

    edit_json(&w.join("world.json"), |m| {
        let first = m["tiles"][0].clone();
        m["tiles"].as_array_mut().expect("tiles").push(first);
    });
    merge_fails(&w, &[], &["tile 0,0 is listed twice"]);
}

#[test]
fn a_density_or_species_function_calling_its_own_forest_is_a_located_error() {
    // forest:instances lays out the forest, calling the density function, which changes it.
    let script = format!(
        "local f = pge.Forest{{size = {{20, 20}}, seed = 1}}\n\
         f:scatter{{species = function() return {BUSH} end, minDistance = 4,\n\
           density = function(x, z)\n\
             f:terrain{{height = 1}}\n\
             return 1\n\
           end}}\n\
         local list = f:instances()\n\
         return f\n"
    );
    script_fails(
        &[("main.lua", &script)],
        &[],
        "main.lua:4: ",
        &["forest:terrain", "busy"],
    );
    // Reading it meanwhile is fine: forest:height from the density function.
    let reading = script.replace("f:terrain{height = 1}", "local h = f:height(x, z)");
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("main.lua"), reading).expect("script");
    let o = common::pge_in(&["run", "main.lua", "-o", "out.glb", "-q"], dir.path());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn a_forest_that_is_its_own_species_is_a_located_error() {
    // A species function returning the forest.
    script_fails(
        &[(
            "main.lua",
            "local f = pge.Forest{size = {20, 20}, seed = 1}\n\
             f:scatter{species = function() return f end, minDistance = 4}\n\
             return f\n",
        )],
        &[],
        "main.lua:2: ",
        &["deeper than the limit of 8"],
    );
    // A species script that is the forest's own script.
    script_fails(
        &[(
            "main.lua",
            "local f = pge.Forest{size = {20, 20}, seed = 1}\n\
             f:scatter{species = \"main.lua\", minDistance = 4}\n\
             return f\n",
        )],
        &[],
        "main.lua:2: forest:scatter: species 'main.lua' failed: main.lua: it grows the forest",
        &["a forest cannot be its own species"],
    );
}

#[cfg(unix)]
#[test]
fn a_closed_stdout_ends_the_command_quietly() {
    use std::process::{Command, Stdio};
    // The reader closes the pipe before pge writes: `pge tiles ... | head -c 0`.
    for args in [
        vec!["tiles".to_string(), forest()],
        vec![
            "run".into(),
            forest(),
            "--tile".into(),
            "0,0".into(),
            "-o".into(),
            "-".into(),
        ],
    ] {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut args = args;
        if let Some(o) = args.iter().position(|a| a == "-") {
            args[o] = s(&dir.path().join("t.glb"));
            args.push("--stats".into());
        }
        let mut child = Command::new(env!("CARGO_BIN_EXE_pge"))
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("pge runs");
        drop(child.stdout.take());
        let o = child.wait_with_output().expect("pge ends");
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
        assert!(err.is_empty(), "{args:?}: {err}");
    }
}

#[test]
fn img_save_in_a_species_script_writes_beside_the_output() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::create_dir_all(dir.path().join("lib")).expect("lib");
    std::fs::create_dir_all(dir.path().join("out")).expect("out");
    std::fs::write(
        dir.path().join("lib/bush.lua"),
        format!("pge.Image.new(2, 2):save(\"bark.png\")\nreturn {BUSH}\n"),
    )
    .expect("species");
    std::fs::write(
        dir.path().join("main.lua"),
        "local f = pge.Forest{size = {10, 10}, seed = 1}\n\
         f:scatter{species = \"lib/bush.lua\", minDistance = 4, variants = 1}\n\
         return f\n",
    )
    .expect("script");
    let o = common::pge_in(
        &["run", "main.lua", "-o", "out/forest.glb", "-q"],
        dir.path(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        dir.path().join("out/bark.png").is_file(),
        "not beside the output"
    );
    assert!(
        !dir.path().join("lib/bark.png").exists(),
        "written beside the species"
    );
}

#[test]
fn variants_out_refuses_steps_and_tampered_counts_are_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let v = dir.path().join("v");
    let o = pge(&["run", &forest(), "--variants-out", &s(&v), "--steps", "1"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!v.exists(), "--variants-out --steps wrote variants");

    pge_ok(&["run", &forest(), "--variants-out", &s(&v), "-q"]);
    let tile = dir.path().join("tile.glb");
    let args = [
        "run",
        &forest(),
        "--tile",
        "0,0",
        "--variants",
        &s(&v),
        "-o",
        &s(&tile),
        "--stats",
    ]
    .map(str::to_string);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    edit_json(&v.join("variants.json"), |j| {
        for g in j["extras"]["pge"]["variants"]["groups"]
            .as_array_mut()
            .expect("groups")
        {
            g["nodes"] = json!(u64::MAX / 2);
        }
    });
    one_line_error(&pge(&args), &["variants.json", "nodes", "2^32"]);
    assert!(!tile.exists());
}

/// A folder with `main.lua` (`source`) and `out/`.
fn case(source: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("main.lua"), source).expect("script");
    std::fs::create_dir(dir.path().join("out")).expect("out");
    dir
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().to_string())
        .collect();
    v.sort();
    v
}

#[test]
fn an_obj_set_or_a_variants_pair_is_written_whole_or_not_at_all() {
    // A textured model as .obj: its .mtl cannot take its place (a folder is there), so the
    // older .obj stays as it was and no texture of the new set is left.
    let dir = case(
        "local img = pge.Image.new(2, 2)\n\
         local m = pge.Lines{width = 0.1}\n\
         m:add({0, 0, 0}, {0, 1, 0})\n\
         return img:applyTo(m:model())\n",
    );
    std::fs::write(dir.path().join("out/model.obj"), "old").expect("old obj");
    std::fs::create_dir(dir.path().join("out/model.mtl")).expect("a folder in the way");
    let o = common::pge_in(
        &["run", "main.lua", "-o", "out/model.obj", "-q"],
        dir.path(),
    );
    one_line_error(&o, &["model.mtl", "folder"]);
    let out = dir.path().join("out");
    assert_eq!(
        std::fs::read_to_string(out.join("model.obj")).expect("obj"),
        "old"
    );
    assert_eq!(names(&out), ["model.mtl", "model.obj"], "{:?}", names(&out));
    std::fs::remove_dir(out.join("model.mtl")).expect("rmdir");
    let o = common::pge_in(
        &["run", "main.lua", "-o", "out/model.obj", "-q"],
        dir.path(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        names(&out).iter().any(|n| n.ends_with(".png")),
        "{:?}",
        names(&out)
    );

    // --variants-out: variants.json cannot take its place, variants.bin stays the old one.
    let dir = tempfile::tempdir().expect("tempdir");
    let v = dir.path().join("v");
    std::fs::create_dir_all(v.join("variants.json")).expect("a folder in the way");
    std::fs::write(v.join("variants.bin"), "old").expect("old bin");
    let o = pge(&["run", &forest(), "--variants-out", &s(&v), "-q"]);
    one_line_error(&o, &["variants.json", "folder"]);
    assert_eq!(std::fs::read(v.join("variants.bin")).expect("bin"), b"old");
    assert_eq!(names(&v), ["variants.bin", "variants.json"]);
}

#[test]
fn temporary_files_of_a_killed_run_are_removed_by_the_next_run_into_the_folder() {
    let dir = case("local l = pge.LSystem()\nl:axiom(\"F\")\nreturn l\n");
    let out = dir.path().join("out");
    // Process ids never go past 2^22 on Linux: this writer is gone. Process 1 runs.
    for name in [
        ".pge-tmp-999999999-a1b2c3",
        ".pge-tmp-1-a1b2c3",
        ".tmpa1b2c3",
        "notes.txt",
    ] {
        std::fs::write(out.join(name), "x").expect("file");
    }
    let o = common::pge_in(
        &["run", "main.lua", "-o", "out/model.glb", "-q"],
        dir.path(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let left = names(&out);
    if Path::new("/proc/self").exists() {
        assert_eq!(
            left,
            [".pge-tmp-1-a1b2c3", ".tmpa1b2c3", "model.glb", "notes.txt"],
            "only the dead writer's temporary file is removed"
        );
    }
}

#[cfg(unix)]
#[test]
fn sigterm_during_the_write_leaves_no_temporary_file() {
    // Thick lines make a big mesh: the glb takes a while to build, its temporary file open.
    let dir = case(
        "local l = pge.Lines{width = 0.01}\n\
         for i = 1, 300000 do l:add({i, 0, 0}, {i, 1, 0}) end\n\
         return l\n",
    );
    let out = dir.path().join("out");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_pge"))
        .args(["run", "main.lua", "-o", "out/model.glb", "-q"])
        .current_dir(dir.path())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("pge runs");
    let started = std::time::Instant::now();
    let mut seen = false;
    while started.elapsed() < std::time::Duration::from_secs(120) {
        if names(&out).iter().any(|n| n.starts_with(".pge-tmp-")) {
            seen = true;
            break;
        }
        if child.try_wait().expect("wait").is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    assert!(seen, "the write was never seen in progress");
    let killed = std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(killed.success());
    let status = child.wait().expect("pge ends");
    assert_eq!(status.code(), Some(128 + 15), "{status:?}");
    assert!(names(&out).is_empty(), "left behind: {:?}", names(&out));
}
