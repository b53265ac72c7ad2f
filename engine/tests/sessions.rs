//! Sessions without the command line: sandbox, modules, parameters, limits.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use pge_engine::{Engine, SessionOptions, mlua};

fn script(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/scripts")
        .join(name)
}

#[test]
fn load_passes_parameters_and_require_caches() {
    let engine = Engine::builder().build().expect("engine");
    let session = engine
        .session(SessionOptions {
            params: vec![("n".into(), "4".into())],
            ..Default::default()
        })
        .expect("session");
    let value = session.run_script(&script("main.lua")).expect("runs");
    let t = value.as_table().expect("a table");
    assert_eq!(t.get::<i64>("child").expect("child"), 12);
    assert_eq!(t.get::<i64>("count").expect("count"), 1);
    let files = session.loaded_files();
    assert_eq!(files.len(), 3, "{files:?}");
    let params = session.declared_params();
    assert_eq!(params.len(), 1);
    assert_eq!(params[0].name, "n");
    assert_eq!(params[0].value, pge_engine::ParamValue::Integer(4));
}

#[test]
fn load_with_an_undeclared_parameter_names_it() {
    let engine = Engine::builder().build().expect("engine");
    let session = engine.session(SessionOptions::default()).expect("session");
    let err = session
        .run_script(&script("bad_load.lua"))
        .expect_err("sise is not declared")
        .to_string();
    assert!(err.contains("bad_load.lua:1: "), "{err}");
    assert!(
        err.contains("unknown parameter sise given with pge.load; declared parameters: size"),
        "{err}"
    );
}

#[test]
fn instruction_budget_stops_a_loop() {
    let engine = Engine::builder()
        .instruction_limit(Some(100_000))
        .build()
        .expect("engine");
    let session = engine.session(SessionOptions::default()).expect("session");
    let err = session
        .eval::<()>("local i = 0\nwhile true do i = i + 1 end")
        .expect_err("stops");
    assert!(
        err.to_string()
            .contains("instruction limit of 100000 exceeded"),
        "{err}"
    );
}

#[test]
fn cancel_flag_stops_a_loop() {
    let cancel = Arc::new(AtomicBool::new(true));
    let engine = Engine::builder()
        .time_limit(Some(Duration::from_secs(60)))
        .build()
        .expect("engine");
    let session = engine
        .session(SessionOptions {
            cancel: Some(cancel),
            ..Default::default()
        })
        .expect("session");
    let err = session
        .eval::<()>("while true do end")
        .expect_err("cancelled");
    assert!(err.to_string().ends_with("cancelled"), "{err}");
}

#[test]
fn math_random_follows_the_seed() {
    let engine = Engine::builder().build().expect("engine");
    let draw = |seed| {
        let s = engine
            .session(SessionOptions {
                seed,
                ..Default::default()
            })
            .expect("session");
        s.eval::<(f64, i64)>("return math.random(), math.random(1, 100)")
            .expect("draws")
    };
    assert_eq!(draw(9), draw(9));
    assert_ne!(draw(9), draw(10));
}

#[test]
fn sandbox_has_no_files_or_binary_chunks() {
    let engine = Engine::builder().build().expect("engine");
    let session = engine.session(SessionOptions::default()).expect("session");
    for code in [
        "return dofile",
        "return loadfile",
        "return io",
        "return os",
        "return debug",
        "return package",
    ] {
        let v: mlua::Value = session.eval(code).expect("evaluates");
        assert!(v.is_nil(), "{code} should be nil");
    }
    let err = session.eval::<mlua::Value>("return load(string.dump(function() end))()");
    assert!(err.is_err(), "binary chunks are refused");
}

#[test]
fn a_script_given_as_text_reads_the_folder_of_its_name_and_is_named_in_errors() {
    let engine = Engine::builder().build().expect("engine");
    let session = engine
        .session(SessionOptions {
            params: vec![("n".into(), "4".into())],
            ..Default::default()
        })
        .expect("session");
    // The text of main.lua, as an editor holds it: it requires its sibling modules.
    let name = script("unsaved.lua");
    let text = std::fs::read_to_string(script("main.lua")).expect("main.lua");
    let value = session
        .run_source(&name.to_string_lossy(), &text)
        .expect("runs");
    let t = value.as_table().expect("a table");
    assert_eq!(t.get::<i64>("child").expect("child"), 12);
    assert_eq!(session.declared_params()[0].name, "n");

    let session = engine.session(SessionOptions::default()).expect("session");
    let err = session
        .run_source("nowhere/tree.lua", "local x = 1\nerror('no tree')")
        .expect_err("fails");
    assert_eq!(
        err.location().map(ToString::to_string).as_deref(),
        Some("nowhere/tree.lua:2")
    );
    assert!(err.to_string().ends_with("no tree"), "{err}");
    // With no folder, a module beside the name is out of reach.
    let session = engine.session(SessionOptions::default()).expect("session");
    let err = session
        .run_source("nowhere/tree.lua", "return require('sub.child')")
        .expect_err("no folder");
    assert!(err.to_string().starts_with("nowhere/tree.lua:1: "), "{err}");
}
