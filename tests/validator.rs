//! Every script in the library writes a glb that the Khronos glTF validator accepts with no
//! errors and no warning about tangents (every normal-mapped mesh carries its tangents). The validator (npm package `gltf-validator`) is installed into `target/` on
//! first use; this needs Node.js and npm.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

use common::{root, run_validator};

/// The scripts `pge run` must turn into valid glb files: every `.lua` under `scripts/`
/// except library modules (`lib/`) and scripts meant to be loaded by others.
fn library_scripts() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                // Forests are validated by tests/forest_validator.rs with small settings.
                if p.file_name()
                    .is_some_and(|n| n != "lib" && n != "data" && n != "forests")
                {
                    walk(&p, out);
                }
            } else if p.extension().is_some_and(|e| e == "lua") {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(&root().join("scripts"), &mut out);
    out
}

#[test]
fn every_library_script_writes_a_valid_glb() {
    let scripts = library_scripts();
    assert!(scripts.len() >= 2, "found only {scripts:?}");
    let dir = tempfile::tempdir().expect("tempdir");
    let mut outputs = Vec::new();
    for (i, script) in scripts.iter().enumerate() {
        let out = dir.path().join(format!("{i}.glb"));
        let o = Command::new(env!("CARGO_BIN_EXE_pge"))
            .arg("run")
            .arg(script)
            .arg("-o")
            .arg(&out)
            .arg("-q")
            .current_dir(root())
            .output()
            .expect("pge runs");
        assert!(
            o.status.success(),
            "{}: {}",
            script.display(),
            String::from_utf8_lossy(&o.stderr)
        );
        outputs.push(out);
    }
    let (passed, report) = run_validator(&outputs);
    let report = outputs
        .iter()
        .zip(&scripts)
        .fold(report.to_string(), |r, (out, s)| {
            r.replace(&out.display().to_string(), &s.display().to_string())
        });
    println!("{report}");
    assert!(passed, "the glTF validator found errors:\n{report}");
    assert_eq!(
        report.lines().filter(|l| l.contains(": 0 errors")).count(),
        scripts.len(),
        "{report}"
    );
    assert_tangents(&report);
}

/// Every normal-mapped mesh carries its tangents: the validator warns of none
/// (`MESH_PRIMITIVE_GENERATED_TANGENT_SPACE`, the tangent space each client would make up)
/// and of no tangent that is not a unit vector with a sign of ±1.
fn assert_tangents(report: &str) {
    let tangent_warnings: Vec<&str> = report
        .lines()
        .filter(|l| l.contains("TANGENT") || l.contains("ACCESSOR_INVALID_SIGN"))
        .collect();
    assert!(
        tangent_warnings.is_empty(),
        "tangent warnings: {tangent_warnings:#?}"
    );
}
