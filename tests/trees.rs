//! End-to-end tests of trees: every species script through `pge run`, the glb it writes
//! (bark and leaf meshes, textures, the skeleton in the extras), `--stats`, determinism, and
//! the located errors of bad tree scripts.

use pge_engine::math;
mod common;

use common::{pge, run_with_stats};
use std::path::Path;

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).to_string()
}

/// Checks what a tree's glb must carry (docs/glb.md) and returns (bark, leaf) triangle counts.
fn check_tree_glb(script: &str, glb: &[u8]) -> (usize, usize) {
    let (doc, buffers, images) =
        gltf::import_slice(glb).unwrap_or_else(|e| panic!("{script}: {e}"));
    // Bark and leaves each carry a PBR set: base colour, normal and roughness maps, 512 px
    // or more.
    assert_eq!(
        images.len(),
        6,
        "{script}: bark and leaf texture sets embedded"
    );
    assert!(
        images.iter().all(|i| i.width >= 512 && i.height >= 512),
        "{script}: maps of 512 px or more"
    );
    let meshes: Vec<_> = doc.meshes().collect();
    assert_eq!(meshes.len(), 2, "{script}: a bark mesh and a leaf mesh");
    let mut counts = [0usize; 2];
    for (k, mesh) in meshes.iter().enumerate() {
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let positions: Vec<[f32; 3]> = reader.read_positions().expect("positions").collect();
            let normals: Vec<[f32; 3]> = reader.read_normals().expect("normals").collect();
            let uvs = reader.read_tex_coords(0).expect("uvs").into_f32().count();
            let indices: Vec<u32> = reader.read_indices().expect("indices").into_u32().collect();
            assert_eq!(normals.len(), positions.len());
            assert_eq!(uvs, positions.len());
            assert!(
                indices.iter().all(|i| (*i as usize) < positions.len()),
                "{script}: index range"
            );
            assert!(normals.iter().all(|n| {
                let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                (l - 1.0).abs() < 1e-3
            }));
            assert!(positions.iter().flatten().all(|c| c.is_finite()));
            counts[k] += indices.len() / 3;
            let material = prim.material();
            assert!(
                material.normal_texture().is_some()
                    && material
                        .pbr_metallic_roughness()
                        .metallic_roughness_texture()
                        .is_some(),
                "{script}: normal and roughness maps"
            );
            assert!(
                material
                    .pbr_metallic_roughness()
                    .base_color_texture()
                    .is_some(),
                "{script}: textured"
            );
            if k == 1 {
                assert_eq!(
                    material.alpha_mode(),
                    gltf::material::AlphaMode::Mask,
                    "{script}: leaves are masked"
                );
                assert!(material.double_sided(), "{script}: leaves are double-sided");
                assert!(
                    reader.read_colors(0).is_some(),
                    "{script}: a colour per leaf"
                );
            }
        }
    }
    let extras: serde_json::Value =
        serde_json::from_str(meshes[0].extras().as_ref().expect("bark extras").get())
            .expect("json");
    let skeleton = &extras["pge"]["skeleton"];
    let parents = skeleton["parents"].as_array().expect("skeleton parents");
    assert_eq!(parents[0], -1, "{script}: node 0 is a root");
    assert_eq!(
        skeleton["positions"].as_array().expect("positions").len(),
        3 * parents.len()
    );
    assert_eq!(
        skeleton["radii"].as_array().expect("radii").len(),
        parents.len()
    );
    (counts[0], counts[1])
}

macro_rules! species {
    ($($name:ident),* $(,)?) => {$(
        #[test]
        fn $name() {
            let script = format!("scripts/species/{}.lua", stringify!($name));
            let dir = tempfile::tempdir().expect("tempdir");
            let (stats, glb) = run_with_stats(&script, dir.path(), &[]);
            let (bark, leaves) = check_tree_glb(&script, &glb);
            assert!(stats["nodes"].as_u64().expect("nodes") > 100, "{script}: {stats}");
            assert!(stats["leaves"].as_u64().expect("leaves") > 100, "{script}: {stats}");
            assert_eq!(stats["triangles"].as_u64(), Some((bark + leaves) as u64));
            assert_eq!(leaves as u64, 2 * stats["leaves"].as_u64().expect("leaves"));
            for phase in ["points", "growth", "radii", "meshing", "leaves", "textures", "export"] {
                assert!(stats["phases"][phase].is_number(), "{script}: phase {phase} in {stats}");
            }
        }
    )*};
}

