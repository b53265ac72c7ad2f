//! Every forest script writes a glb that the Khronos glTF validator accepts with no errors,
//! with `EXT_mesh_gpu_instancing` and with one node per instance. Small settings
//! (`--set points=150`) keep the debug build quick; the structure of the file is the same.
//! The validator (npm package `gltf-validator`) is installed into `target/` on first use.

mod common;

use std::path::PathBuf;

use common::{pge, root, run_validator};

#[test]
fn every_forest_script_writes_a_valid_glb_in_both_instancing_forms() {
    let mut scripts: Vec<PathBuf> = std::fs::read_dir(root().join("scripts/forests"))
        .expect("scripts/forests")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "lua"))
        .collect();
    scripts.sort();
    assert!(scripts.len() >= 4, "{scripts:?}");
    let dir = tempfile::tempdir().expect("tempdir");
    let mut outputs = Vec::new();
    for script in &scripts {
        let name = script
            .file_stem()
            .expect("stem")
            .to_string_lossy()
            .to_string();
        let script = script.to_string_lossy().to_string();
        for form in ["gpu", "nodes"] {
            let out = dir.path().join(format!("{name}_{form}.glb"));
            let out_s = out.to_string_lossy().to_string();
            // The big forest keeps its layout but grows one small variant per species.
            let mut args = vec![
                "run",
                &script,
                "-o",
                &out_s,
                "-q",
                "--instancing",
                form,
                "--set",
                "points=150",
            ];
            if name == "big" {
                args.extend(["--set", "variants=1"]);
            }
            let o = pge(&args);
            assert!(
                o.status.success(),
                "{script}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            outputs.push(out);
        }
    }
    let (passed, report) = run_validator(&outputs);
    println!("{report}");
    assert!(passed, "the glTF validator found errors:\n{report}");
    assert_eq!(
        report.lines().filter(|l| l.contains(": 0 errors")).count(),
        outputs.len(),
        "{report}"
    );
}
