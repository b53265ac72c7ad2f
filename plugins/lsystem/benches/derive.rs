//! Derivation speed against peers measured in the same run (see `benches/README.md`).
//!
//! Each group runs PGE and its peer on the same input, so their ratio holds on a loaded
//! machine where absolute times do not:
//! - `classic_1_24d`: ABOP fig. 1.24d (`X -> F[+X]F[-X]+X`, `F -> FF`) against the
//!   `lindenmayer` crate. Every iteration makes the whole final string on both sides, in
//!   pairs that allocate alike: fresh buffers on both sides (PGE's two module buffers against
//!   the crate's `string`, which allocates a new `String` each step), or buffers kept from
//!   the previous iteration on both sides (PGE's two buffers against the crate's streaming
//!   `builder` collected into one kept `String`: its `string` cannot write into the
//!   caller's buffer). The strings are compared once before timing;
//! - `parametric_2_6`: ABOP fig. 2.6 (Honda's tree) against a hand-written `Vec<Module>`
//!   loop specialised to these three rules;
//! - `context_signal`: signal propagation on 100 000 modules against a hand-written
//!   bracket-aware loop (a straightforward one, not a tuned limit);
//! - `lua_rules`: rule functions (a rule returning three modules, a rule returning one
//!   module with a parameter, a rule that does not apply), with no peer and no speed
//!   target: they run under the deterministic instruction limit, and classic notation is
//!   the fast path.
//!
//! Criterion reports modules produced per second ("elements").

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pge_lsystem::{DeriveOptions, ModuleString, NativeHost, Output, Prepared, SymbolTable, System};
use rand_mt::Mt;

struct Setup {
    prepared: Prepared,
    axiom: ModuleString,
    symbols: SymbolTable,
}

fn setup(axiom: &str, rules: &[&str], globals: &[(&str, f64)], ignore: &str) -> Setup {
    let mut symbols = SymbolTable::new();
    let mut system = System::new();
    for (n, v) in globals {
        system.set_global(n, *v);
    }
    system.ignore(ignore, &mut symbols);
    for r in rules {
        system
            .add_production(r, None, 0, &mut symbols)
            .expect("rule");
    }
    let prepared = system.prepare(&symbols).expect("prepare");
    let axiom = system
        .parse_string(axiom, &mut symbols, &mut || 0.0)
        .expect("axiom");
    Setup {
        prepared,
        axiom,
        symbols,
    }
}

/// Derives `steps` steps; returns the final string and the modules produced over all steps.
/// The first step reads the axiom in place (as the hand-written peers read their input).
fn derive(s: &Setup, steps: u32, a: &mut ModuleString, b: &mut ModuleString) -> u64 {
    let mut rng = Mt::new(1);
    let mut produced = 0u64;
    for step in 1..=steps {
        let opts = DeriveOptions::new(step, 1, 100_000_000);
        let src = if step == 1 { &s.axiom } else { &*a };
        s.prepared
            .derive(
                src,
                &opts,
                &mut NativeHost { rng: &mut rng },
                Output::Keep(b),
            )
            .expect("derive");
        produced += b.len() as u64;
        std::mem::swap(a, b);
    }
    produced
}

