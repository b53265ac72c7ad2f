//! End-to-end tests of L-systems: `pge derive` and `pge run` on the scripts of
//! `scripts/lsystems/`, and the errors bad L-system scripts get.

mod common;

use common::pge;
use std::path::Path;
use std::process::Output;

fn stdout_of(o: &Output) -> String {
    assert!(
        o.status.success(),
        "pge failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout.clone()).expect("utf-8")
}

fn derive(script: &str, extra: &[&str]) -> String {
    let mut args = vec!["derive", script];
    args.extend_from_slice(extra);
    stdout_of(&pge(&args)).trim_end().to_string()
}

const L: &str = "scripts/lsystems";

#[test]
fn derive_text_of_fig_1_24a() {
    assert_eq!(
        derive(&format!("{L}/plants.lua"), &["--steps", "1"]),
        "F [ + F ] F [ - F ] F"
    );
}

#[test]
fn derive_count_of_fig_1_24_at_the_books_depths() {
    // Counted by hand from the productions: a) 5^5 F and 6 * (5^5 - 1) / 4 others.
    assert_eq!(
        derive(&format!("{L}/plants.lua"), &["--format", "count"]),
        "7811"
    );
    // d) n = 7: X -> F[+X]F[-X]+X, F -> FF.
    let d = derive(
        &format!("{L}/plants.lua"),
        &["--set", "variant=d", "--format", "count"],
    );
    let (mut x, mut f, mut other) = (1u64, 0u64, 0u64);
    for _ in 0..7 {
        (x, f, other) = (3 * x, 2 * f + 2 * x, other + 7 * x);
    }
    assert_eq!(d, (x + f + other).to_string());
}

#[test]
fn derive_hogeweg_step_by_step() {
    let s = format!("{L}/hogeweg.lua");
    assert_eq!(derive(&s, &["--steps", "1"]), "F 1 F 0 F 1");
    assert_eq!(derive(&s, &["--steps", "2"]), "F 1 F 1 F 1 F 1");
    assert_eq!(derive(&s, &["--steps", "3"]), "F 1 F 0 F 0 F 1");
}

#[test]
fn derive_signal_propagation_enters_branches() {
    let s = format!("{L}/signal.lua");
    assert!(derive(&s, &["--steps", "1"]).starts_with("c F b F a F [ + a F"));
    // After three steps the signal has climbed past the first branch point and into it.
    let t = derive(&s, &["--steps", "3"]);
    assert!(t.starts_with("c F c F c F [ + b F a F"), "{t}");
}

#[test]
fn derive_json_and_parameters() {
    let s = format!("{L}/honda.lua");
    assert_eq!(derive(&s, &["--steps", "0"]), "A(1,10)");
    let json: serde_json::Value =
        serde_json::from_str(&derive(&s, &["--steps", "1", "--format", "json"])).expect("json");
    let modules = json.as_array().expect("array");
    // !(w*ws) F(l) [ &(a0) B(l*r2,w*wr) ] /(d) A(l*r1,w*wr)
    assert_eq!(modules.len(), 8);
    assert_eq!(modules[1]["name"], "F");
    assert_eq!(modules[1]["params"], serde_json::json!([1]));
    assert_eq!(modules[2]["name"], "[");
    assert_eq!(modules[7]["name"], "A");
    assert_eq!(modules[7]["params"][0], 0.9);
}

#[test]
fn derive_named_lua_parameters_as_json_objects() {
    let json: serde_json::Value = serde_json::from_str(&derive(
        &format!("{L}/city.lua"),
        &["--steps", "1", "--format", "json"],
    ))
    .expect("json");
    assert_eq!(json[0]["name"], "Block");
    assert_eq!(json[0]["params"]["d"].as_f64(), Some(60.0));
}

#[test]
fn stochastic_runs_repeat_per_seed() {
    let s = format!("{L}/stochastic.lua");
    let a = derive(&s, &["--seed", "1"]);
    assert_eq!(a, derive(&s, &["--seed", "1"]));
    assert_ne!(a, derive(&s, &["--seed", "2"]));
}

#[test]
fn open_lsystem_stops_at_the_height() {
    let low = derive(
        &format!("{L}/open.lua"),
        &["--set", "height=1", "--format", "count"],
    );
    let high = derive(
        &format!("{L}/open.lua"),
        &["--set", "height=5", "--format", "count"],
    );
    let (low, high): (u64, u64) = (low.parse().expect("n"), high.parse().expect("n"));
    assert!(low < high, "{low} < {high}");
}

fn run_glb(script: &str, extra: &[&str]) -> (Vec<u8>, serde_json::Value) {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out.glb");
    let out_s = out.to_string_lossy().to_string();
    let mut args = vec!["run", script, "-o", out_s.as_str(), "-q", "--stats"];
    args.extend_from_slice(extra);
    let stats = stdout_of(&pge(&args));
    let stats: serde_json::Value = serde_json::from_str(stats.trim()).expect("stats json");
    (std::fs::read(&out).expect("glb written"), stats)
}

macro_rules! runs {
    ($name:ident, $script:expr, $min_nodes:expr) => {
        #[test]
        fn $name() {
            let script = format!("{L}/{}", $script);
            let (glb, stats) = run_glb(&script, &[]);
            assert_eq!(&glb[0..4], b"glTF");
            let gltf = gltf::Gltf::from_slice(&glb).expect("valid glTF");
            assert!(gltf.meshes().count() >= 1);
            assert!(stats["modules"].as_u64().expect("modules") > 0);
            assert!(stats["triangles"].as_u64().expect("triangles") > 0);
            let nodes = stats["nodes"].as_u64().expect("nodes");
            let min: Option<u64> = $min_nodes;
            assert!(min.is_none_or(|min| nodes >= min), "{stats}");
            let (again, _) = run_glb(&script, &[]);
            assert!(glb == again, "{script}: same seed, same bytes");
        }
    };
}

runs!(run_koch, "koch.lua", Some(100));
runs!(run_plants, "plants.lua", Some(1000));
runs!(run_hogeweg, "hogeweg.lua", Some(100));
runs!(run_signal, "signal.lua", Some(10));
runs!(run_stochastic, "stochastic.lua", Some(10));
runs!(run_honda, "honda.lua", Some(500));
runs!(run_ternary, "ternary.lua", Some(500));
runs!(run_bush, "bush.lua", Some(500));
runs!(run_city, "city.lua", None);
runs!(run_open, "open.lua", Some(50));

#[test]
fn run_stats_count_modules_and_steps_override() {
    let (_, stats) = run_glb(&format!("{L}/plants.lua"), &["--steps", "2"]);
    assert_eq!(stats["modules"], 61);
    assert_eq!(stats["nodes"], 26);
}

/// A failing command on a script written to a temporary folder: exit 1, one line
/// `FILE:LINE: message` containing `needle`.
fn assert_fails(command: &str, source: &str, line: u32, needle: &str) {
    let dir = tempfile::tempdir().expect("tempdir");
    let script = dir.path().join("bad.lua");
    std::fs::write(&script, source).expect("write");
    let script_s = script.to_string_lossy().to_string();
    let out = dir.path().join("out.glb");
    let out_s = out.to_string_lossy().to_string();
    let args: Vec<&str> = if command == "run" {
        vec!["run", script_s.as_str(), "-o", out_s.as_str(), "-q"]
    } else {
        vec!["derive", script_s.as_str()]
    };
    let o = pge(&args);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    let prefix = format!("{script_s}:{line}: ");
    assert!(
        err.starts_with(&prefix),
        "expected '{prefix}...', got {err}"
    );
    assert!(err.contains(needle), "expected '{needle}' in {err}");
    assert!(!Path::new(&out).exists());
}

#[test]
fn a_left_side_that_does_not_parse() {
    assert_fails(
        "run",
        "local l = pge.LSystem('x')\nl:axiom('F')\nl:rule('A(1) -> B')\nreturn l\n",
        3,
        "rule 'A(1) -> B': a parameter of 'A' on a left side must be a name",
    );
}

#[test]
fn an_expression_with_an_unknown_name() {
    assert_fails(
        "derive",
        "local l = pge.LSystem('x')\nl:axiom('A(1)')\n\nl:rule('A(x) -> A(x * k)')\nl:iterations(2)\nreturn l\n",
        4,
        "unknown name 'k'",
    );
}

#[test]
fn a_successor_of_the_wrong_type() {
    assert_fails(
        "run",
        "local l = pge.LSystem('x')\nl:axiom('A')\nl:RRule('A', function() return true end)\nl:iterations(1)\nreturn l\n",
        3,
        "RRule 'A' is boolean",
    );
}

#[test]
fn a_parameter_a_classic_production_cannot_read() {
    assert_fails(
        "derive",
        "local l = pge.LSystem('x')\nl:axiom{ A{ v = 'green' } }\nl:rule('A(x) -> B(x)')\nl:iterations(1)\nreturn l\n",
        3,
        "cannot read the non-numeric parameters",
    );
}

#[test]
fn growth_past_max_modules_fails_fast() {
    assert_fails(
        "derive",
        "local l = pge.LSystem('x')\nl:axiom('F')\nl:rule('F -> FF')\nl:iterations(40)\nreturn l\n",
        1,
        "step 24: the string reached 16777216 modules, more than maxModules (10000000)",
    );
}

#[test]
fn a_write_to_this_in_an_rrule() {
    assert_fails(
        "run",
        "local l = pge.LSystem('x')\nl:axiom('A')\nl:RRule('A', function()\n  this:forward(2)\n  return 'F'\nend)\nl:iterations(1)\nreturn l\n",
        4,
        "RRule 'A': turtle:forward is not allowed",
    );
}

#[test]
fn derive_needs_an_lsystem() {
    let dir = tempfile::tempdir().expect("tempdir");
    let script = dir.path().join("model.lua");
    std::fs::write(&script, "return pge.model()\n").expect("write");
    let o = pge(&["derive", script.to_string_lossy().as_ref()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("needs a script that returns an L-system"));
}

#[test]
fn a_turtle_with_a_palette_writes_one_bark_mesh_with_vertex_colours() {
    // lsystems/bush.lua steps through four colours with `'`: one bark mesh (every colour's
    // branches, the colour in the vertices, one bark texture) and one leaf mesh, not a mesh
    // pair and a colour-baked texture per colour index.
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("bush.glb");
    let out_s = out.to_string_lossy().to_string();
    stdout_of(&pge(&["run", &format!("{L}/bush.lua"), "-o", &out_s, "-q"]));
    let (doc, buffers, _) = gltf::import(&out).expect("the glb imports");
    let names: Vec<_> = doc.meshes().map(|m| m.name().map(str::to_string)).collect();
    assert_eq!(names.len(), 2, "bark and leaves: {names:?}");
    // One bark texture set (colour, normal, roughness), not one per colour index.
    let bark_images: Vec<_> = doc
        .images()
        .filter_map(|i| i.name().filter(|n| n.starts_with("bark")))
        .collect();
    assert_eq!(
        bark_images,
        ["bark color", "bark normal", "bark roughness"],
        "one bark texture set"
    );
    let bark = doc.meshes().next().expect("the bark mesh");
    let prim = bark.primitives().next().expect("primitive");
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let colours: std::collections::BTreeSet<[u8; 4]> = reader
        .read_colors(0)
        .expect("bark vertex colours")
        .into_rgba_u8()
        .collect();
    // The palette's four colours ("#5a3d26", "#4a6b2a", "#3f7f2a", "#5c9b33"), linear.
    assert_eq!(colours.len(), 4, "{colours:?}");
    let extras: serde_json::Value =
        serde_json::from_str(bark.extras().as_ref().expect("bark extras").get()).expect("json");
    let parents = extras["pge"]["skeleton"]["parents"]
        .as_array()
        .expect("one skeleton for every colour");
    let roots = parents.iter().filter(|p| p.as_i64() == Some(-1)).count();
    assert!(
        roots > 1,
        "every colour's skeleton keeps its roots: {roots}"
    );
}
