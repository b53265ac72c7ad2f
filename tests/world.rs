//! `pge world`: a world directory recorded tile by tile (`init`, `variants`, `add`,
//! `adopt`, `finish`), verified, resumed; folders that are not this world's are refused and
//! left as they were; damaged or foreign files are found.

mod common;

use std::path::Path;

use common::{pge, pge_ok, ray_forest as forest};
use serde_json::Value;

fn json(bytes: &[u8]) -> Value {
    serde_json::from_slice(bytes).expect("json on stdout")
}

/// Runs `pge args`, expecting exit 1 and one line holding every needle.
fn fails(args: &[&str], needles: &[&str]) {
    let o = pge(args);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    for n in needles {
        assert!(err.contains(n), "'{n}' not in: {err}");
    }
}

fn tiles(script: &str) -> Vec<String> {
    json(&pge_ok(&["tiles", script]))
        .as_array()
        .expect("tiles")
        .iter()
        .map(|t| format!("{},{}", t["i"], t["j"]))
        .collect()
}

/// `pge run --tile ... --out-dir DIR/tiles`, referring to DIR's variants when `shared`.
fn grow(script: &str, dir: &str, which: &[String], shared: bool) {
    let out = format!("{dir}/tiles");
    let mut args = vec!["run", script, "--out-dir", &out, "-q"];
    for t in which {
        args.extend(["--tile", t]);
    }
    if shared {
        args.extend(["--variants", dir]);
    }
    pge_ok(&args);
}

#[test]
fn a_world_is_recorded_tile_by_tile_verified_and_resumed() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("world");
    let d = dir.to_string_lossy().to_string();
    let script = forest();
    let all = tiles(&script);
    let init = json(&pge_ok(&["world", "init", &script, "--out", &d]));
    assert_eq!(
        (&init["created"], &init["fresh"]),
        (&Value::Bool(true), &Value::Bool(true))
    );
    assert_eq!(init["tiles"], Value::Array(vec![]));
    pge_ok(&["run", &script, "--variants-out", &d, "-q"]);
    let v = json(&pge_ok(&["world", "variants", &d]));
    assert_eq!(v["changed"], false);
    assert_eq!(v["variants"]["file"], "variants.bin");

    grow(&script, &d, &all[..3], true);
    pge_ok(&["world", "add", &d, &all[0], &all[1], &all[2]]);
    // Not every tile yet: neither finished nor verified.
    fails(&["world", "finish", &d], &["13 of 16 tiles not recorded"]);
    fails(&["world", "verify", &d], &["13 of 16 tiles"]);
    fails(&["merge", &d], &["not complete"]);

    // The rest written by others (a job array), adopted.
    grow(&script, &d, &all[3..], true);
    let adopted = json(&pge_ok(&["world", "adopt", &d]));
    assert_eq!(adopted.as_array().expect("list").len(), 13);
    let done = json(&pge_ok(&["world", "finish", &d]));
    assert_eq!(done["tiles"], 16);
    let verified = String::from_utf8(pge_ok(&["world", "verify", &d])).expect("text");
    assert!(
        verified.contains("complete world of 16 tiles"),
        "{verified}"
    );

    let m: Value = json(&std::fs::read(dir.join("world.json")).expect("manifest"));
    assert_eq!(m["complete"], true);
    assert_eq!(m["seed"], 1);
    assert_eq!(m["params"]["spin"], 0);
    let t = &m["tiles"][5];
    let (i, j) = (t["i"].as_u64().expect("i"), t["j"].as_u64().expect("j"));
    // The bounds are the ones `pge tiles` prints.
    let listed = json(&pge_ok(&["tiles", &script]));
    let same = listed
        .as_array()
        .expect("tiles")
        .iter()
        .find(|l| l["i"] == i && l["j"] == j)
        .expect("listed");
    assert_eq!((&t["min"], &t["max"]), (&same["min"], &same["max"]));
    let sum: u64 = m["tiles"]
        .as_array()
        .expect("tiles")
        .iter()
        .map(|t| t["instances"].as_u64().expect("n"))
        .sum();
    assert_eq!(m["instances"], sum);
    pge_ok(&["merge", &d, "-o", &format!("{d}.glb")]);

    // Again: everything kept. A damaged tile is found, dropped on resume, regrown alone.
    let again = json(&pge_ok(&["world", "init", &script, "--out", &d]));
    assert_eq!(again["fresh"], false);
    assert_eq!(
        (&again["complete"], &again["variants"]),
        (&Value::Bool(true), &Value::Bool(true))
    );
    let file = dir.join(format!("tiles/{i}_{j}.glb"));
    let mut bytes = std::fs::read(&file).expect("tile");
    bytes.push(0);
    std::fs::write(&file, bytes).expect("damaged");
    fails(
        &["world", "verify", &d],
        &[&format!("{i}_{j}.glb"), "world.json records"],
    );
    let resumed = json(&pge_ok(&["world", "init", &script, "--out", &d]));
    assert_eq!(resumed["complete"], false);
    assert_eq!(resumed["tiles"].as_array().expect("kept").len(), 15);
    std::fs::remove_file(&file).expect("rm");
    grow(&script, &d, &[format!("{i},{j}")], true);
    pge_ok(&["world", "add", &d, &format!("{i},{j}")]);
    pge_ok(&["world", "finish", &d]);
    pge_ok(&["world", "verify", &d]);

    // Another seed, or tiles of the other form, are not this world's.
    fails(
        &["world", "init", &script, "--out", &d, "--seed", "2"],
        &["holds another world", "seed 1"],
    );
    let standalone = json(&pge_ok(&[
        "world",
        "init",
        &script,
        "--out",
        &d,
        "--standalone-tiles",
    ]));
    assert_eq!(standalone["tiles"], Value::Array(vec![]));
    fails(
        &["world", "add", &d, &all[0]],
        &["refers to shared variants"],
    );
}