// conifer.lua and spruce.lua (pge.Conifer, no attraction points): tests/conifers.rs.
species!(oak, poplar, willow, bush, vase, topiary);

/// Every script in `scripts/species/`, including those the tests above do not run: bark and
/// leaves each carry base colour, normal and roughness maps of 512 px or more.
#[test]
fn every_species_carries_normal_and_roughness_maps() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut scripts: Vec<String> = std::fs::read_dir(common::root().join("scripts/species"))
        .expect("scripts/species")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "lua"))
        .filter_map(|p| Some(format!("scripts/species/{}", p.file_name()?.to_str()?)))
        .collect();
    scripts.sort();
    assert!(scripts.len() >= 7, "{scripts:?}");
    for script in &scripts {
        let (_, glb) = run_with_stats(script, dir.path(), &[]);
        check_tree_glb(script, &glb);
    }
}

/// The skeleton in the oak's glb: one tree rooted at node 0, parents before children, tips
/// at the tip radius and the pipe model `r^n = sum of r_child^n` at every fork (n = 2.2 in
/// oak.lua).
#[test]
fn the_exported_skeleton_is_one_tree_with_pipe_radii() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (_, glb) = run_with_stats("scripts/species/oak.lua", dir.path(), &[]);
    let doc = gltf::Gltf::from_slice(&glb).expect("glb");
    let mesh = doc.meshes().next().expect("bark");
    let extras: serde_json::Value =
        serde_json::from_str(mesh.extras().as_ref().expect("extras").get()).expect("json");
    let skeleton = &extras["pge"]["skeleton"];
    let parents: Vec<i64> = skeleton["parents"]
        .as_array()
        .expect("parents")
        .iter()
        .map(|p| p.as_i64().expect("int"))
        .collect();
    let radii: Vec<f64> = skeleton["radii"]
        .as_array()
        .expect("radii")
        .iter()
        .map(|r| r.as_f64().expect("number"))
        .collect();
    assert_eq!(parents[0], -1);
    let mut children = vec![Vec::new(); parents.len()];
    for (i, p) in parents.iter().enumerate().skip(1) {
        assert!(
            *p >= 0 && (*p as usize) < i,
            "node {i} has parent {p}: one tree, parents first"
        );
        children[*p as usize].push(i);
    }
    let n = 2.2f64;
    for (i, kids) in children.iter().enumerate() {
        if kids.is_empty() {
            assert!(
                (radii[i] - 0.025).abs() < 1e-6,
                "tip {i} has radius {}",
                radii[i]
            );
        } else {
            let sum: f64 = kids.iter().map(|c| math::powf(radii[*c], n)).sum();
            assert!(
                (math::powf(radii[i], n) - sum).abs() <= 1e-4 * sum,
                "node {i}: {} vs {}",
                math::powf(radii[i], n),
                sum
            );
        }
    }
}

/// Lua appended to conifer.lua (its `return pge.Conifer{` made `local tree =`):
/// grows the tree, walks its skeleton as it grew (a branch goes on through each node's first
/// child, the lowest index; later children start side branches) and fails the run if a
/// segment turns more than `LIMIT` degrees from its branch's first segment.
const TURN_CHECK: &str = r#"
local s = tree:skeleton()
assert(s:count() > 1000, "a conifer of " .. s:count() .. " nodes")
local start, continued, worst = {}, {}, 0
for i = 1, s:count() do
  local q = s:parent(i)
  if q > 0 then
    local d = (s:position(i) - s:position(q)):normalize()
    start[i] = (continued[q] or start[q] == nil) and d or start[q]
    continued[q] = true
    local cos = math.max(-1, math.min(1, d:dot(start[i])))
    worst = math.max(worst, math.deg(math.acos(cos)))
  end
end
if worst > LIMIT then error(string.format("a branch turns %.1f degrees", worst)) end
return tree
"#;

