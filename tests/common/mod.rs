//! Helpers shared by the end-to-end tests: where the repository is and how to run `pge`.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root (scripts are given relative to it).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs `pge` with `args` in the repository root.
pub fn pge(args: &[&str]) -> Output {
    pge_in(args, &root())
}

/// Runs `pge` with `args` in `cwd`.
pub fn pge_in(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pge"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("the pge binary runs")
}

/// The version of the Khronos glTF validator (npm `gltf-validator`) the tests run.
pub const VALIDATOR_VERSION: &str = "2.0.0-dev.3.10";

/// The folder holding `node_modules/gltf-validator`, installing it into `target/` if needed
/// (Node.js and npm are needed).
pub fn validator_dir() -> PathBuf {
    let dir = root().join("target").join("gltf-validator");
    if dir.join("node_modules").join("gltf-validator").exists() {
        return dir;
    }
    std::fs::create_dir_all(&dir).expect("create target/gltf-validator");
    let status = Command::new("npm")
        .args(["install", "--prefix"])
        .arg(&dir)
        .arg(format!("gltf-validator@{VALIDATOR_VERSION}"))
        .args(["--no-audit", "--no-fund", "--silent"])
        .status()
        .expect("npm is needed to install the glTF validator (apt-get install nodejs npm)");
    assert!(status.success(), "npm install gltf-validator failed");
    dir
}

/// Runs the Khronos glTF validator on `files`: whether it passed, and its report (one line
/// per file, `FILE: N errors, ...`; the validator's stderr follows when it failed).
pub fn run_validator(files: &[PathBuf]) -> (bool, String) {
    let o = Command::new("node")
        .arg(root().join("tests/support/validate.js"))
        .args(files)
        .env("NODE_PATH", validator_dir().join("node_modules"))
        .output()
        .expect("node runs the validator");
    let mut report = String::from_utf8_lossy(&o.stdout).to_string();
    if !o.status.success() {
        report.push_str(&String::from_utf8_lossy(&o.stderr));
    }
    (o.status.success(), report)
}

/// Runs `pge` with `args` and checks that it succeeded; its standard output.
pub fn pge_ok(args: &[&str]) -> Vec<u8> {
    let o = pge(args);
    assert!(
        o.status.success(),
        "pge {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o.stdout
}

/// The 16-tile test forest of the Ray integration.
pub fn ray_forest() -> String {
    root()
        .join("integrations/ray/tests/forest.lua")
        .to_string_lossy()
        .to_string()
}

/// Runs a script to `dir/tree.glb` with `--stats` (plus `extra`); returns the stats and the
/// glb's bytes. Fails the test when the run fails.
pub fn run_with_stats(script: &str, dir: &Path, extra: &[&str]) -> (serde_json::Value, Vec<u8>) {
    let out = dir.join("tree.glb");
    let out_s = out.to_string_lossy().to_string();
    let mut args = vec!["run", script, "-o", out_s.as_str(), "--stats", "-q"];
    args.extend_from_slice(extra);
    let o = pge(&args);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{script}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let stats: serde_json::Value =
        serde_json::from_str(String::from_utf8_lossy(&o.stdout).trim()).expect("stats are JSON");
    (stats, std::fs::read(&out).expect("glb written"))
}

/// Checks a failed command: exit 1, one line holding every needle, no panic.
pub fn one_line_error(o: &Output, needles: &[&str]) -> String {
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "exit code: {err}");
    assert!(!err.contains("panicked"), "a panic: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    for n in needles {
        assert!(err.contains(n), "'{n}' not in: {err}");
    }
    err
}

/// Runs `pge run main.lua -o out.glb -q` plus `extra` in a folder holding `files` (name,
/// text); checks a one-line error at `main.lua:LINE:` (or at `at` when given) holding every
/// needle, no model written. Returns the line.
pub fn script_fails(files: &[(&str, &str)], extra: &[&str], at: &str, needles: &[&str]) -> String {
    let dir = tempfile::tempdir().expect("tempdir");
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).expect("script");
    }
    let mut args = vec!["run", "main.lua", "-o", "out.glb", "-q"];
    args.extend_from_slice(extra);
    let o = pge_in(&args, dir.path());
    let err = one_line_error(&o, needles);
    assert!(err.starts_with(at), "expected '{at}...', got: {err}");
    assert!(!dir.path().join("out.glb").exists(), "a model was written");
    err
}

/// A small space-colonized bush, a species for forests in tests.
pub const BUSH: &str = "pge.SpaceColonization{envelope = pge.shape.sphere{center = {0, 0.5, 0}, \
                    radius = 0.4}, points = 10, roots = {{0, 0, 0}}}";
