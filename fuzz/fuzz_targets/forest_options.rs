//! `pge.Forest` with random options: the forest's size, seed and tile, its terrain and a few
//! layers of random options (numbers of any size and sign, wrong types, density functions
//! returning odd values), laid out with `forest:instances()` and `forest:tiles()`, then run
//! as the script's value. Script errors are expected; a panic, an abort or a hang is a
//! finding.
#![no_main]

use std::cell::OnceCell;
use std::fmt::Write as _;
use std::time::Duration;

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use pge_engine::{Engine, SessionOptions};

/// A Lua value for an option.
#[derive(Arbitrary, Clone, Debug)]
enum Val {
    Num(f64),
    Int(i32),
    Small(u8),
    Bool(bool),
    Str(u8),
    Pair(f64, f64),
    Nil,
    Function(u8),
}

impl Val {
    fn lua(&self) -> String {
        match self {
            Val::Num(x) if x.is_nan() => "0/0".into(),
            Val::Num(x) if x.is_infinite() => if *x > 0.0 { "1/0" } else { "-1/0" }.into(),
            Val::Num(x) => format!("{x:e}"),
            Val::Int(i) => i.to_string(),
            Val::Small(n) => (f64::from(*n) / 8.0).to_string(),
            Val::Bool(b) => b.to_string(),
            Val::Str(k) => ["\"poisson\"", "\"jittered\"", "\"unique\"", "\"x.png\"", "\"\""]
                [*k as usize % 5]
                .into(),
            Val::Pair(a, b) => format!("{{{}, {}}}", Val::Num(*a).lua(), Val::Num(*b).lua()),
            Val::Nil => "nil".into(),
            Val::Function(k) => [
                "function(x, z) return 0.5 end",
                "function(x, z) return true end",
                "function(x, z) error({}) end",
                "function(x, z) return x / z end",
                "function(x, z) return F:height(x, z) end",
                "function(x, z) F:scatter{species = S, minDistance = 1} return 1 end",
            ][*k as usize % 6]
                .into(),
        }
    }
}

const FOREST_KEYS: &[&str] = &["size", "seed", "tile"];
const TERRAIN_KEYS: &[&str] = &[
    "height",
    "scale",
    "octaves",
    "lacunarity",
    "persistence",
    "resolution",
    "image",
];
const SCATTER_KEYS: &[&str] = &[
    "minDistance",
    "method",
    "jitter",
    "density",
    "slope",
    "altitude",
    "variants",
    "scale",
    "params",
];

#[derive(Arbitrary, Debug)]
struct Forest {
    forest: Vec<(u8, Val)>,
    terrain: Option<Vec<(u8, Val)>>,
    layers: Vec<Vec<(u8, Val)>>,
    select: Option<(u8, u8)>,
}

fn table(keys: &[&str], options: &[(u8, Val)]) -> String {
    let mut s = String::from("{");
    for (k, v) in options.iter().take(12) {
        let _ = write!(s, "{} = {}, ", keys[*k as usize % keys.len()], v.lua());
    }
    s.push('}');
    s
}

fn script(f: &Forest) -> String {
    let mut s = String::from(
        "S = function() return pge.SpaceColonization{envelope = pge.shape.sphere{center = \
         {0, 0.5, 0}, radius = 0.3}, points = 5, roots = {{0, 0, 0}}} end\n",
    );
    // A size that keeps the layout small unless the fuzzer sets one.
    let mut forest = vec![(0u8, Val::Pair(30.0, 30.0))];
    forest.extend(f.forest.iter().cloned());
    let _ = writeln!(s, "F = pge.Forest{}", table(FOREST_KEYS, &forest));
    if let Some(t) = &f.terrain {
        let _ = writeln!(s, "pcall(function() F:terrain{} end)", table(TERRAIN_KEYS, t));
    }
    for layer in f.layers.iter().take(3) {
        let options = table(SCATTER_KEYS, layer);
        let options = options.replacen('{', "{species = S, ", 1);
        let _ = writeln!(s, "pcall(function() F:scatter{options} end)");
    }
    if let Some((i, j)) = f.select {
        let _ = writeln!(s, "pcall(function() F:selectTile({i}, {j}) end)");
    }
    s.push_str("pcall(function() return F:tiles() end)\n");
    s.push_str("pcall(function() return F:instances() end)\n");
    s.push_str("return F\n");
    s
}

thread_local! {
    static ENGINE: OnceCell<(Engine, tempfile::TempDir)> = const { OnceCell::new() };
}

fuzz_target!(|forest: Forest| {
    let source = script(&forest);
    ENGINE.with(|cell| {
        let (engine, dir) = cell.get_or_init(|| {
            let engine = pge::default_engine()
                .memory_limit_mib(256)
                .time_limit(Some(Duration::from_secs(5)))
                .instruction_limit(Some(20_000_000))
                .build()
                .expect("the engine builds");
            let dir = tempfile::tempdir().expect("a temporary folder");
            (engine, dir)
        });
        let path = dir.path().join("forest.lua");
        std::fs::write(&path, &source).expect("write the script");
        let Ok(session) = engine.session(SessionOptions::default()) else {
            return;
        };
        let _ = session.generate(&path, &mut |_, _| {});
    });
});
