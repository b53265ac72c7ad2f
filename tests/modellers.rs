//! End-to-end tests of the modellers (extruder, metaballs, lines, images) and the thesis'
//! example scripts in `scripts/modellers/`: `pge run` on the real scripts, checking the
//! glb, the statistics, the frames of the animated ones, the PNG the explorers write, and
//! the one-line `FILE:LINE:` errors of bad input.

mod common;

use common::{pge_in, root};
use std::path::PathBuf;

fn script(name: &str) -> PathBuf {
    root().join("scripts/modellers").join(name)
}

/// `pge run SCRIPT -o out.glb --stats -q EXTRA...` in a fresh folder: the statistics, the
/// glb bytes and the folder (for files the script wrote).
fn run(name: &str, extra: &[&str]) -> (serde_json::Value, Vec<u8>, tempfile::TempDir) {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = script(name);
    let mut args = vec![
        "run",
        path.to_str().expect("utf-8 path"),
        "-o",
        "out.glb",
        "--stats",
        "-q",
    ];
    args.extend_from_slice(extra);
    let o = pge_in(&args, dir.path());
    assert!(
        o.status.success(),
        "{name} {extra:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let stats: serde_json::Value = serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{name}: --stats is not JSON: {e}"));
    let glb = std::fs::read(dir.path().join("out.glb")).expect("the glb was written");
    if count(&stats, "vertices") > 0 {
        let gltf =
            gltf::Gltf::from_slice(&glb).unwrap_or_else(|e| panic!("{name}: invalid glb: {e}"));
        assert!(gltf.meshes().count() > 0, "{name}: no mesh");
    }
    (stats, glb, dir)
}

fn count(stats: &serde_json::Value, key: &str) -> u64 {
    stats[key]
        .as_u64()
        .unwrap_or_else(|| panic!("stats lack {key}: {stats}"))
}

/// The line segments in a glb (primitives of mode LINES), from its index accessors.
fn line_segments(glb: &[u8]) -> usize {
    let gltf = gltf::Gltf::from_slice(glb).expect("valid glb");
    gltf.meshes()
        .flat_map(|m| m.primitives().collect::<Vec<_>>())
        .filter(|p| p.mode() == gltf::mesh::Mode::Lines)
        .map(|p| p.indices().map_or(0, |a| a.count() / 2))
        .sum()
}

macro_rules! writes_a_glb {
    ($($name:ident: $file:literal, min_triangles $tris:expr;)*) => {$(
        #[test]
        fn $name() {
            let (stats, glb, _dir) = run($file, &[]);
            assert!(count(&stats, "triangles") >= $tris, "{}: {stats}", $file);
            let (_, again, _dir) = run($file, &[]);
            assert_eq!(glb, again, "{}: the same script and seed give the same bytes", $file);
        }
    )*};
}

writes_a_glb! {
    sierpinski_writes_a_glb: "sierpinski.lua", min_triangles 968;
    tower_writes_a_glb: "tower.lua", min_triangles 10_000;
    crystals_writes_a_glb: "crystals.lua", min_triangles 500;
    coral_writes_a_glb: "coral.lua", min_triangles 20_000;
    coral_metaballs_writes_a_glb: "coral_metaballs.lua", min_triangles 10_000;
    city_writes_a_glb: "city.lua", min_triangles 10_000;
    explorers_writes_a_glb: "explorers.lua", min_triangles 2;
}

#[test]
fn fireworks_writes_a_glb_of_lines() {
    let (stats, glb, _dir) = run("fireworks.lua", &["--steps", "30", "--set", "width=0"]);
    assert_eq!(count(&stats, "triangles"), 0);
    assert!(line_segments(&glb) > 100, "a burst at frame 30");
}

#[test]
fn sierpinski_triangles_follow_the_depth() {
    for depth in 0..5u32 {
        let set = format!("depth={depth}");
        let (stats, _, _dir) = run("sierpinski.lua", &["--set", &set]);
        // (3^(d+1) - 1) / 2 triangular prisms of 2*3 side and 2 cap triangles.
        let prisms = (3u64.pow(depth + 1) - 1) / 2;
        assert_eq!(count(&stats, "triangles"), prisms * 8, "depth {depth}");
    }
}

#[test]
fn sierpinski_steps_are_levels_of_the_fractal() {
    for k in 0..4u32 {
        let steps = k.to_string();
        let (stats, _, _dir) = run("sierpinski.lua", &["--steps", &steps]);
        let prisms = (3u64.pow(k + 1) - 1) / 2;
        assert_eq!(count(&stats, "triangles"), prisms * 8, "step {k}");
        // Each refined triangle is P, then three branches Push Corner S Pop.
        assert_eq!(
            count(&stats, "modules"),
            1 + 12 * (prisms - 3u64.pow(k)),
            "step {k}"
        );
    }
}

