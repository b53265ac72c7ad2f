//! Thread counts end to end: a big tree (its bark meshed tube by tube in parallel, its glb
//! written in parallel pieces) gives the same bytes on 1, 2 and 3 threads.

mod common;

use std::path::Path;

use common::pge;

/// Runs `pge run` of the oak with `threads` worker threads and the given extra arguments,
/// and reads back the glb.
fn oak_glb(dir: &Path, threads: u32, extra: &[&str]) -> Vec<u8> {
    let out = dir.join(format!("oak_{threads}.glb"));
    let out = out.to_string_lossy().to_string();
    let threads = threads.to_string();
    let mut args = vec![
        "run",
        "scripts/species/oak.lua",
        "-o",
        &out,
        "--threads",
        &threads,
        "-q",
    ];
    args.extend(extra);
    let o = pge(&args);
    assert!(
        o.status.success(),
        "pge {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::read(&out).expect("the glb")
}

#[test]
fn a_big_tree_is_byte_identical_on_one_two_and_three_threads() {
    let dir = tempfile::tempdir().expect("tempdir");
    // 12,000 attraction points: hundreds of tubes, and the bark's views cut in several
    // pieces of 256 KiB (over 22,000 vertices).
    let big = ["--set", "points=12000"];
    let one = oak_glb(dir.path(), 1, &big);
    let gltf = gltf::Gltf::from_slice(&one).expect("a glb");
    let bark = gltf.meshes().next().expect("the bark");
    let positions = bark
        .primitives()
        .next()
        .and_then(|p| p.get(&gltf::Semantic::Positions))
        .expect("bark positions");
    assert!(
        positions.count() > 22_000,
        "a big bark: {} vertices",
        positions.count()
    );
    for threads in [2, 3] {
        let other = oak_glb(dir.path(), threads, &big);
        assert!(
            other == one,
            "the glb differs between 1 and {threads} threads"
        );
    }
}
