//! Derivation speed: the performance targets of the L-system engine.
//!
//! Each benchmark reports modules produced per second (criterion's "elements").
//!
//! Measured on the 2-core development machine while other builds ran (load average 2.7-5),
//! so these are lower bounds (targets of the L-system issue in brackets):
//! - `classic_plain` (`X -> F[+X]F[-X]+X`, `F -> FF`, 12 steps): 590-890 M modules/s (100 M)
//! - `classic_parametric` (ABOP fig. 2.6, 16 steps): 63-89 M modules/s (30 M)
//! - `context` (signal propagation on 100 000 modules with branches): 44-89 M modules/s (10 M)
//! - `lua_rules` (`RRule("A", ...)` returning three symbols, 100 000 calls, including the
//!   set-up of the instance and the axiom): 2.6-3.1 M modules/s (3 M); about a tenth of it is
//!   the session's instruction-count hook
//! - memory: 10^6 modules with two parameters take 24 MiB, 48 MiB during a step (64 MiB)

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pge_lsystem::{ModuleString, NativeHost, StepOptions, SymbolTable, System};
use rand_mt::Mt;

struct Setup {
    system: System,
    axiom: ModuleString,
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
    system.prepare(&symbols).expect("prepare");
    let axiom = system
        .parse_string(axiom, &mut symbols, &mut || 0.0)
        .expect("axiom");
    Setup { system, axiom }
}

/// Derives `steps` steps; returns the final string and the modules produced over all steps.
fn derive(s: &Setup, steps: u32, a: &mut ModuleString, b: &mut ModuleString) -> u64 {
    let mut rng = Mt::new(1);
    a.clear();
    a.append(&s.axiom);
    let mut produced = 0u64;
    for step in 1..=steps {
        let opts = StepOptions {
            step,
            max_modules: 100_000_000,
            stream: false,
        };
        s.system
            .step(a, b, &mut NativeHost { rng: &mut rng }, &opts)
            .expect("derive");
        produced += b.len() as u64;
        std::mem::swap(a, b);
    }
    produced
}

fn bench_classic(c: &mut Criterion) {
    let s = setup("X", &["X -> F[+X]F[-X]+X", "F -> FF"], &[], "");
    let (mut a, mut b) = (ModuleString::new(), ModuleString::new());
    let produced = derive(&s, 12, &mut a, &mut b);
    eprintln!(
        "classic: {} modules after 12 steps, {produced} produced",
        a.len()
    );
    let mut g = c.benchmark_group("classic_plain");
    g.throughput(Throughput::Elements(produced));
    g.sample_size(20);
    g.bench_function("X->F[+X]F[-X]+X,F->FF x12", |bench| {
        bench.iter(|| derive(&s, 12, &mut a, &mut b));
    });
    g.finish();
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
    eprintln!(
        "parametric: {} modules after {steps} steps, {produced} produced, string {} bytes",
        a.len(),
        a.memory_bytes()
    );
    let mut g = c.benchmark_group("classic_parametric");
    g.throughput(Throughput::Elements(produced));
    g.sample_size(10);
    g.bench_function("ABOP fig 2.6 x16", |bench| {
        bench.iter(|| derive(&s, steps, &mut a, &mut b));
    });
    g.finish();
}

fn bench_context(c: &mut Criterion) {
    // Signal propagation along a 100 000-module string with branches every 10 modules.
    let mut axiom = String::from("b");
    for i in 1..100_000 {
        axiom.push(if i % 10 == 0 {
            '['
        } else if i % 10 == 5 {
            ']'
        } else {
            'a'
        });
    }
    let s = setup(&axiom, &["b < a -> b", "b -> a", "a > b -> c"], &[], "+ -");
    let (mut a, mut b) = (ModuleString::new(), ModuleString::new());
    let produced = derive(&s, 1, &mut a, &mut b);
    let mut g = c.benchmark_group("context");
    g.throughput(Throughput::Elements(produced));
    g.bench_function("signal 100k", |bench| {
        bench.iter(|| derive(&s, 1, &mut a, &mut b));
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
    let value = session
        .eval_value(
            r#"local l = pge.LSystem("bench")
            l:axiom(string.rep("A", 100000))
            l:RRule("A", function(a) return { B{}, A{}, B{} } end)
            l:iterations(1)
            return l"#,
        )
        .expect("script");
    let ctx = session.context();
    let location = Location::new("bench", 0);
    let mut g = c.benchmark_group("lua_rules");
    g.throughput(Throughput::Elements(300_000));
    g.sample_size(10);
    g.bench_function("RRule A -> {B{}, A{}, B{}} on 100k", |bench| {
        bench.iter(|| {
            let d =
                pge_lsystem::derive_value(session.lua(), &value, &ctx, &location).expect("derives");
            assert_eq!(d.len(), 300_000);
        });
    });
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
