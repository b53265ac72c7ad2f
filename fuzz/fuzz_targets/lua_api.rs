//! The Lua API driven by random calls: every function reachable from `pge` (constructors,
//! `pge.shape.*`, `pge.noise.*`, ...) called with random argument types, then random
//! methods of what they returned, random fields set on them, and the last value run as an
//! algorithm. Script errors are expected; a panic, an abort or a hang is a finding.
#![no_main]

use std::cell::OnceCell;
use std::fmt::Write as _;
use std::time::Duration;

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use pge_engine::{Engine, SessionOptions};

/// Method names of PGE's userdata (and a few that exist nowhere).
const METHODS: &[&str] = &[
    "IRule",
    "RRule",
    "add",
    "advance",
    "afterStep",
    "algorithm",
    "applyTo",
    "axiom",
    "beforeStep",
    "bounds",
    "calc",
    "children",
    "choice",
    "clear",
    "clearShape",
    "clone",
    "contains",
    "copy",
    "count",
    "createInstance",
    "cross",
    "declare",
    "depth",
    "distance",
    "dot",
    "extrude",
    "fill",
    "finish",
    "get",
    "getHex",
    "getMatrix",
    "getNode",
    "getParticle",
    "getPathMatrix",
    "getShapeMatrix",
    "gradient",
    "grow",
    "heading",
    "height",
    "ignore",
    "inside",
    "instanceCount",
    "instances",
    "int",
    "interpretEveryStep",
    "inverse",
    "iterations",
    "kind",
    "leafCount",
    "left",
    "length",
    "lerp",
    "maxModules",
    "mesh",
    "meshCount",
    "model",
    "name",
    "nodes",
    "normal",
    "normalize",
    "order",
    "parent",
    "pngBytes",
    "pointCount",
    "polygon",
    "pop",
    "position",
    "push",
    "radius",
    "range",
    "reset",
    "rollToHorizontal",
    "rotate",
    "rule",
    "save",
    "scale",
    "scatter",
    "selectTile",
    "set",
    "setColor",
    "setEnvironment",
    "setMatrix",
    "skeleton",
    "start",
    "terrain",
    "texture",
    "tiles",
    "tips",
    "transformPoint",
    "transformVector",
    "translate",
    "triangleCount",
    "turnAround",
    "uniform",
    "unpack",
    "up",
    "update",
    "vertexCount",
    "width",
    "x",
    "y",
    "z",
    "nope",
];

/// Option and field names the plugins read.
const KEYS: &[&str] = &[
    "altitude",
    "angle",
    "at",
    "atlas",
    "axiom",
    "balls",
    "bounds",
    "caps",
    "center",
    "color",
    "colors",
    "count",
    "directedness",
    "direction",
    "distance",
    "elasticity",
    "envelope",
    "exponent",
    "feed",
    "field",
    "girth",
    "height",
    "image",
    "influence",
    "iso",
    "iterations",
    "jitter",
    "kill",
    "lacunarity",
    "layout",
    "leafSize",
    "leaves",
    "length",
    "lod",
    "material",
    "maxBranches",
    "maxCells",
    "maxDepth",
    "maxIterations",
    "maxModules",
    "mergeStraight",
    "mesh",
    "method",
    "minDistance",
    "mode",
    "model",
    "name",
    "nodes",
    "octaves",
    "path",
    "perTip",
    "persistence",
    "points",
    "position",
    "profile",
    "radii",
    "radius",
    "ratio",
    "resolution",
    "root",
    "roots",
    "rules",
    "scale",
    "sectors",
    "seed",
    "shape",
    "sides",
    "size",
    "slope",
    "smooth",
    "smoothing",
    "species",
    "spread",
    "start",
    "step",
    "steps",
    "strength",
    "texture",
    "thickness",
    "tile",
    "tip",
    "tipRadius",
    "tropism",
    "trunk",
    "turtle",
    "value",
    "variants",
    "width",
    "widthFactor",
    "x",
    "y",
    "z",
];

