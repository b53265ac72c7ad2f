//! The Lua API of space colonization through a real session: scripts in, models or
//! `FILE:LINE:` errors out.

use std::path::{Path, PathBuf};

use pge_engine::geometry::Model;
use pge_engine::{Engine, Error, SessionOptions};
use pge_spacecol::SpaceColonizationPlugin;

/// A folder holding the test's script and files.
struct Scene {
    dir: tempfile::TempDir,
}

impl Scene {
    fn new() -> Scene {
        Scene {
            dir: tempfile::tempdir().expect("tempdir"),
        }
    }

    fn file(&self, name: &str, text: &str) -> PathBuf {
        let path = self.dir.path().join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).expect("mkdir");
        }
        std::fs::write(&path, text).expect("write");
        path
    }

    fn run(&self, script: &str) -> Result<Model, Error> {
        let path = self.file("tree.lua", script);
        generate(&path, 1)
    }
}

fn generate(path: &Path, seed: u64) -> Result<Model, Error> {
    let engine = Engine::builder()
        .plugin(SpaceColonizationPlugin)
        .build()
        .expect("engine");
    let session = engine
        .session(SessionOptions {
            seed,
            ..SessionOptions::default()
        })
        .expect("session");
    session.generate(path, &mut |_, _| {}).map(|g| g.model)
}

/// Runs `script`, expects an error at `tree.lua:LINE:` that contains `needle`.
fn assert_error(script: &str, line: u32, needle: &str) {
    let scene = Scene::new();
    let err = scene
        .run(script)
        .expect_err("the script must fail")
        .to_string();
    let at = format!("tree.lua:{line}: ");
    let pos = err
        .find(&at)
        .unwrap_or_else(|| panic!("expected '{at}' in: {err}"));
    assert!(
        err[..pos].ends_with('/') || pos == 0,
        "the location comes first: {err}"
    );
    assert!(err.contains(needle), "expected '{needle}' in: {err}");
    assert_eq!(err.lines().count(), 1, "one line: {err}");
}

const CUBE_OBJ: &str = "v -2 3 -2\nv 2 3 -2\nv 2 7 -2\nv -2 7 -2\nv -2 3 2\nv 2 3 2\nv 2 7 2\nv -2 7 2\n\
f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

#[test]
fn a_tree_with_leaves_and_stats() {
    let scene = Scene::new();
    let model = scene
        .run(
            r#"
return pge.SpaceColonization{
  envelope = pge.shape.sphere{ center = {0, 5, 0}, radius = 2 },
  points = 500, step = 0.2, influence = 1.5, kill = 0.4,
  leaves = { perTip = {2, 3}, size = 0.2 },
}"#,
        )
        .expect("grows");
    model.validate().expect("valid");
    assert_eq!(model.meshes.len(), 2);
    assert!(model.stats.nodes > 50);
    assert!(
        model.stats.leaves
            >= 2 * model.meshes[0]
                .skeleton
                .as_ref()
                .expect("skeleton")
                .tips()
                .len() as u64
    );
    let phases: Vec<&str> = model.stats.phases.iter().map(|(n, _)| n.as_str()).collect();
    for phase in ["points", "growth", "radii", "meshing", "leaves"] {
        assert!(phases.contains(&phase), "phase {phase} in {phases:?}");
    }
}

#[test]
fn every_shape_grows_a_tree() {
    let shapes = [
        "pge.shape.sphere{ center = {0, 5, 0}, radius = 2 }",
        "pge.shape.ellipsoid{ center = {0, 5, 0}, radii = {3, 2, 2} }",
        "pge.shape.box{ min = {-2, 3, -2}, max = {2, 6, 2} }",
        "pge.shape.capsule{ a = {0, 3, 0}, b = {0, 6, 0}, radius = 1.5 }",
        "pge.shape.cone{ base = {0, 3, 0}, apex = {0, 8, 0}, radius = 2 }",
        "pge.shape.cylinder{ a = {0, 3, 0}, b = {0, 6, 0}, radius = 2 }",
        "pge.shape.revolve{ profile = {{0, 3}, {2, 4}, {1.5, 6}, {0, 7}} }",
        "pge.shape.union{ pge.shape.sphere{ center = {-1, 5, 0}, radius = 1.5 }, pge.shape.sphere{ center = {1.5, 5, 0}, radius = 1.5 } }",
        "pge.shape.difference{ pge.shape.sphere{ center = {0, 5, 0}, radius = 2.5 }, pge.shape.sphere{ center = {0, 4, 0}, radius = 1.5 } }",
        "pge.shape.predicate(function(p) return p.y > 4 end, { min = {-2, 3, -2}, max = {2, 6, 2} })",
    ];
    for shape in shapes {
        let scene = Scene::new();
        let script = format!(
            "return pge.SpaceColonization{{ envelope = {shape}, points = 300, step = 0.25, influence = 1.5, kill = 0.4 }}"
        );
        let model = scene
            .run(&script)
            .unwrap_or_else(|e| panic!("{shape}: {e}"));
        model.validate().expect("valid");
        assert!(
            model.stats.nodes > 10,
            "{shape}: {} nodes",
            model.stats.nodes
        );
    }
}