/// Runs conifer.lua with [`TURN_CHECK`] at `limit` degrees; returns the exit code and stderr.
fn conifer_turn_check(limit: f64, dir: &Path) -> (Option<i32>, String) {
    let source = std::fs::read_to_string("scripts/species/conifer.lua").expect("conifer.lua");
    let head = "return pge.Conifer{";
    assert_eq!(
        source.matches(head).count(),
        1,
        "conifer.lua returns one pge.Conifer"
    );
    let script = source.replace(head, "local tree = pge.Conifer{")
        + &TURN_CHECK.replace("LIMIT", &limit.to_string());
    let path = dir.join("conifer_turns.lua");
    std::fs::write(&path, script).expect("write");
    let out = dir.join("tree.glb");
    let o = pge(&[
        "run",
        &path.to_string_lossy(),
        "-o",
        &out.to_string_lossy(),
        "-q",
    ]);
    (o.status.code(), text(&o.stderr))
}

/// The conifer's side branches never loop back (pge.Conifer grows it): no branch of its skeleton turns more than 120 degrees from
/// its start. (The same walk at 10 degrees does fail: it sees the droop of the lower
/// branches.)
#[test]
fn conifer_branches_never_turn_back() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (code, stderr) = conifer_turn_check(120.0, dir.path());
    assert_eq!(code, Some(0), "{stderr}");
    let (code, stderr) = conifer_turn_check(10.0, dir.path());
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("a branch turns"), "{stderr}");
}

/// The mesh envelope of topiary.lua in its three modes.
#[test]
fn mesh_envelope_modes() {
    let dir = tempfile::tempdir().expect("tempdir");
    for mode in ["fill", "surround", "vertices"] {
        let set = format!("mode={mode}");
        let (stats, glb) =
            run_with_stats("scripts/species/topiary.lua", dir.path(), &["--set", &set]);
        check_tree_glb(&format!("topiary {mode}"), &glb);
        assert!(
            stats["nodes"].as_u64().expect("nodes") > 50,
            "{mode}: {stats}"
        );
    }
}

#[test]
fn same_seed_same_bytes_other_seed_other_tree() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (_, a) = run_with_stats("scripts/species/bush.lua", dir.path(), &["--seed", "7"]);
    let (_, b) = run_with_stats("scripts/species/bush.lua", dir.path(), &["--seed", "7"]);
    let (_, c) = run_with_stats("scripts/species/bush.lua", dir.path(), &["--seed", "8"]);
    assert_eq!(a, b);
    assert_ne!(a, c);
}

#[test]
fn parameters_and_steps_change_the_tree() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (full, _) = run_with_stats("scripts/species/bush.lua", dir.path(), &[]);
    let (few, _) = run_with_stats(
        "scripts/species/bush.lua",
        dir.path(),
        &["--set", "points=300"],
    );
    let (early, _) = run_with_stats("scripts/species/bush.lua", dir.path(), &["--steps", "5"]);
    assert!(few["nodes"].as_u64() < full["nodes"].as_u64());
    assert!(early["nodes"].as_u64() < few["nodes"].as_u64());
}