/// Strings worth trying: rules, colours, shapes, file names.
const STRINGS: &[&str] = &[
    "",
    "F",
    "A",
    "F -> F[+F]F[-F]F",
    "A(l) : l > 1 -> F(l) [ +(30) A(l/2) ] A(l/2)",
    "A(x) -> A(x+rand())",
    "X -> F[+X][-X]FX",
    "#ff8800",
    "red",
    "#12",
    "sphere",
    "box",
    "x.png",
    "out/x.png",
    "../x.png",
    "notes.txt",
    "mesh.obj",
    "missing.glb",
    "FFF+FF-[F]",
    "linear",
    "cubic",
    "union",
    "nan",
    "1e309",
    "examples/spiral.lua",
    "a.b.c",
];

#[derive(Arbitrary, Debug)]
enum Key {
    Name(u8),
    Index(u8),
}

#[derive(Arbitrary, Debug)]
enum Scalar {
    Nil,
    Bool(bool),
    Int(i64),
    Small(i8),
    Num(f64),
    Str(u8),
    Raw(String),
    Obj(u8),
    Vec3(i8, i8, i8),
    Fn(FnKind),
}

#[derive(Arbitrary, Debug)]
enum FnKind {
    Constant(i8),
    Error,
    Identity,
    Table,
    Collect,
}

#[derive(Arbitrary, Debug)]
enum Arg {
    Scalar(Scalar),
    Table(Vec<(Key, Scalar)>),
    Nested(Vec<(Key, Vec<(Key, Scalar)>)>),
}

#[derive(Arbitrary, Debug)]
enum Op {
    Call { f: u8, args: Vec<Arg> },
    Method { obj: u8, m: u8, args: Vec<Arg> },
    SetField { obj: u8, key: Key, value: Arg },
    GetField { obj: u8, key: Key },
    Arith { a: u8, b: u8, op: u8 },
}

#[derive(Arbitrary, Debug)]
struct Program {
    ops: Vec<Op>,
    result: u8,
}

fn quote(s: &str) -> String {
    let mut out = String::from("\"");
    for b in s.bytes().take(64) {
        if b.is_ascii_alphanumeric() || b == b' ' {
            out.push(b as char);
        } else {
            let _ = write!(out, "\\{b}");
        }
    }
    out.push('"');
    out
}

fn key(k: &Key) -> String {
    match k {
        Key::Name(i) => format!("[{}]", quote(KEYS[*i as usize % KEYS.len()])),
        Key::Index(i) => format!("[{}]", i % 8 + 1),
    }
}

fn scalar(s: &Scalar) -> String {
    match s {
        Scalar::Nil => "nil".into(),
        Scalar::Bool(b) => b.to_string(),
        Scalar::Int(i) => format!("math.tointeger({i})"),
        Scalar::Small(i) => i.to_string(),
        Scalar::Num(n) if n.is_nan() => "(0/0)".into(),
        Scalar::Num(n) if n.is_infinite() => {
            if *n > 0.0 { "math.huge" } else { "-math.huge" }.into()
        }
        Scalar::Num(n) => format!("{n:e}"),
        Scalar::Str(i) => quote(STRINGS[*i as usize % STRINGS.len()]),
        Scalar::Raw(s) => quote(s),
        Scalar::Obj(i) => format!("O[{}]", i % 16 + 1),
        Scalar::Vec3(x, y, z) => format!("pge.vec({x}, {y}, {z})"),
        Scalar::Fn(FnKind::Constant(c)) => format!("function() return {c} end"),
        Scalar::Fn(FnKind::Error) => "function() error(\"fuzz\") end".into(),
        Scalar::Fn(FnKind::Identity) => "function(...) return ... end".into(),
        Scalar::Fn(FnKind::Table) => "function() return {} end".into(),
        Scalar::Fn(FnKind::Collect) => "function() collectgarbage() return 1 end".into(),
    }
}

