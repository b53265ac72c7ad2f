//! The forest's Rust face: a host builds the forest in Rust and grows it from the library's
//! species scripts (the `forest_species` example); a variant's limit reaches the host as the
//! engine's typed limit, and the command line prints it located; the algorithm a script
//! returns is asked for its tiles from Rust.

mod common;
#[path = "../examples/forest_species.rs"]
mod forest_species;

use std::sync::Arc;
use std::time::Duration;

use common::{pge, root};
use pge_engine::{Error, RunContext, SessionOptions};
use pge_forest::lua::SessionGrower;
use pge_forest::{ForestError, ForestRun, ForestSpec, Layer, ScriptSpecies, Species};

#[test]
fn the_rust_host_example_grows_the_forest_it_laid_out() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("species.glb");
    let engine = pge::default_engine().build().expect("engine");
    let model = forest_species::run(engine.clone(), 150, None, &out).expect("the example runs");
    let layout = forest_species::spec(150)
        .expect("spec")
        .forest()
        .layout(None)
        .expect("layout");
    assert!(layout.counts.iter().all(|&n| n > 0), "{:?}", layout.counts);
    assert_eq!(forest_species::counts(&model), layout.counts);
    assert_eq!(model.instance_count(), 1 + layout.instances.len());
    let names: Vec<&str> = model.groups.iter().map(|g| g.name.as_str()).collect();
    assert_eq!(names, ["oak/0", "oak/1", "conifer/0", "conifer/1"]);
    // Grown trees, not markers: every variant has bark and leaves.
    assert!(
        model.groups.iter().all(|g| g.meshes.len() >= 2),
        "{names:?}"
    );
    let glb = std::fs::read(&out).expect("written");
    assert_eq!(&glb[..4], b"glTF");
    // A tile holds the tile's trees of the same layout.
    let tile = forest_species::run(engine, 150, Some((1, 0)), &dir.path().join("t.glb"))
        .expect("the tile runs");
    let in_tile = forest_species::spec(150)
        .expect("spec")
        .forest()
        .layout(Some((1, 0)))
        .expect("layout");
    assert_eq!(forest_species::counts(&tile), in_tile.counts);
}

/// A forest script beside a species script that never ends.
fn looping_forest() -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("loop.lua"),
        "local n = 0\nwhile true do\n  n = n + 1\nend\n",
    )
    .expect("species");
    let script = dir.path().join("forest.lua");
    std::fs::write(
        &script,
        "local f = pge.Forest{ size = 40 }\n\
         f:scatter{ species = \"loop.lua\", minDistance = 5, variants = 1 }\n\
         return f\n",
    )
    .expect("forest");
    (dir, script)
}

fn is_the_loop(e: &Error) -> bool {
    matches!(e, Error::TimeLimit { location } if location.file.ends_with("loop.lua") && location.line.is_some_and(|l| (2..=3).contains(&l)))
}

#[test]
fn a_variant_that_runs_out_of_time_is_a_time_limit_to_the_host() {
    let (dir, script) = looping_forest();
    let engine = pge::default_engine()
        .time_limit(Some(Duration::from_millis(300)))
        .build()
        .expect("engine");
    // Through a session, as the command line runs it: the engine's typed limit.
    let session = engine.session(SessionOptions::default()).expect("session");
    let e = session
        .generate(&script, &mut |_, _| {})
        .expect_err("the species loops");
    assert!(is_the_loop(&e), "{e:?}");
    // Through the Rust face: the forest's error, with the session's limit inside.
    let mut spec = ForestSpec::new([40.0, 40.0], 1, None).expect("spec");
    let mut layer = Layer::new("loop", 5.0);
    layer.variants = pge_forest::Variants::Count(1);
    let species = ScriptSpecies::new(dir.path().join("loop.lua").to_string_lossy(), &[]);
    spec.add_layer(layer, Species::Script(species))
        .expect("layer");
    let mut run = ForestRun::new(spec).grower(Arc::new(SessionGrower::new(engine)));
    let e = run
        .run(&RunContext::default())
        .expect_err("the species loops");
    let ForestError::Species {
        layer: 0, error, ..
    } = &e
    else {
        panic!("{e:?}");
    };
    assert!(is_the_loop(error), "{error:?}");
    assert!(e.engine_error().is_some_and(Error::is_limit));
    assert!(is_the_loop(&run.engine_error(e)));
}

#[test]
fn the_command_line_prints_a_variants_time_limit_located_and_exits_1() {
    let (dir, script) = looping_forest();
    let out = dir.path().join("out.glb");
    let o = pge(&[
        "run",
        &script.to_string_lossy(),
        "-o",
        &out.to_string_lossy(),
        "-q",
        "--time-limit",
        "0.3",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("loop.lua:2: time limit exceeded (see --time-limit)")
            || err.contains("loop.lua:3: time limit exceeded (see --time-limit)"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists());
}

#[test]
fn the_algorithm_a_forest_script_returns_is_asked_for_its_tiles() {
    let engine = pge::default_engine().build().expect("engine");
    let session = engine.session(SessionOptions::default()).expect("session");
    let value = session
        .run_script(&root().join("scripts/forests/mixed.lua"))
        .expect("runs");
    let mut algorithm = session.algorithm_from(value).expect("an algorithm");
    let forest = ForestRun::of(&mut *algorithm).expect("a forest");
    let tiles = forest.tiles(&pge_engine::Budget::default()).expect("tiled");
    assert_eq!(tiles.len(), 9);
    assert_eq!((tiles[4].i, tiles[4].j), (1, 1));
    assert_eq!(tiles[4].rect.min, [-50.0, -50.0]);
    forest.select_tile(1, 2).expect("a tile");
    assert_eq!(forest.spec().tile(), Some((1, 2)));
    let e = forest.select_tile(3, 0).expect_err("out of range");
    assert!(
        matches!(e, ForestError::TileOutOfRange { i: 3, .. }),
        "{e:?}"
    );
    let located = forest.engine_error(e).to_string();
    assert!(
        located.starts_with(&format!(
            "{}:9: ",
            root().join("scripts/forests/mixed.lua").display()
        )),
        "{located}"
    );
    // Anything else is no forest.
    let value = session
        .eval_value("return pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }")
        .expect("a mesh");
    let mut mesh = session.algorithm_from(value).expect("an algorithm");
    assert!(ForestRun::of(&mut *mesh).is_none());
}
