//! Every script of `scripts/modellers/` runs with the modeller plugins (and the L-system
//! plugin) in an engine of their own, gives a valid, non-empty model and exports the same
//! glb bytes twice. (The `pge` command's end-to-end tests are in `tests/modellers.rs`.)

use std::path::PathBuf;

use pge_engine::geometry::{Model, Primitive};
use pge_engine::{Engine, SessionOptions};

fn script(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scripts/modellers")
        .join(name)
}

fn generate(name: &str, params: &[(&str, &str)], steps: Option<u32>) -> Model {
    generate_seeded(name, params, steps, 1)
}

fn generate_seeded(name: &str, params: &[(&str, &str)], steps: Option<u32>, seed: u64) -> Model {
    let engine = Engine::builder()
        .plugin(pge_extruder::ExtruderPlugin)
        .plugin(pge_metaballs::MetaballsPlugin)
        .plugin(pge_canvas::CanvasPlugin)
        .plugin(pge_lsystem::LSystemPlugin)
        .build()
        .expect("engine");
    let options = SessionOptions {
        params: params
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        steps,
        seed,
        ..SessionOptions::default()
    };
    let session = engine.session(options).expect("session");
    let model = session
        .generate(&script(name), &mut |_, _| {})
        .expect(name)
        .model;
    model.validate().expect("valid model");
    model
}

fn glb(model: &Model) -> Vec<u8> {
    pge_engine::export::glb_bytes(model, &Default::default()).expect("exports")
}

fn lines(model: &Model) -> usize {
    model
        .instances
        .iter()
        .map(|i| &model.meshes[i.mesh])
        .filter(|m| m.primitive == Primitive::Lines)
        .map(|m| m.indices.len() / 2)
        .sum()
}

macro_rules! script_test {
    ($name:ident, $file:literal, $check:expr) => {
        #[test]
        fn $name() {
            let a = generate($file, &[], None);
            let b = generate($file, &[], None);
            assert_eq!(glb(&a), glb(&b), "{} is deterministic", $file);
            let check: fn(&Model) = $check;
            check(&a);
        }
    };
}

script_test!(sierpinski, "sierpinski.lua", |m| {
    // depth 4, stacked: (3^5 - 1) / 2 = 121 triangular prisms of 8 triangles.
    assert_eq!(m.triangle_count(), 121 * 8);
});
script_test!(tower, "tower.lua", |m| assert!(m.triangle_count() > 10_000));
script_test!(crystals, "crystals.lua", |m| assert!(
    m.triangle_count() > 500
));
script_test!(coral, "coral.lua", |m| {
    assert_eq!(m.meshes.len(), 2, "extrusion and metaballs");
    assert!(m.meshes.iter().all(|mesh| mesh.triangle_count() > 1000));
});
script_test!(coral_metaballs, "coral_metaballs.lua", |m| {
    assert_eq!(m.stats.modules, 161, "3^4 * 2 - 1 symbols after 4 steps");
    assert!(m.triangle_count() > 10_000);
});
script_test!(city, "city.lua", |m| assert!(m.triangle_count() > 10_000));
script_test!(fireworks, "fireworks.lua", |m| {
    // Thin tubes by default: triangles every client renders, no line primitives.
    assert_eq!(lines(m), 0);
    assert!(m.triangle_count() > 1000);
});
script_test!(explorers, "explorers.lua", |m| {
    assert_eq!(m.meshes.len(), 3, "map, marks, plants");
    assert!(m.meshes.iter().any(|mesh| mesh.material.texture.is_some()));
});

#[test]
fn sierpinski_depth_follows_the_formula() {
    for depth in 0..4u32 {
        let m = generate("sierpinski.lua", &[("depth", &depth.to_string())], None);
        let prisms = (3usize.pow(depth + 1) - 1) / 2;
        assert_eq!(m.triangle_count(), prisms * 8, "depth {depth}");
        let flat = generate(
            "sierpinski.lua",
            &[("depth", &depth.to_string()), ("stacked", "0")],
            None,
        );
        assert_eq!(
            flat.triangle_count(),
            3usize.pow(depth) * 8,
            "flat, depth {depth}"
        );
    }
}

#[test]
fn fireworks_frames_differ_and_the_show_burns_out() {
    let counts: Vec<usize> = [1, 10, 25, 40]
        .iter()
        .map(|&k| lines(&generate("fireworks.lua", &[("width", "0")], Some(k))))
        .collect();
    assert!(counts[0] < counts[1] && counts[1] < counts[2], "{counts:?}");
    // Long after the last burst every trail has faded and `B > B` has cleaned the string.
    let end = generate("fireworks.lua", &[("frames", "200"), ("width", "0")], None);
    assert_eq!(lines(&end), 0);
    assert!(
        end.stats.modules <= 8,
        "spent trails leave the string: {}",
        end.stats.modules
    );
}

#[test]
fn city_rows_and_random_buildings() {
    let identical = generate("city.lua", &[("random", "0")], None).triangle_count();
    let one = generate("city.lua", &[("random", "0"), ("identical", "1")], None).triangle_count();
    assert_eq!(identical, 3 * one, "the City rule copies the same building");
    // The City row ignores the seed; the RandCity row draws new buildings from it.
    let fixed = |seed| glb(&generate_seeded("city.lua", &[("random", "0")], None, seed));
    assert_eq!(fixed(1), fixed(2));
    let random = |seed| {
        glb(&generate_seeded(
            "city.lua",
            &[("identical", "0")],
            None,
            seed,
        ))
    };
    assert_ne!(random(1), random(2));
}
