//! A fixed amount of Lua rule calls, for `perf stat` (instructions and CPU time per module):
//! `cargo run --release -p pge-lsystem --example lua_rules -- CASE [RUNS]`, where CASE is
//! `one` (`RRule("A", function(a) return A{a[1] + 1} end)`), `three` (`{ B{}, A{}, B{} }`)
//! or `nil` (a rule that does not apply). Each run derives 100 steps of a 1,000-module string
//! (100,000 rule calls; `three`: 20 steps) in the session's usual limits (instruction-count
//! hook included). It prints the rule calls made and the CPU time of the thread per call.

use pge_engine::{Engine, Location, SessionOptions};

fn main() {
    let mut args = std::env::args().skip(1);
    let case = args.next().unwrap_or_else(|| "one".into());
    let runs: u32 = args.next().and_then(|a| a.parse().ok()).unwrap_or(20);
    let rule = match case.as_str() {
        "one" => "function(a) return A{a[1] + 1} end",
        "three" => "function(a) return { B{}, A{}, B{} } end",
        "nil" => "function(a) return nil end",
        other => {
            eprintln!("unknown case '{other}': one, three or nil");
            std::process::exit(2);
        }
    };
    // `three` adds two modules per call: fewer steps keep the string (copied at each step)
    // short.
    let (axiom, steps, made) = match case.as_str() {
        "three" => ("string.rep('A', 1000)", 20u32, 3u64),
        "one" => ("string.rep('A(1)', 1000)", 100, 1),
        _ => ("string.rep('A(1)', 1000)", 100, 0),
    };
    let prelude = std::env::var("LUA_RULES_PRELUDE").unwrap_or_default();
    let code = format!(
        "{prelude}\nlocal l = pge.LSystem('bench')\nl:axiom({axiom})\nl:RRule('A', {rule})\n\
         l:iterations({steps})\nl:maxModules(100000000)\nreturn l"
    );
    let engine = match Engine::builder().plugin(pge_lsystem::LSystemPlugin).build() {
        Ok(e) => e,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    let result = (|| -> pge_engine::Result<u64> {
        let session = engine.session(SessionOptions::default())?;
        let value = session.eval_value(&code)?;
        let ctx = session.context();
        let location = Location::new("lua_rules", 0);
        let mut calls = 0u64;
        for _ in 0..runs {
            let d = pge_lsystem::derive_value(session.lua(), &value, &ctx, &location)?;
            // Every step calls the rule once for each of the 1,000 A.
            calls += 1000 * u64::from(steps);
            std::hint::black_box(d.len());
        }
        Ok(calls)
    })();
    match result {
        Ok(calls) => {
            let cpu = thread_cpu_ns();
            println!(
                "{case}: {calls} rule calls making {} modules, {:.0} ns of thread CPU per call \
                 ({:.2} M calls/s)",
                calls * made,
                cpu as f64 / calls as f64,
                calls as f64 / cpu as f64 * 1e3
            );
        }
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
}

/// The CPU time of this thread (Linux), 0 elsewhere.
fn thread_cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}
