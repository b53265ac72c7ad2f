//! Properties of the Lua API: any option table given to any constructor either
//! builds or fails with a located error (`FILE:LINE: message`), never a panic.

use pge::pge_engine::{Engine, SessionOptions};
use proptest::prelude::*;

/// Constructors taking an option table, as a Lua expression with `OPTS` for the table.
const CONSTRUCTORS: &[&str] = &[
    "pge.turtle(OPTS)",
    "pge.SpaceColonization(OPTS)",
    "pge.Growth(OPTS)",
    "pge.Conifer(OPTS)",
    "pge.Metaballs(OPTS)",
    "pge.MarchingCubes(pge.Metaballs{}, OPTS)",
    "pge.Extruder(OPTS)",
    "pge.Lines(OPTS)",
    "pge.tree(OPTS)",
    "pge.shape.sphere(OPTS)",
    "pge.shape.ellipsoid(OPTS)",
    "pge.shape.box(OPTS)",
    "pge.shape.capsule(OPTS)",
    "pge.shape.cone(OPTS)",
    "pge.shape.cylinder(OPTS)",
    "pge.shape.revolve(OPTS)",
    "pge.shape.union(OPTS)",
    "pge.shape.difference(OPTS)",
    "pge.shape.mesh(OPTS)",
    "pge.lod.budget(OPTS)",
    "pge.Forest(OPTS)",
];

/// Option names the constructors read, and a few they do not.
const KEYS: &[&str] = &[
    "angle",
    "width",
    "step",
    "radius",
    "center",
    "radii",
    "min",
    "max",
    "a",
    "b",
    "base",
    "apex",
    "profile",
    "envelope",
    "points",
    "influence",
    "kill",
    "mode",
    "thickness",
    "iterations",
    "resolution",
    "iso",
    "bounds",
    "maxCells",
    "color",
    "material",
    "mesh",
    "leaves",
    "sides",
    "tropism",
    "elasticity",
    "seed",
    "size",
    "species",
    "layout",
    "path",
    "model",
    "scale",
    "girth",
    "smoothing",
    "mergeStraight",
    "texture",
    "colors",
    "leafSize",
    "count",
    "tip",
    "steps",
    "lod",
    "years",
    "perWhorl",
    "crown",
    "orders",
    "segment",
    "unknownOption",
];

fn value() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        Just("nil".to_string()),
        Just("true".to_string()),
        Just("false".to_string()),
        any::<i64>().prop_map(|i| format!("math.tointeger({i})")),
        (-1e6f64..1e6).prop_map(|v| format!("{v:e}")),
        Just("0".to_string()),
        Just("-1".to_string()),
        Just("(0/0)".to_string()),
        Just("math.huge".to_string()),
        Just("\"#ff8800\"".to_string()),
        Just("\"fill\"".to_string()),
        Just("\"x\"".to_string()),
        Just("pge.vec(1, 2, 3)".to_string()),
        Just("{1, 2, 3}".to_string()),
        Just("pge.shape.sphere{radius = 1}".to_string()),
        Just("function() return 1 end".to_string()),
        Just("function() error('boom') end".to_string()),
    ];
    leaf.prop_recursive(2, 12, 4, |inner| {
        prop::collection::vec((prop::sample::select(KEYS), inner), 0..4).prop_map(|fields| {
            let body: Vec<String> = fields.iter().map(|(k, v)| format!("{k} = {v}")).collect();
            format!("{{{}}}", body.join(", "))
        })
    })
}

fn options() -> impl Strategy<Value = String> {
    prop::collection::vec((prop::sample::select(KEYS), value()), 0..6).prop_map(|fields| {
        let body: Vec<String> = fields.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        format!("{{{}}}", body.join(", "))
    })
}

thread_local! {
    static ENGINE: Engine = pge::default_engine()
        .memory_limit_mib(256)
        .instruction_limit(Some(5_000_000))
        .build()
        .expect("engine");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn any_option_table_builds_or_fails_with_a_located_error(
        constructor in prop::sample::select(CONSTRUCTORS),
        opts in options(),
    ) {
        let code = format!("local x = {}\nreturn x", constructor.replace("OPTS", &opts));
        let result = ENGINE.with(|engine| {
            let session = engine.session(SessionOptions::default()).expect("session");
            session.eval::<mlua::Value>(&code).map(|_| ()).map_err(|e| e.to_string())
        });
        if let Err(message) = result {
            prop_assert!(
                message.starts_with("eval:1: "),
                "not located at the constructor's line:\n{}\n  gave: {}", code, message
            );
            prop_assert!(!message.contains('\n'), "more than one line: {}", message);
        }
    }
}
