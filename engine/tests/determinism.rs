//! Byte-identical output without any build setting: the engine as a host program gets it,
//! whatever seed Lua gives its string hashes (the clock and addresses, different in every
//! process and every Lua state). The script builds its model in `pairs` and `next` order.
//!
//! The test runs this test binary again as two child processes (with `PGE_DETERMINISM_CHILD`
//! set to a file name, `child_writes_the_glb` writes the glb there) and compares their bytes;
//! within one process, two Lua states alive at the same time (so at different addresses)
//! must agree too.

use std::path::PathBuf;
use std::process::Command;

use pge_engine::export::glb_bytes;
use pge_engine::{Engine, SessionOptions};

const CHILD: &str = "PGE_DETERMINISM_CHILD";

fn script() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/scripts/hash_order.lua")
}

/// The glb of the script in a session of `engine`.
fn glb(session: &pge_engine::Session) -> Vec<u8> {
    let generated = session
        .generate(&script(), &mut |_, _| {})
        .expect("generates");
    glb_bytes(&generated.model, &Default::default()).expect("exports")
}

#[test]
fn child_writes_the_glb() {
    let Some(out) = std::env::var_os(CHILD) else {
        return;
    };
    let engine = Engine::builder().build().expect("engine");
    let session = engine.session(SessionOptions::default()).expect("session");
    std::fs::write(out, glb(&session)).expect("written");
}

#[test]
fn two_processes_write_the_same_bytes() {
    let dir = std::env::temp_dir().join(format!("pge-determinism-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp folder");
    let run = |name: &str| {
        let file = dir.join(name);
        let out = Command::new(std::env::current_exe().expect("test binary"))
            .args(["--exact", "child_writes_the_glb", "--quiet"])
            .env(CHILD, &file)
            .output()
            .expect("runs");
        assert!(
            out.status.success(),
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        std::fs::read(&file).expect("the child wrote the glb")
    };
    let (a, b) = (run("a.glb"), run("b.glb"));
    std::fs::remove_dir_all(&dir).ok();
    assert!(a.len() > 1000);
    assert_eq!(a, b, "two processes wrote different bytes");
}

#[test]
fn two_lua_states_at_once_agree_and_visit_keys_in_order() {
    let engine = Engine::builder().build().expect("engine");
    let s1 = engine.session(SessionOptions::default()).expect("session");
    let s2 = engine.session(SessionOptions::default()).expect("session");
    let (a, b) = (glb(&s1), glb(&s2));
    assert_eq!(a, b);
    let generated = s1.generate(&script(), &mut |_, _| {}).expect("generates");
    assert_eq!(
        generated.model.meshes[0].name,
        "-7,0.5,key1,key10,key100,key101,key102,key103,key104,key105,key106,key107"
    );
}