#[test]
fn fireworks_steps_are_frames() {
    // Lines only: two vertices per segment (an empty frame has no glb meshes to count).
    let frames: Vec<u64> = ["1", "10", "25", "40"]
        .iter()
        .map(|k| {
            let stats = run("fireworks.lua", &["--steps", k, "--set", "width=0"]).0;
            count(&stats, "vertices") / 2
        })
        .collect();
    assert!(
        frames[0] < frames[1] && frames[1] < frames[2],
        "rising then bursting: {frames:?}"
    );
    let (stats, _, _dir) = run(
        "fireworks.lua",
        &["--set", "frames=200", "--set", "width=0"],
    );
    assert_eq!(
        count(&stats, "vertices"),
        0,
        "the show has burnt out: {stats}"
    );
    assert!(
        count(&stats, "modules") <= 8,
        "B > B removed the spent trails: {stats}"
    );
}

#[test]
fn explorers_write_their_trails_into_a_png() {
    let (_, early, dir) = run(
        "explorers.lua",
        &["--steps", "5", "--set", "out=trails.png"],
    );
    let png = std::fs::read(dir.path().join("trails.png")).expect("the map was saved");
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let size = |b: &[u8], at: usize| u32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
    assert_eq!((size(&png, 16), size(&png, 20)), (64, 64), "the map's size");
    let (_, late, dir2) = run("explorers.lua", &["--set", "out=trails.png"]);
    let png_late = std::fs::read(dir2.path().join("trails.png")).expect("saved");
    assert_ne!(png, png_late, "more trails after more steps");
    assert_ne!(early, late);
}

/// A script that must fail: exit 1, one line `tests/modellers/FILE:LINE: ...` naming the
/// problem, no panic.
fn assert_fails(file: &str, extra: &[&str], line: u32, needle: &str) {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out.glb");
    let path = format!("tests/modellers/{file}");
    let mut args = vec![
        "run",
        path.as_str(),
        "-o",
        out.to_str().expect("utf-8"),
        "-q",
    ];
    args.extend_from_slice(extra);
    let o = pge_in(&args, &root());
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "{file}: {err}");
    assert!(!err.contains("panicked"), "{file}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{file}: one line: {err}");
    let prefix = format!("{path}:{line}: ");
    assert!(
        err.starts_with(&prefix),
        "{file}: expected '{prefix}...', got: {err}"
    );
    assert!(
        err.contains(needle),
        "{file}: expected '{needle}' in: {err}"
    );
    assert!(!out.exists(), "{file} wrote a model");
}

#[test]
fn bad_input_gives_located_errors() {
    assert_fails(
        "too_few_points.lua",
        &[],
        4,
        "the shape has 2 point(s); extruding needs at least 3",
    );
    assert_fails(
        "pop_without_push.lua",
        &[],
        4,
        "pop without a matching push",
    );
    assert_fails("extruder_pop.lua", &[], 4, "pop without a matching push");
    assert_fails(
        "bad_resolution.lua",
        &[],
        3,
        "resolution must be a whole number of cells between 1 and",
    );
    assert_fails(
        "grid_too_large.lua",
        &["--memory-limit", "16"],
        6,
        "memory limit",
    );
    assert_fails(
        "pixel_out_of_range.lua",
        &[],
        3,
        "pixel (16, 2) is outside the 16x8 image",
    );
    assert_fails("missing_image.lua", &[], 1, "no_such_map.png");
}

/// Per segment of a tube mesh (8 vertices, all of the segment's colour): the brightest
/// channel of its colour, 0 to 255.
fn tube_brightness(glb: &[u8]) -> Vec<u8> {
    let (doc, buffers, _) = gltf::import_slice(glb).expect("the glb imports");
    let mut out = Vec::new();
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            assert_eq!(prim.mode(), gltf::mesh::Mode::Triangles, "tubes, not lines");
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let colours: Vec<[u8; 4]> = reader
                .read_colors(0)
                .expect("vertex colours")
                .into_rgba_u8()
                .collect();
            out.extend(
                colours
                    .chunks_exact(8)
                    .map(|c| c[0][0].max(c[0][1]).max(c[0][2])),
            );
        }
    }
    out
}

#[test]
fn fireworks_default_frame_shows_lit_tubes() {
    // The default frame shows bursts while they are bright; frame 60 (the old default) had
    // faded to black.
    let (stats, glb, _dir) = run("fireworks.lua", &[]);
    let lit = |b: &[u8]| b.iter().filter(|&&v| v >= 128).count();
    let default = tube_brightness(&glb);
    assert_eq!(count(&stats, "triangles"), 8 * default.len() as u64);
    assert!(lit(&default) >= 100, "lit segments: {}", lit(&default));
    let (_, late, _dir) = run("fireworks.lua", &["--set", "frames=60"]);
    let late = tube_brightness(&late);
    assert!(
        lit(&late) < lit(&default) / 4,
        "frame 60 has faded: {}",
        lit(&late)
    );
}
