//! Conifers that read as conifers: `conifer.lua` (a pine) and `spruce.lua` grown
//! by `pge.Conifer`, measured on the skeleton their glb carries (`extras.pge.skeleton`):
//! a straight leader, first-order branches in whorls, thin joints. Also the generator's
//! stages and its located errors.

use pge_engine::math;
mod common;

use common::{pge, run_with_stats as run};

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).to_string()
}

/// The skeleton of a tree's glb: parents (-1 for the root), positions and radii.
struct Skeleton {
    parents: Vec<i64>,
    positions: Vec<[f64; 3]>,
    radii: Vec<f64>,
}

fn skeleton(glb: &[u8]) -> Skeleton {
    let doc = gltf::Gltf::from_slice(glb).expect("glb");
    let bark = doc
        .meshes()
        .find(|m| m.extras().is_some())
        .expect("a bark mesh with extras");
    let extras: serde_json::Value =
        serde_json::from_str(bark.extras().as_ref().expect("extras").get()).expect("json");
    let s = &extras["pge"]["skeleton"];
    let numbers = |key: &str| -> Vec<f64> {
        s[key]
            .as_array()
            .unwrap_or_else(|| panic!("skeleton {key}"))
            .iter()
            .map(|v| v.as_f64().expect("a number"))
            .collect()
    };
    let parents = numbers("parents").iter().map(|p| *p as i64).collect();
    let positions = numbers("positions")
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    Skeleton {
        parents,
        positions,
        radii: numbers("radii"),
    }
}

/// What the issue measures.
#[derive(Debug)]
struct Metrics {
    /// Whorls of 3 or more first-order branches.
    whorls: usize,
    /// Share of first-order branches in such whorls.
    in_whorls: f64,
    /// Largest horizontal distance of a trunk node from the root's vertical, over the height.
    deviation: f64,
    /// Median of (a branch's first radius / the trunk's radius at its joint).
    joint_ratio: f64,
    first_order: usize,
    height: f64,
}

/// Trunk: from the root, the child with the largest radius. First-order branches: the
/// other children of trunk nodes. Whorls: first-order origins sorted by height and grouped
/// while within `WINDOW` of the height of the group's lowest.
fn metrics(s: &Skeleton) -> Metrics {
    const WINDOW: f64 = 0.02;
    assert_eq!(s.parents[0], -1, "node 0 is the root");
    let n = s.parents.len();
    let mut children = vec![Vec::new(); n];
    for (i, &p) in s.parents.iter().enumerate().skip(1) {
        assert!(p >= 0 && (p as usize) < i, "node {i}: parent {p}");
        children[p as usize].push(i);
    }
    let root = s.positions[0];
    let height = s
        .positions
        .iter()
        .map(|p| p[1] - root[1])
        .fold(0.0, f64::max);
    let mut trunk = vec![0usize];
    let mut next_on_trunk = vec![None; n];
    loop {
        let t = *trunk.last().expect("root");
        let Some(&next) = children[t]
            .iter()
            .max_by(|a, b| s.radii[**a].total_cmp(&s.radii[**b]))
        else {
            break;
        };
        next_on_trunk[t] = Some(next);
        trunk.push(next);
    }
    let mut origins = Vec::new();
    let mut ratios = Vec::new();
    let mut deviation: f64 = 0.0;
    for &t in &trunk {
        let p = s.positions[t];
        deviation = deviation.max(math::hypot(p[0] - root[0], p[2] - root[2]));
        for &c in &children[t] {
            if Some(c) != next_on_trunk[t] {
                origins.push(p[1] - root[1]);
                ratios.push(s.radii[c] / s.radii[t]);
            }
        }
    }
    origins.sort_by(f64::total_cmp);
    let mut groups: Vec<(f64, usize)> = Vec::new();
    for h in &origins {
        match groups.last_mut() {
            Some((low, count)) if h - *low <= WINDOW * height => *count += 1,
            _ => groups.push((*h, 1)),
        }
    }
    let whorls: Vec<usize> = groups.iter().map(|g| g.1).filter(|&c| c >= 3).collect();
    ratios.sort_by(f64::total_cmp);
    Metrics {
        whorls: whorls.len(),
        in_whorls: whorls.iter().sum::<usize>() as f64 / origins.len().max(1) as f64,
        deviation: deviation / height,
        joint_ratio: ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN),
        first_order: origins.len(),
        height,
    }
}

/// A conifer species: a valid tree glb whose skeleton passes the thresholds.
fn check_conifer(script: &str) {
    let dir = tempfile::tempdir().expect("tempdir");
    let (stats, glb) = run(script, dir.path(), &[]);
    let (doc, _, images) = gltf::import_slice(&glb).expect("a valid glb");
    assert_eq!(doc.meshes().count(), 2, "{script}: bark and needles");
    assert_eq!(images.len(), 6, "{script}: bark and leaf texture sets");
    let leaves = doc
        .materials()
        .find(|m| m.name() == Some("leaves"))
        .expect("a leaf material");
    assert_eq!(leaves.alpha_mode(), gltf::material::AlphaMode::Mask);
    assert!(stats["nodes"].as_u64().expect("nodes") > 500, "{stats}");
    assert!(stats["leaves"].as_u64().expect("leaves") > 1000, "{stats}");
    let m = metrics(&skeleton(&glb));
    eprintln!("{script}: {m:?} {stats}");
    assert!(m.whorls >= 8, "{script}: {m:?}");
    assert!(m.in_whorls >= 0.75, "{script}: {m:?}");
    assert!(m.deviation <= 0.05, "{script}: {m:?}");
    assert!(m.joint_ratio <= 0.45, "{script}: {m:?}");
}