#[test]
fn mesh_envelopes_from_obj_glb_and_script_models() {
    let scene = Scene::new();
    scene.file("data/cube.obj", CUBE_OBJ);
    let from_obj = scene
        .run(r#"return pge.SpaceColonization{ envelope = pge.shape.mesh{ path = "data/cube.obj" }, points = 400, step = 0.25, influence = 1.5, kill = 0.4 }"#)
        .expect("obj");
    assert!(from_obj.stats.nodes > 20);
    // A transform places the mesh: the cube (y from 3 to 7) halved, then raised by 2.
    scene
        .run(
            r#"local s = pge.shape.mesh{ path = "data/cube.obj", transform = pge.mat4.translate{0, 2, 0} * pge.mat4.scale(0.5) }
local lo, hi = s:bounds()
assert(math.abs(lo.y - 3.5) < 1e-5 and math.abs(hi.y - 5.5) < 1e-5 and math.abs(hi.x - 1) < 1e-5, "bounds")
assert(s:contains{0, 4.5, 0} and not s:contains{0, 6, 0})
return pge.SpaceColonization{ envelope = s, points = 200, step = 0.1, influence = 0.8, kill = 0.2 }"#,
        )
        .expect("transformed mesh");

    // The same cube as a glb written by the engine's exporter.
    let cube = r#"local v = {-2,3,-2, 2,3,-2, 2,7,-2, -2,7,-2, -2,3,2, 2,3,2, 2,7,2, -2,7,2}
local f = {0,3,2, 0,2,1, 4,5,6, 4,6,7, 0,1,5, 0,5,4, 1,2,6, 1,6,5, 2,3,7, 2,7,6, 3,0,4, 3,4,7}
return pge.mesh{ positions = v, indices = f }"#;
    let engine = Engine::builder().build().expect("engine");
    let session = engine.session(SessionOptions::default()).expect("session");
    let mesh = session.eval_value(cube).expect("mesh");
    let mut alg = session.algorithm_from(mesh).expect("model");
    let model =
        pge_engine::algorithm::run(&mut *alg, &session.context(), &mut |_| {}).expect("runs");
    let glb = pge_engine::export::glb_bytes(&model, &Default::default()).expect("glb");
    std::fs::write(scene.dir.path().join("cube.glb"), glb).expect("write glb");
    let from_glb = scene
        .run(r#"return pge.SpaceColonization{ envelope = pge.shape.mesh{ path = "cube.glb" }, points = 400, step = 0.25, influence = 1.5, kill = 0.4 }"#)
        .expect("glb");
    assert!(from_glb.stats.nodes > 20);

    let from_model = scene
        .run(&format!(
            "local m = (function() {cube} end)()\nreturn pge.SpaceColonization{{ envelope = pge.shape.mesh{{ model = m }}, mode = \"vertices\", step = 0.25, influence = 2.5, kill = 0.4 }}"
        ))
        .expect("model, vertices mode");
    assert!(from_model.stats.nodes > 5);
}

#[test]
fn same_seed_same_tree_other_seed_other_tree() {
    let scene = Scene::new();
    let path = scene.file(
        "tree.lua",
        "return pge.SpaceColonization{ envelope = pge.shape.sphere{ center = {0, 5, 0}, radius = 2 }, points = 400, leaves = {} }",
    );
    let a = generate(&path, 3).expect("a");
    let b = generate(&path, 3).expect("b");
    let c = generate(&path, 4).expect("c");
    let glb = |m: &Model| pge_engine::export::glb_bytes(m, &Default::default()).expect("glb");
    assert_eq!(glb(&a), glb(&b));
    assert_ne!(glb(&a), glb(&c));
}

#[test]
fn bad_parameters_are_located_errors() {
    let env = "envelope = pge.shape.sphere{ center = {0, 5, 0}, radius = 2 }";
    assert_error(
        &format!("local x = 1\nreturn pge.SpaceColonization{{ {env}, influence = 1, kill = 2 }}"),
        2,
        "kill (2) must be smaller than influence (1)",
    );
    assert_error(
        &format!("return pge.SpaceColonization{{ {env}, step = 0 }}"),
        1,
        "step must be a number > 0, got 0",
    );
    assert_error(
        &format!("return pge.SpaceColonization{{ {env}, step = -1 }}"),
        1,
        "step must be a number > 0, got -1",
    );
    assert_error(
        &format!("return pge.SpaceColonization{{ {env}, influence = 0/0 }}"),
        1,
        "influence must be a number > 0, got NaN",
    );
    assert_error(
        &format!("return pge.SpaceColonization{{ {env}, tropism = {{0, 0/0, 0}} }}"),
        1,
        "tropism must be a vector",
    );
    assert_error(
        &format!("return pge.SpaceColonization{{ {env}, persistence = -1 }}"),
        1,
        "persistence must be a number >= 0, got -1",
    );
    assert_error(
        &format!("return pge.SpaceColonization{{ {env}, perception = 200 }}"),
        1,
        "perception must be a number between 0 and 180, got 200",
    );
    assert_error(
        &format!("return pge.SpaceColonization{{ {env}, maxTurn = 0 }}"),
        1,
        "maxTurn must be an angle in degrees > 0 and <= 180, got 0",
    );
    assert_error(
        &format!("return pge.SpaceColonization{{ {env}, points = 0 }}"),
        1,
        "points must be an integer between 1 and 10000000, got 0",
    );
    assert_error(
        &format!("return pge.SpaceColonization{{ {env}, mode = \"cloud\" }}"),
        1,
        "mode must be \"fill\", \"surround\" or \"vertices\"",
    );
    assert_error(
        &format!("return pge.SpaceColonization{{ {env}, influense = 3 }}"),
        1,
        "'influense' is not an option (known: envelope,",
    );
    assert_error(
        &format!("return pge.SpaceColonization{{ {env}, mesh = {{ sides = 2 }} }}"),
        1,
        "mesh.sides must be an integer between 3 and 64, got 2",
    );
    assert_error(
        &format!("return pge.SpaceColonization{{ {env}, leaves = {{ colors = {{\"green\"}} }} }}"),
        1,
        "leaves.colors[1] must be a colour",
    );
    assert_error(
        "return pge.SpaceColonization{ points = 10 }",
        1,
        "envelope is required",
    );
    assert_error(
        "return pge.SpaceColonization{ envelope = 3 }",
        1,
        "envelope must be a shape (pge.shape.*), got integer",
    );
    assert_error(
        "local m = pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }\nreturn pge.SpaceColonization{ envelope = m }",
        2,
        "got userdata (a mesh or model becomes a shape with pge.shape.mesh{model = m})",
    );
    assert_error(
        "local s = pge.shape.sphere{ center = {0, 0, 0}, radius = -1 }",
        1,
        "pge.shape.sphere: radius must be a number > 0, got -1",
    );
    assert_error(
        "local s = pge.shape.ellipsoid{ radii = {1, 0, 1} }",
        1,
        "radii must all be > 0",
    );
    assert_error(
        "local s = pge.shape.box{ min = {0, 0, 0}, max = {1, 0, 1} }",
        1,
        "min must be below max on every axis",
    );
    assert_error(
        "local s = pge.shape.revolve{ profile = {{0, 0}, {1, 1}} }",
        1,
        "profile needs at least 3 points",
    );
    assert_error(
        "local s = pge.shape.revolve{ profile = {{0, 0}, {-1, 1}, {0, 2}} }",
        1,
        "profile[2] must have a finite r >= 0",
    );
}

#[test]
fn envelopes_without_points_are_located_errors() {
    assert_error(
        "local s = pge.shape.sphere{ center = {0, 5, 0}, radius = 2 }\nreturn pge.SpaceColonization{ envelope = pge.shape.difference{ s, s } }",
        2,
        "yields no attraction points",
    );
    assert_error(
        "\nreturn pge.SpaceColonization{ envelope = pge.shape.predicate(function(p) return false end, {min = {0,0,0}, max = {1,1,1}}) }",
        2,
        "yields no attraction points",
    );
    assert_error(
        "return pge.SpaceColonization{ envelope = pge.shape.predicate(function(p) return true end, {min = {0,0,0}, max = {1,1,1}}), mode = 'surround' }",
        1,
        "needs an envelope with a surface",
    );
}

#[test]
fn predicate_errors_point_into_the_predicate() {
    assert_error(
        "local function inside(p)\n  return p.y > nil\nend\nreturn pge.SpaceColonization{ envelope = pge.shape.predicate(inside, {min = {0,0,0}, max = {1,1,1}}) }",
        2,
        "attempt to compare",
    );
}

#[test]
fn mesh_file_problems_are_located_errors() {
    assert_error(
        "\nlocal s = pge.shape.mesh{ path = \"missing.obj\" }",
        2,
        "missing.obj",
    );
    let scene = Scene::new();
    scene.file(
        "open.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\n",
    );
    scene.file("bad.obj", "v 0 0 0\nv 1 0 oops\n");
    scene.file("crown.txt", "");
    let err = scene
        .run("local s = pge.shape.mesh{ path = \"open.obj\" }\nreturn pge.SpaceColonization{ envelope = s }")
        .expect_err("open mesh")
        .to_string();
    assert!(
        err.contains("tree.lua:2: ") && err.contains("mesh 'open.obj' is not closed"),
        "{err}"
    );
    let err = scene
        .run("local s = pge.shape.mesh{ path = \"bad.obj\" }")
        .expect_err("bad obj")
        .to_string();
    assert!(
        err.contains("tree.lua:1: ") && err.contains("'bad.obj': line 2: 'oops' is not a number"),
        "{err}"
    );
    let err = scene
        .run("local s = pge.shape.mesh{ path = \"crown.txt\" }")
        .expect_err("bad ext")
        .to_string();
    assert!(err.contains("must be an .obj, .glb or .gltf file"), "{err}");
    // The open mesh is fine for the vertices mode.
    let model = scene
        .run("return pge.SpaceColonization{ envelope = pge.shape.mesh{ path = \"open.obj\" }, mode = \"vertices\", step = 0.1, influence = 2, kill = 0.05, root = {0.2, -0.5, 0.2} }")
        .expect("vertices of an open mesh");
    assert!(model.stats.nodes >= 2);
}

#[test]
fn an_unreachable_crown_stops_at_the_cap() {
    let scene = Scene::new();
    let model = scene
        .run("return pge.SpaceColonization{ envelope = pge.shape.sphere{ center = {0, 500, 0}, radius = 2 }, points = 100, step = 0.5, influence = 1, kill = 0.3, maxIterations = 40 }")
        .expect("stops with a warning, not an error");
    assert_eq!(model.stats.nodes, 41);
}

#[test]
fn defaults_follow_the_values_given() {
    let scene = Scene::new();
    // Only a small influence: the default kill (two steps) would exceed it, so it shrinks.
    let model = scene
        .run("return pge.SpaceColonization{ envelope = pge.shape.sphere{ center = {0, 3, 0}, radius = 1 }, points = 200, step = 0.1, influence = 0.15 }")
        .expect("kill follows influence");
    assert!(model.stats.nodes > 10);
    // Only a large kill: the default influence grows past it.
    scene
        .run("return pge.SpaceColonization{ envelope = pge.shape.sphere{ center = {0, 3, 0}, radius = 1 }, points = 200, step = 0.1, kill = 2 }")
        .expect("influence follows kill");
}

#[test]
fn a_seed_option_grows_different_trees_in_one_run() {
    let scene = Scene::new();
    let model = scene
        .run(
            r#"local function tree(seed)
  return pge.SpaceColonization{ envelope = pge.shape.sphere{ center = {0, 3, 0}, radius = 1 }, points = 200, step = 0.1, seed = seed }:model()
end
local m = pge.model()
m:add(tree(1))
m:add(tree(2), pge.mat4.translate{5, 0, 0})
m:add(tree(1), pge.mat4.translate{10, 0, 0})
return m"#,
        )
        .expect("three trees");
    assert_eq!(model.instances.len(), 3);
    let bark = |k: usize| &model.meshes[model.instances[k].mesh].positions;
    assert_ne!(bark(0), bark(1), "seeds 1 and 2 differ");
    assert_eq!(bark(0), bark(2), "seed 1 twice is the same tree");
    assert_error(
        "return pge.SpaceColonization{ envelope = pge.shape.sphere{ radius = 1 }, seed = -3 }",
        1,
        "seed must be an integer >= 0, got -3",
    );
}