fn bench_classic(c: &mut Criterion) {
    let depth = 12;
    let s = setup("X", &["X -> F[+X]F[-X]+X", "F -> FF"], &[], "");
    let peer = lindenmayer::LSystem::new(String::from("X"), &[('X', "F[+X]F[-X]+X"), ('F', "FF")]);
    // The same string on every side, module for module, checked once before timing.
    let (mut a, mut b) = (ModuleString::new(), ModuleString::new());
    derive(&s, depth, &mut a, &mut b);
    let modules = a.len();
    let peer_string = peer.string(depth as usize);
    assert!(
        a.to_text(&s.symbols, "") == peer_string,
        "PGE and the lindenmayer crate derive the same string"
    );
    let mut kept = String::new();
    kept.extend(peer.builder(depth as usize));
    assert!(kept == peer_string, "the crate's builder makes its string");
    drop(peer_string);
    let mut g = c.benchmark_group("classic_1_24d");
    g.throughput(Throughput::Elements(modules as u64));
    g.sample_size(10);
    // Fresh buffers on both sides: each iteration allocates from nothing, and its string is
    // returned (and dropped) inside the timing.
    g.bench_function("pge, fresh buffers", |bench| {
        bench.iter(|| {
            let (mut a, mut b) = (ModuleString::new(), ModuleString::new());
            derive(&s, depth, &mut a, &mut b);
            a
        });
    });
    g.bench_function("lindenmayer string, fresh buffers", |bench| {
        bench.iter(|| peer.string(depth as usize));
    });
    // Buffers kept from the previous iteration on both sides.
    g.bench_function("pge, kept buffers", |bench| {
        bench.iter(|| {
            derive(&s, depth, &mut a, &mut b);
            a.len()
        });
    });
    g.bench_function("lindenmayer builder, kept buffer", |bench| {
        bench.iter(|| {
            kept.clear();
            kept.extend(peer.builder(depth as usize));
            kept.len()
        });
    });
    g.finish();
}

/// A module of the hand-written parametric loop.
#[derive(Clone, Copy)]
struct Module {
    sym: u8,
    a: f64,
    b: f64,
}

impl Module {
    fn new(sym: u8, a: f64, b: f64) -> Module {
        Module { sym, a, b }
    }
}

/// One step of ABOP fig. 2.6 written by hand for these three rules (no rule matching, no
/// expression evaluation).
fn honda_step(src: &[Module], out: &mut Vec<Module>) {
    let (r1, r2, a0, a2, d, wr) = (0.9, 0.7, 45.0, 45.0, 137.5, 0.707);
    out.clear();
    for m in src {
        let (l, w) = (m.a, m.b);
        let m0 = |sym| Module::new(sym, 0.0, 0.0);
        let m1 = |sym, a| Module::new(sym, a, 0.0);
        match m.sym {
            b'A' => out.extend_from_slice(&[
                m1(b'!', w),
                m1(b'F', l),
                m0(b'['),
                m1(b'&', a0),
                Module::new(b'B', l * r2, w * wr),
                m0(b']'),
                m1(b'/', d),
                Module::new(b'A', l * r1, w * wr),
            ]),
            b'B' => out.extend_from_slice(&[
                m1(b'!', w),
                m1(b'F', l),
                m0(b'['),
                m1(b'-', a2),
                m0(b'$'),
                Module::new(b'C', l * r2, w * wr),
                m0(b']'),
                Module::new(b'C', l * r1, w * wr),
            ]),
            b'C' => out.extend_from_slice(&[
                m1(b'!', w),
                m1(b'F', l),
                m0(b'['),
                m1(b'+', a2),
                m0(b'$'),
                Module::new(b'B', l * r2, w * wr),
                m0(b']'),
                Module::new(b'B', l * r1, w * wr),
            ]),
            _ => out.push(*m),
        }
    }
}