/// A failing tree script: exit 1, one `FILE:LINE: message` line containing `needle`.
fn assert_tree_error(source: &str, line: u32, needle: &str) {
    let dir = tempfile::tempdir().expect("tempdir");
    let script = dir.path().join("bad.lua");
    std::fs::write(&script, source).expect("write");
    let out = dir.path().join("bad.glb");
    let (script_s, out_s) = (
        script.to_string_lossy().to_string(),
        out.to_string_lossy().to_string(),
    );
    let o = pge(&["run", &script_s, "-o", &out_s, "-q"]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{source}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(
        err.starts_with(&format!("{script_s}:{line}: ")),
        "located at line {line}: {err}"
    );
    assert!(err.contains(needle), "expected '{needle}' in: {err}");
    assert!(!out.exists());
}

#[test]
fn bad_tree_scripts_fail_with_located_errors() {
    let sphere = "pge.shape.sphere{ center = {0, 5, 0}, radius = 2 }";
    assert_tree_error(
        &format!(
            "-- kill larger than influence\nreturn pge.SpaceColonization{{ envelope = {sphere}, influence = 1, kill = 2 }}\n"
        ),
        2,
        "kill (2) must be smaller than influence (1)",
    );
    assert_tree_error(
        &format!("return pge.SpaceColonization{{ envelope = {sphere}, step = 0 }}\n"),
        1,
        "step must be a number > 0",
    );
    assert_tree_error(
        &format!("return pge.SpaceColonization{{ envelope = {sphere}, influence = 0/0 }}\n"),
        1,
        "influence must be a number > 0, got NaN",
    );
    assert_tree_error(
        "local s = pge.shape.mesh{ path = \"no-such-crown.obj\" }\nreturn s\n",
        1,
        "no-such-crown.obj",
    );
    assert_tree_error(
        "local never = pge.shape.predicate(function(p) return false end, { min = {-1, 0, -1}, max = {1, 2, 1} })\nreturn pge.SpaceColonization{ envelope = never }\n",
        2,
        "yields no attraction points",
    );
    assert_tree_error(
        "local s = pge.shape.sphere{ center = {0, 5, 0}, radius = 2 }\n\nreturn pge.SpaceColonization{ envelope = pge.shape.difference{ s, s } }\n",
        3,
        "yields no attraction points",
    );
}

#[test]
fn an_unreachable_crown_stops_at_the_cap_with_a_warning() {
    let dir = tempfile::tempdir().expect("tempdir");
    let script = dir.path().join("far.lua");
    std::fs::write(
        &script,
        "return pge.SpaceColonization{ envelope = pge.shape.sphere{ center = {0, 900, 0}, radius = 2 }, step = 0.5, influence = 1, kill = 0.3, maxIterations = 30 }\n",
    )
    .expect("write");
    let out = dir.path().join("far.glb");
    let o = pge(&[
        "run",
        &script.to_string_lossy(),
        "-o",
        &out.to_string_lossy(),
        "-q",
    ]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("warning: space colonization stopped at maxIterations = 30"),
        "{err}"
    );
    assert!(out.exists());
}

/// The oak's leaves are lit on both faces: their material lets light through with the
/// translucency and back colour oak.lua gives (`KHR_materials_diffuse_transmission`,
/// declared used, not required), the bark's does not, and the file validates.
#[test]
fn oak_leaves_carry_the_species_diffuse_transmission() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (_, glb) = run_with_stats("scripts/species/oak.lua", dir.path(), &[]);
    let json: serde_json::Value =
        serde_json::from_slice(&gltf::binary::Glb::from_slice(&glb).expect("glb").json)
            .expect("json");
    let ext = "KHR_materials_diffuse_transmission";
    let used = json["extensionsUsed"].as_array().expect("extensionsUsed");
    assert!(used.iter().any(|e| e == ext), "{used:?}");
    let required = json["extensionsRequired"].as_array();
    assert!(!required.is_some_and(|r| r.iter().any(|e| e == ext)));
    let material = |name: &str| {
        json["materials"]
            .as_array()
            .expect("materials")
            .iter()
            .find(|m| m["name"] == name)
            .unwrap_or_else(|| panic!("a {name} material"))
            .clone()
    };
    assert!(material("bark")["extensions"].get(ext).is_none());
    let leaves = &material("leaves")["extensions"][ext];
    // oak.lua: backColor = "#b4c86e", translucency = 0.25.
    let source =
        std::fs::read_to_string(common::root().join("scripts/species/oak.lua")).expect("oak.lua");
    assert!(source.contains("backColor = \"#b4c86e\", translucency = 0.25"));
    let factor = leaves["diffuseTransmissionFactor"]
        .as_f64()
        .expect("factor");
    assert!((factor - 0.25).abs() < 1e-6, "{leaves}");
    let linear = |byte: u8| {
        let c = f64::from(byte) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            math::powf((c + 0.055) / 1.055, 2.4)
        }
    };
    let color = leaves["diffuseTransmissionColorFactor"]
        .as_array()
        .expect("colour");
    for (got, byte) in color.iter().zip([0xb4u8, 0xc8, 0x6e]) {
        let got = got.as_f64().expect("number");
        assert!((got - linear(byte)).abs() < 1e-5, "{leaves}");
    }
    let path = dir.path().join("tree.glb");
    let (ok, report) = common::run_validator(&[path]);
    assert!(ok, "{report}");
}