#[test]
fn a_tile_of_another_run_is_refused() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let d = tmp.path().join("w").to_string_lossy().to_string();
    let script = forest();
    pge_ok(&["world", "init", &script, "--out", &d, "--standalone-tiles"]);
    let out = format!("{d}/tiles/1_0.glb");
    pge_ok(&[
        "run", &script, "--tile", "1,0", "--seed", "5", "-o", &out, "-q",
    ]);
    fails(&["world", "adopt", &d], &["1_0.glb", "another seed"]);
    // A file named for one tile holding another.
    pge_ok(&["run", &script, "--tile", "2,0", "-o", &out, "-q"]);
    fails(
        &["world", "add", &d, "1,0"],
        &["1_0.glb", "another seed, parameters or tile"],
    );
    std::fs::write(&out, b"not a glb").expect("junk");
    fails(&["world", "add", &d, "1,0"], &["1_0.glb", "not a tile"]);
    fails(
        &["world", "add", &d, "3,0"],
        &["3_0.glb", "no such tile file"],
    );
}

#[test]
fn a_folder_of_other_files_is_refused_and_left_untouched() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let home = tmp.path().join("home");
    std::fs::create_dir_all(home.join("tiles")).expect("folders");
    std::fs::write(home.join("notes.txt"), b"mine").expect("file");
    std::fs::write(home.join("tiles/.tmp-mine"), b"mine too").expect("file");
    let h = home.to_string_lossy().to_string();
    fails(
        &["world", "init", &forest(), "--out", &h],
        &["not empty and not a world", "notes.txt"],
    );
    let mut names: Vec<String> = walk(&home);
    names.sort();
    assert_eq!(names, ["notes.txt", "tiles", "tiles/.tmp-mine"]);
    // A file where the folder should be.
    let file = home.join("notes.txt").to_string_lossy().to_string();
    fails(
        &["world", "init", &forest(), "--out", &file],
        &["not a folder"],
    );
    fails(&["world", "verify", &h], &["no world here"]);
}

fn walk(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).expect("dir").flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        if e.path().is_dir() {
            out.extend(walk(&e.path()).into_iter().map(|n| format!("{name}/{n}")));
        }
        out.push(name);
    }
    out
}