fn bench_parametric(c: &mut Criterion) {
    let globals = [
        ("r1", 0.9),
        ("r2", 0.7),
        ("a0", 45.0),
        ("a2", 45.0),
        ("d", 137.5),
        ("wr", 0.707),
    ];
    let rules = [
        "A(l,w) -> !(w)F(l)[&(a0)B(l*r2,w*wr)]/(d)A(l*r1,w*wr)",
        "B(l,w) -> !(w)F(l)[-(a2)$C(l*r2,w*wr)]C(l*r1,w*wr)",
        "C(l,w) -> !(w)F(l)[+(a2)$B(l*r2,w*wr)]B(l*r1,w*wr)",
    ];
    let s = setup("A(1,10)", &rules, &globals, "");
    let (mut a, mut b) = (ModuleString::new(), ModuleString::new());
    let steps = 16;
    let produced = derive(&s, steps, &mut a, &mut b);
    let hand = |x: &mut Vec<Module>, y: &mut Vec<Module>| {
        x.clear();
        x.push(Module::new(b'A', 1.0, 10.0));
        let mut produced = 0;
        for _ in 0..steps {
            honda_step(x, y);
            produced += y.len() as u64;
            std::mem::swap(x, y);
        }
        produced
    };
    let (mut x, mut y) = (Vec::new(), Vec::new());
    assert_eq!(hand(&mut x, &mut y), produced);
    let sum: f64 = (0..a.len()).flat_map(|i| a.params(i).iter()).sum();
    let hand_sum: f64 = x
        .iter()
        .map(|m| match m.sym {
            b'[' | b']' | b'$' => 0.0,
            b'A' | b'B' | b'C' => m.a + m.b,
            _ => m.a,
        })
        .sum();
    assert!(
        (sum - hand_sum).abs() < 1e-6 * sum.abs(),
        "{sum} {hand_sum}"
    );
    eprintln!(
        "parametric: {} modules after {steps} steps, {produced} produced, string {} bytes",
        a.len(),
        a.memory_bytes()
    );
    let mut g = c.benchmark_group("parametric_2_6");
    g.throughput(Throughput::Elements(produced));
    g.sample_size(10);
    g.bench_function("pge", |bench| {
        bench.iter(|| derive(&s, steps, &mut a, &mut b));
    });
    g.bench_function("hand-written Vec<Module>", |bench| {
        bench.iter(|| hand(&mut x, &mut y));
    });
    g.finish();
}

/// Whether the left context of module `i` (skipping branches, climbing out of enclosing
/// ones) is `want`.
fn left_is(src: &[u8], matches: &[u32], i: usize, want: u8) -> bool {
    let mut j = i;
    loop {
        if j == 0 {
            return false;
        }
        j -= 1;
        match src[j] {
            b']' => match matches[j] {
                u32::MAX => return false,
                open => j = open as usize,
            },
            b'[' => {}
            s => return s == want,
        }
    }
}

/// Whether the right context of module `i` (along the axis, skipping branches) is `want`.
fn right_is(src: &[u8], matches: &[u32], i: usize, want: u8) -> bool {
    let mut j = i + 1;
    while j < src.len() {
        match src[j] {
            b'[' => match matches[j] {
                u32::MAX => return false,
                close => j = close as usize + 1,
            },
            s => return s == want,
        }
    }
    false
}

/// One step of the signal system (`b < a -> b`, `b -> a`, `a > b -> c`) written by hand.
fn signal_step(src: &[u8], matches: &mut Vec<u32>, stack: &mut Vec<u32>, out: &mut Vec<u8>) {
    matches.clear();
    matches.resize(src.len(), u32::MAX);
    stack.clear();
    for (i, &s) in src.iter().enumerate() {
        if s == b'[' {
            stack.push(i as u32);
        } else if s == b']'
            && let Some(open) = stack.pop()
        {
            matches[i] = open;
            matches[open as usize] = i as u32;
        }
    }
    out.clear();
    for (i, &s) in src.iter().enumerate() {
        out.push(match s {
            b'a' if left_is(src, matches, i, b'b') => b'b',
            b'a' if right_is(src, matches, i, b'b') => b'c',
            b'b' => b'a',
            s => s,
        });
    }
}

