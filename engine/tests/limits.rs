//! A host matching the limits a script ran into: they come back as typed errors
//! (`Error::TimeLimit`, `Error::MemoryLimit`, ...), also when they happened in Rust code that
//! Lua called, and still print as `FILE:LINE: message`.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use pge_engine::{Engine, Error, Location, SessionOptions};

fn engine_with_time_limit(limit: Duration) -> Engine {
    Engine::builder()
        .time_limit(Some(limit))
        .build()
        .expect("engine")
}

#[test]
fn an_endless_loop_is_a_time_limit() {
    let session = engine_with_time_limit(Duration::from_millis(50))
        .session(SessionOptions::default())
        .expect("session");
    let err = session
        .eval::<()>("local i = 0\nwhile true do\n  i = i + 1\nend")
        .expect_err("stops");
    match &err {
        Error::TimeLimit { location } => assert_eq!(location.file, "eval"),
        other => panic!("expected Error::TimeLimit, got {other:?}"),
    }
    assert!(err.is_limit());
    let text = err.to_string();
    assert!(text.starts_with("eval:"), "{text}");
    assert!(
        text.ends_with(": time limit exceeded (see --time-limit)"),
        "{text}"
    );
}

#[test]
fn a_time_limit_inside_an_algorithm_run_from_lua_comes_back_typed() {
    // The step is Lua, the loop around it is Rust (`:model()` runs the algorithm), and the
    // deadline is found by the Rust side: the error crosses Lua twice.
    let session = engine_with_time_limit(Duration::from_millis(50))
        .session(SessionOptions::default())
        .expect("session");
    let err = session
        .eval::<()>(
            "local a = pge.Algorithm{\n  step = function() return true end,\n  \
             finish = function() return pge.model() end,\n}\nlocal m = a:model()",
        )
        .expect_err("stops");
    assert!(
        matches!(err, Error::TimeLimit { .. }),
        "expected Error::TimeLimit, got {err:?}"
    );
}

#[test]
fn memory_instructions_and_cancel_are_their_own_variants() {
    let engine = Engine::builder()
        .memory_limit_mib(16)
        .build()
        .expect("engine");
    let session = engine.session(SessionOptions::default()).expect("session");
    let err = session
        .eval::<()>("local t = {}\nfor i = 1, 1e8 do t[i] = {i} end")
        .expect_err("too big");
    match &err {
        Error::MemoryLimit {
            location, limit, ..
        } => {
            assert_eq!(*limit, 16 << 20);
            assert_eq!(location.file, "eval");
        }
        other => panic!("expected Error::MemoryLimit, got {other:?}"),
    }
    assert!(err.to_string().contains("memory limit of 16 MiB exceeded"));

    let engine = Engine::builder()
        .instruction_limit(Some(100_000))
        .build()
        .expect("engine");
    let session = engine.session(SessionOptions::default()).expect("session");
    let err = session.eval::<()>("while true do end").expect_err("stops");
    assert!(
        matches!(err, Error::InstructionLimit { limit: 100_000, .. }),
        "{err:?}"
    );

    let cancel = Arc::new(AtomicBool::new(true));
    let session = Engine::builder()
        .build()
        .expect("engine")
        .session(SessionOptions {
            cancel: Some(cancel.clone()),
            ..SessionOptions::default()
        })
        .expect("session");
    let err = session.eval::<()>("while true do end").expect_err("stops");
    assert!(matches!(err, Error::Cancelled { .. }), "{err:?}");
    cancel.store(false, Ordering::Relaxed);
}

#[test]
fn mistakes_stay_script_errors() {
    let session = Engine::builder()
        .build()
        .expect("engine")
        .session(SessionOptions::default())
        .expect("session");
    let err = session
        .eval::<()>("\nlocal r = pge.rng(1):int(3, 1)")
        .expect_err("bad bounds");
    match err {
        Error::Script {
            location, message, ..
        } => {
            assert_eq!(location, Location::new("eval", 2));
            assert_eq!(message, "rng:int(3, 1): the first bound exceeds the second");
        }
        other => panic!("expected Error::Script, got {other:?}"),
    }
}
