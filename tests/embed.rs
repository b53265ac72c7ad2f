//! End-to-end tests of the library's entry point (`pge::generate`, what the Python module
//! and other hosts call): its bytes are `pge run`'s for the same arguments, its statistics
//! `--stats`' without the file, its errors typed with file and line.

mod common;

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use common::{pge, root};
use pge::{ErrorKind, Request, Script};

/// `pge run SCRIPT -o OUT ARGS... --stats -q` in the repository root: the bytes and the stats.
fn run(script: &str, args: &[&str]) -> (Vec<u8>, serde_json::Value) {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out.glb");
    let out_arg = out.to_string_lossy().to_string();
    let mut all = vec!["run", script, "-o", &out_arg, "--stats", "-q"];
    all.extend_from_slice(args);
    let o = pge(&all);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stats = serde_json::from_slice(&o.stdout).expect("stats json");
    (std::fs::read(&out).expect("written"), stats)
}

fn file(script: &str) -> Request {
    Request::new(Script::File(root().join(script)))
}

/// The stats without what differs between two runs (seconds) or what only a file has.
fn comparable(mut stats: serde_json::Value) -> serde_json::Value {
    let object = stats.as_object_mut().expect("an object");
    for key in ["seconds", "phases", "output"] {
        object.remove(key);
    }
    stats
}

#[test]
fn the_oak_is_the_bytes_pge_run_writes_with_its_stats() {
    let (bytes, stats) = run(
        "scripts/species/oak.lua",
        &["--seed", "3", "--set", "height=9"],
    );
    let mut request = file("scripts/species/oak.lua");
    request.seed = 3;
    request.params.push(("height".into(), "9".into()));
    let generation = pge::generate(&request).expect("generates");
    assert!(generation.glb == bytes, "the glb differs from pge run's");
    assert_eq!(comparable(generation.stats.clone()), comparable(stats));
    assert!(generation.warnings.is_empty(), "{:?}", generation.warnings);
    // The same on a pool of its own of one thread.
    request.threads = Some(1);
    assert!(pge::generate(&request).expect("generates").glb == bytes);
}

#[test]
fn a_script_given_as_text_is_the_file_it_names() {
    let script = "scripts/examples/spiral.lua";
    let (bytes, _) = run(script, &["--steps", "3"]);
    // Named by its absolute path, so its `require("lib.box")` finds the library beside it.
    let mut request = Request::new(Script::Source {
        name: root().join(script).to_string_lossy().to_string(),
        text: std::fs::read_to_string(root().join(script)).expect("script"),
    });
    request.steps = Some(3);
    let generation = pge::generate(&request).expect("generates");
    assert!(generation.glb == bytes);
    // What a host watches to regenerate on save: the script and the module it requires.
    let names: Vec<_> = generation
        .files
        .iter()
        .filter_map(|f| f.file_name())
        .collect();
    assert!(names.contains(&"spiral.lua".as_ref()), "{names:?}");
    assert!(names.contains(&"box.lua".as_ref()), "{names:?}");
}

#[test]
fn stages_are_the_bytes_of_pge_run_stages() {
    let script = "scripts/lsystems/plants.lua";
    let (bytes, stats) = run(script, &["--stages", "1,3"]);
    let mut request = file(script);
    request.stages = Some(vec![1, 3]);
    let generation = pge::generate(&request).expect("generates");
    assert!(generation.glb == bytes, "the glb differs from pge run's");
    assert_eq!(comparable(generation.stats), comparable(stats));
}

#[test]
fn errors_carry_the_file_line_and_kind() {
    let dir = tempfile::tempdir().expect("tempdir");
    let script = dir.path().join("bad.lua");
    std::fs::write(&script, "local x = 1\nlocal y = nil + x\nreturn y").expect("write");
    let e = pge::generate(&Request::new(Script::File(script.clone()))).expect_err("fails");
    assert_eq!(e.kind(), ErrorKind::Script);
    assert_eq!(e.file().as_deref(), Some(&*script.to_string_lossy()));
    assert_eq!(e.line(), Some(2));
    // pge run prints the same line.
    let o = pge(&["run", &script.to_string_lossy(), "-o", "/dev/null/x.glb"]);
    assert_eq!(String::from_utf8_lossy(&o.stderr).trim(), e.to_string());
    let missing = pge::generate(&file("no/such.lua")).expect_err("no file");
    assert_eq!(missing.kind(), ErrorKind::Script);
    assert!(
        missing.message().starts_with("cannot read script"),
        "{missing}"
    );
}

#[test]
fn a_runaway_script_stops_at_its_time_limit_or_when_cancelled() {
    let runaway = || {
        Request::new(Script::Source {
            name: "runaway.lua".into(),
            text: "local t = {}\nwhile true do\n  t[1] = (t[1] or 0) + 1\nend".into(),
        })
    };
    let mut request = runaway();
    request.time_limit = Duration::from_millis(300);
    let e = pge::generate(&request).expect_err("stops");
    assert_eq!(e.kind(), ErrorKind::TimeLimit);
    assert_eq!(e.file().as_deref(), Some("runaway.lua"));
    // Cancelled from another thread while it runs.
    let cancel = Arc::new(AtomicBool::new(false));
    let mut request = runaway();
    request.cancel = Some(cancel.clone());
    let worker = std::thread::spawn(move || pge::generate(&request));
    std::thread::sleep(Duration::from_millis(100));
    cancel.store(true, Ordering::Relaxed);
    let e = worker.join().expect("joins").expect_err("cancelled");
    assert_eq!(e.kind(), ErrorKind::Cancelled, "{e}");
    assert!(Path::new(&e.file().expect("a file")).ends_with("runaway.lua"));
}