fn bench_context(c: &mut Criterion) {
    // Signal propagation along a 100 000-module string with branches every 10 modules.
    let mut axiom = String::from("b");
    for i in 1..100_000 {
        axiom.push(if i % 10 == 0 {
            '['
        } else if i % 10 == 5 {
            ']'
        } else if i % 1000 == 7 {
            'b'
        } else {
            'a'
        });
    }
    let s = setup(&axiom, &["b < a -> b", "b -> a", "a > b -> c"], &[], "+ -");
    let (mut a, mut b) = (ModuleString::new(), ModuleString::new());
    let produced = derive(&s, 1, &mut a, &mut b);
    let src = axiom.as_bytes().to_vec();
    let (mut matches, mut stack, mut out) = (Vec::new(), Vec::new(), Vec::new());
    signal_step(&src, &mut matches, &mut stack, &mut out);
    let pge_text = a.to_text(&s.symbols, "");
    assert_eq!(
        pge_text.as_bytes(),
        out.as_slice(),
        "same string as by hand"
    );
    let mut g = c.benchmark_group("context_signal");
    g.throughput(Throughput::Elements(produced));
    g.bench_function("pge", |bench| {
        bench.iter(|| derive(&s, 1, &mut a, &mut b));
    });
    g.bench_function("hand-written loop", |bench| {
        bench.iter(|| signal_step(&src, &mut matches, &mut stack, &mut out));
    });
    g.finish();
}

fn bench_lua(c: &mut Criterion) {
    use pge_engine::{Engine, Location, SessionOptions};
    let engine = Engine::builder()
        .plugin(pge_lsystem::LSystemPlugin)
        .build()
        .expect("engine");
    let session = engine.session(SessionOptions::default()).expect("session");
    let ctx = session.context();
    let location = Location::new("bench", 0);
    let mut g = c.benchmark_group("lua_rules");
    g.sample_size(10);
    // (name, script, modules produced, modules in the final string)
    let cases = [
        (
            "RRule A -> {B{}, A{}, B{}} on 100k",
            r#"local l = pge.LSystem("bench")
            l:axiom(string.rep("A", 100000))
            l:RRule("A", function(a) return { B{}, A{}, B{} } end)
            l:iterations(1)
            return l"#,
            300_000,
            300_000,
        ),
        (
            "RRule A(x) -> A(x+1) on 100k",
            r#"local l = pge.LSystem("bench")
            l:axiom(string.rep("A(1)", 100000))
            l:RRule("A", function(a) return A{a[1] + 1} end)
            l:iterations(1)
            return l"#,
            100_000,
            100_000,
        ),
        // The rule calls alone: the axiom is 100 times shorter, so parsing it and setting
        // up the run are about 1% of the work.
        (
            "RRule A(x) -> A(x+1), 1k modules x 100 steps",
            r#"local l = pge.LSystem("bench")
            l:axiom(string.rep("A(1)", 1000))
            l:RRule("A", function(a) return A{a[1] + 1} end)
            l:iterations(100)
            return l"#,
            100_000,
            1_000,
        ),
        // The floor: a rule that does not apply (the module is copied).
        (
            "RRule A(x) -> nil, 1k modules x 100 steps",
            r#"local l = pge.LSystem("bench")
            l:axiom(string.rep("A(1)", 1000))
            l:RRule("A", function(a) return nil end)
            l:iterations(100)
            return l"#,
            100_000,
            1_000,
        ),
    ];
    for (name, code, produced, len) in cases {
        let value = session.eval_value(code).expect("script");
        g.throughput(Throughput::Elements(produced));
        g.bench_function(name, |bench| {
            bench.iter(|| {
                let d = pge_lsystem::derive_value(session.lua(), &value, &ctx, &location)
                    .expect("derives");
                assert_eq!(d.len() as u64, len);
            });
        });
    }
    g.finish();
}

fn bench_memory(_: &mut Criterion) {
    // One million modules with two numeric parameters.
    let mut string = ModuleString::new();
    let mut symbols = SymbolTable::new();
    let a = symbols.intern("A");
    for i in 0..1_000_000 {
        string.push(a, &[f64::from(i), 0.5]);
    }
    eprintln!(
        "memory: 1 000 000 modules with 2 parameters = {:.1} MiB (two buffers during a step: {:.1} MiB)",
        string.memory_bytes() as f64 / 1048576.0,
        2.0 * string.memory_bytes() as f64 / 1048576.0
    );
}

criterion_group!(
    benches,
    bench_classic,
    bench_parametric,
    bench_context,
    bench_lua,
    bench_memory
);
criterion_main!(benches);