#[test]
fn conifer_lua_is_a_pine_in_whorls() {
    check_conifer("scripts/species/conifer.lua");
}

#[test]
fn spruce_lua_is_a_spruce_in_whorls() {
    check_conifer("scripts/species/spruce.lua");
}

/// The metrics see what they measure: neither a colonized oak nor a tree grown by nutrient
/// transport passes them.
#[test]
fn the_metrics_fail_trees_that_are_not_conifers() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (_, glb) = run(
        "scripts/species/oak.lua",
        dir.path(),
        &["--set", "points=600"],
    );
    let m = metrics(&skeleton(&glb));
    assert!(m.whorls < 8 || m.in_whorls < 0.75, "oak: {m:?}");
    let (_, glb) = run("scripts/species/broadleaf.lua", dir.path(), &[]);
    let m = metrics(&skeleton(&glb));
    assert!(
        m.whorls < 8 || m.in_whorls < 0.75 || m.deviation > 0.05 || m.joint_ratio > 0.45,
        "broadleaf: {m:?}"
    );
}

/// Every skeleton a glb carries (one per bark mesh), as its positions.
fn all_skeleton_positions(glb: &[u8]) -> Vec<serde_json::Value> {
    let doc = gltf::Gltf::from_slice(glb).expect("glb");
    doc.meshes()
        .filter_map(|m| {
            let extras: serde_json::Value =
                serde_json::from_str(m.extras().as_ref()?.get()).expect("json");
            let s = extras["pge"]["skeleton"]["positions"].clone();
            (!s.is_null()).then_some(s)
        })
        .collect()
}

/// One step is one year: `--stages` writes ages of one tree, stage k the tree of
/// `--steps k`, a younger tree smaller.
#[test]
fn stages_are_years_of_one_tree() {
    let dir = tempfile::tempdir().expect("tempdir");
    let s = "scripts/species/spruce.lua";
    let (staged_stats, staged) = run(s, dir.path(), &["--stages", "6,12"]);
    let doc = gltf::Gltf::from_slice(&staged).expect("glb");
    let names: Vec<_> = doc.scenes().map(|s| s.name().map(String::from)).collect();
    assert_eq!(names, [Some("step 6".into()), Some("step 12".into())]);
    let stages = staged_stats["stages"].as_array().expect("stages");
    let nodes = |v: &serde_json::Value| v["nodes"].as_u64().expect("nodes");
    assert!(nodes(&stages[0]) < nodes(&stages[1]), "{staged_stats}");
    let in_stages = all_skeleton_positions(&staged);
    assert_eq!(in_stages.len(), 2);
    let (_, young) = run(s, dir.path(), &["--steps", "6"]);
    let (_, older) = run(s, dir.path(), &["--steps", "12"]);
    assert_eq!(all_skeleton_positions(&young), in_stages[..1]);
    assert_eq!(all_skeleton_positions(&older), in_stages[1..]);
    let (young, older) = (metrics(&skeleton(&young)), metrics(&skeleton(&older)));
    assert!(young.height < 0.6 * older.height, "{young:?} {older:?}");
    assert!(young.first_order < older.first_order, "{young:?} {older:?}");
}

/// A failing script: exit 1, one `FILE:LINE: message` line containing `needle`.
fn assert_error(source: &str, line: u32, needle: &str) {
    let dir = tempfile::tempdir().expect("tempdir");
    let script = dir.path().join("bad.lua");
    std::fs::write(&script, source).expect("write");
    let out = dir.path().join("bad.glb");
    let script_s = script.to_string_lossy().to_string();
    let o = pge(&["run", &script_s, "-o", &out.to_string_lossy(), "-q"]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{source}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.starts_with(&format!("{script_s}:{line}: ")),
        "located at line {line}: {err}"
    );
    assert!(err.contains(needle), "expected '{needle}' in: {err}");
    assert!(!out.exists());
}

#[test]
fn bad_conifer_options_fail_with_located_errors() {
    assert_error(
        "-- too many a whorl\nreturn pge.Conifer{ perWhorl = {2, 40} }\n",
        2,
        "pge.Conifer: perWhorl[2] must be an integer between 1 and 12, got 40",
    );
    assert_error(
        "return pge.Conifer{ crown = \"round\" }\n",
        1,
        "pge.Conifer: crown must be \"conic\", \"ogive\", \"columnar\" or a list",
    );
    assert_error(
        "return pge.Conifer{ crown = {1, -1} }\n",
        1,
        "pge.Conifer: crown[2] must be a number >= 0, got -1",
    );
    assert_error(
        "return pge.Conifer{ whorls = 3 }\n",
        1,
        "pge.Conifer: unknown option 'whorls'",
    );
    assert_error(
        "return pge.Conifer{ years = 100000 }\n",
        1,
        "pge.Conifer: years must be an integer between 1 and 1000",
    );
    assert_error(
        "return pge.Conifer{ height = 0/0 }\n",
        1,
        "pge.Conifer: height must be a number > 0, got NaN",
    );
    assert_error(
        "\nreturn pge.Conifer{ orders = 3, perWhorl = 12, segment = 0.01, maxNodes = 5000 }\n",
        2,
        "more than 5000 nodes (maxNodes)",
    );
}