fn table(fields: &[(Key, Scalar)]) -> String {
    let mut out = String::from("{");
    for (k, v) in fields.iter().take(8) {
        let _ = write!(out, "{} = {}, ", key(k), scalar(v));
    }
    out.push('}');
    out
}

fn arg(a: &Arg) -> String {
    match a {
        Arg::Scalar(s) => scalar(s),
        Arg::Table(fields) => table(fields),
        Arg::Nested(fields) => {
            let mut out = String::from("{");
            for (k, v) in fields.iter().take(6) {
                let _ = write!(out, "{} = {}, ", key(k), table(v));
            }
            out.push('}');
            out
        }
    }
}

fn args(list: &[Arg]) -> String {
    list.iter().take(6).map(arg).collect::<Vec<_>>().join(", ")
}

const PRELUDE: &str = r#"
local F = {}
local function walk(t, depth)
  local keys = {}
  for k in pairs(t) do if type(k) == "string" then keys[#keys + 1] = k end end
  table.sort(keys)
  for _, k in ipairs(keys) do
    local v = t[k]
    if type(v) == "function" then
      F[#F + 1] = v
    elseif type(v) == "table" and depth < 3 then
      local mt = getmetatable(v)
      if type(mt) == "table" and mt.__call then F[#F + 1] = v end
      walk(v, depth + 1)
    end
  end
end
walk(pge, 0)
O = {}
local function keep(ok, v) if ok and v ~= nil then O[#O + 1] = v end end
"#;

fn script(p: &Program) -> String {
    let mut s = String::from(PRELUDE);
    for op in p.ops.iter().take(24) {
        match op {
            Op::Call { f, args: a } => {
                let _ = writeln!(s, "keep(pcall(F[{} % #F + 1], {}))", f, args(a));
            }
            Op::Method { obj, m, args: a } => {
                let name = METHODS[*m as usize % METHODS.len()];
                let _ = writeln!(
                    s,
                    "keep(pcall(function() local o = O[{}]; return o:{name}({}) end))",
                    obj % 16 + 1,
                    args(a)
                );
            }
            Op::SetField { obj, key: k, value } => {
                let _ = writeln!(
                    s,
                    "pcall(function() O[{}]{} = {} end)",
                    obj % 16 + 1,
                    key(k),
                    arg(value)
                );
            }
            Op::GetField { obj, key: k } => {
                let _ = writeln!(
                    s,
                    "keep(pcall(function() return O[{}]{} end))",
                    obj % 16 + 1,
                    key(k)
                );
            }
            Op::Arith { a, b, op } => {
                let sym = ["+", "-", "*", "/", "..", "==", "<", "#"][*op as usize % 8];
                let expr = if sym == "#" {
                    format!("#O[{}]", a % 16 + 1)
                } else {
                    format!("O[{}] {sym} O[{}]", a % 16 + 1, b % 16 + 1)
                };
                let _ = writeln!(s, "keep(pcall(function() return {expr} end))");
            }
        }
    }
    let _ = writeln!(s, "return O[{}]", p.result % 16 + 1);
    s
}

thread_local! {
    static ENGINE: OnceCell<(Engine, tempfile::TempDir)> = const { OnceCell::new() };
}

fuzz_target!(|program: Program| {
    let source = script(&program);
    ENGINE.with(|cell| {
        let (engine, dir) = cell.get_or_init(|| {
            let engine = pge::default_engine()
                .memory_limit_mib(96)
                .time_limit(Some(Duration::from_secs(3)))
                .instruction_limit(Some(20_000_000))
                .max_modules(20_000)
                .build()
                .expect("the engine builds");
            let dir = tempfile::tempdir().expect("a temporary folder");
            // Scripts write relative to the working directory or their own folder: keep both
            // in the temporary folder.
            std::env::set_current_dir(dir.path()).expect("cd");
            (engine, dir)
        });
        let path = dir.path().join("fuzz.lua");
        std::fs::write(&path, &source).expect("write the script");
        let Ok(session) = engine.session(SessionOptions::default()) else {
            return;
        };
        let _ = session.generate(&path, &mut |_, _| {});
    });
});
