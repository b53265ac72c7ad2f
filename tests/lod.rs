//! End-to-end tests of foliage levels of detail (docs/lua-api.md, docs/glb.md): a real tree with `lod` through
//! `pge run`, its leaf mesh and `extras.pge.lod` read back from the glb and checked against
//! what the construction promises (the invariant of every row, ranges inside V, the finest
//! level equal to the plain tree's leaves, every level a cut of the collapse forest, leaf
//! areas, the coarse crown's extent), sectors, the budget from Lua, and bad input.

// Coordinates are compared axis by axis across several arrays.
#![allow(clippy::needless_range_loop)]

mod common;

use common::pge;
use serde_json::Value;
use std::collections::HashMap;
use std::path::Path;

type Quad = [[f32; 3]; 4];

/// Runs `script` with `args`, writing `dir/NAME.glb`; returns the glb and stderr.
fn run(script: &str, dir: &Path, name: &str, args: &[&str]) -> (Vec<u8>, String) {
    let out = dir.join(format!("{name}.glb"));
    let out_s = out.to_string_lossy().to_string();
    let mut all = vec!["run", script, "-o", out_s.as_str(), "-q"];
    all.extend_from_slice(args);
    let o = pge(&all);
    let stderr = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(0), "{script}: {stderr}");
    (std::fs::read(&out).expect("glb written"), stderr)
}

/// The leaf mesh's quads (four vertices each, in vertex order: leaf `k` of V is vertices
/// `4k..4k+4`), the quads its index buffer draws, and its `extras.pge`.
fn leaf_mesh(glb: &[u8]) -> (Vec<Quad>, Vec<Quad>, Value) {
    let (doc, buffers, _) = gltf::import_slice(glb).expect("valid glb");
    let mesh = doc
        .meshes()
        .find(|m| m.name() == Some("leaves"))
        .expect("a leaf mesh");
    let extras: Value = mesh
        .extras()
        .as_ref()
        .map(|r| serde_json::from_str(r.get()).expect("json"))
        .unwrap_or(Value::Null);
    let prim = mesh.primitives().next().expect("a primitive");
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let positions: Vec<[f32; 3]> = reader.read_positions().expect("positions").collect();
    let indices: Vec<u32> = reader.read_indices().expect("indices").into_u32().collect();
    assert_eq!(indices.len() % 6, 0);
    assert_eq!(positions.len() % 4, 0);
    let quads = positions
        .chunks(4)
        .map(|q| [q[0], q[1], q[2], q[3]])
        .collect();
    let drawn = indices
        .chunks(6)
        .map(|t| {
            // Two triangles (q0 q1 q2) (q0 q2 q3) of one leaf's four vertices.
            let base = t[0] - t[0] % 4;
            assert_eq!(t, [base, base + 1, base + 2, base, base + 2, base + 3]);
            [t[0], t[1], t[2], t[5]].map(|i| positions[i as usize])
        })
        .collect();
    (
        quads,
        drawn,
        extras.get("pge").cloned().unwrap_or(Value::Null),
    )
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn area(q: &Quad) -> f32 {
    let (u, v) = (sub(q[1], q[0]), sub(q[3], q[0]));
    let c = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
}

fn bounds(quads: &[&Quad]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::MAX; 3];
    let mut hi = [f32::MIN; 3];
    for q in quads {
        for p in q.iter() {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    (lo, hi)
}

fn table(lod: &Value) -> Vec<[usize; 3]> {
    lod["table"]
        .as_array()
        .expect("table")
        .iter()
        .map(|r| {
            let r = r.as_array().expect("row");
            [0, 1, 2].map(|k| r[k].as_u64().expect("integer") as usize)
        })
        .collect()
}

/// The positions of V drawn at a level.
fn drawn(row: &[usize; 3]) -> Vec<usize> {
    let [a, b, c] = *row;
    (0..a).chain(b..b + c).collect()
}

#[test]
fn a_tree_with_lod_keeps_its_promises() {
    let dir = tempfile::tempdir().expect("tempdir");
    let script = "scripts/examples/lod.lua";
    let small = ["--set", "points=1200", "--set", "atlas=0"];
    let (glb, _) = run(script, dir.path(), "lod", &small);
    let mut plain_args = small.to_vec();
    plain_args.extend_from_slice(&["--set", "lod=0"]);
    let (plain_glb, _) = run(script, dir.path(), "plain", &plain_args);
    let (quads, indexed, pge_extras) = leaf_mesh(&glb);
    let (_, plain, plain_extras) = leaf_mesh(&plain_glb);
    assert!(plain_extras.get("lod").is_none());
    let lod = &pge_extras["lod"];
    let originals = lod["leaves"].as_u64().expect("leaves") as usize;
    let roots = lod["roots"].as_u64().expect("roots") as usize;
    assert_eq!(originals, plain.len());
    assert!(originals > 500, "{originals} leaves");
    // The chain goes down to a tenth of the leaves or fewer: a 10% level is in the table.
    assert!(roots * 10 <= originals, "{roots} roots of {originals}");
    let m = quads.len();
    assert_eq!(m, 2 * originals - roots, "|M| = |O| + collapses");
    let rows = table(lod);
    assert_eq!(rows.len(), originals - roots + 1);

    // Every row: a + c = |R| + i, both ranges inside V, the first inside the originals.
    for (i, &[a, b, c]) in rows.iter().enumerate() {
        assert_eq!(a + c, roots + i, "row {i}");
        assert!(
            a <= originals && b >= originals && b + c <= m,
            "row {i}: {a} {b} {c}"
        );
    }
    // The finest level draws exactly the original leaves, the coarsest exactly R.
    assert_eq!(rows[rows.len() - 1], [originals, originals, 0]);
    let key = |q: &Quad| q.map(|p| p.map(f32::to_bits));
    let mut finest: Vec<_> = quads[..originals].iter().map(key).collect();
    let mut expected: Vec<_> = plain.iter().map(key).collect();
    finest.sort_unstable();
    expected.sort_unstable();
    assert_eq!(
        finest, expected,
        "the finest level is the plain tree's leaves"
    );
    // An ordinary viewer draws the index buffer: exactly the finest level, V[0..|O|).
    assert_eq!(indexed, quads[..originals].to_vec());
    assert_eq!(drawn(&rows[0]).len(), roots);

    // Consecutive levels differ by one split: one leaf out, its two children in.
    let mut parent: HashMap<usize, usize> = HashMap::new();
    for i in 0..rows.len() - 1 {
        let now: std::collections::HashSet<usize> = drawn(&rows[i]).into_iter().collect();
        let next: std::collections::HashSet<usize> = drawn(&rows[i + 1]).into_iter().collect();
        let gone: Vec<usize> = now.difference(&next).copied().collect();
        let came: Vec<usize> = next.difference(&now).copied().collect();
        assert_eq!((gone.len(), came.len()), (1, 2), "level {i} to {}", i + 1);
        for c in &came {
            assert!(parent.insert(*c, gone[0]).is_none(), "a leaf made twice");
        }
        // The promised area: between the summed children's and their bounding quad's on
        // the new leaf's axes.
        let parent_quad = &quads[gone[0]];
        let (u, v) = (
            sub(parent_quad[1], parent_quad[0]),
            sub(parent_quad[3], parent_quad[0]),
        );
        let unit = |w: [f32; 3]| {
            let l = dot(w, w).sqrt();
            w.map(|x| x / l)
        };
        let (u, v) = (unit(u), unit(v));
        let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
        for p in quads[came[0]].iter().chain(quads[came[1]].iter()) {
            let d = sub(*p, parent_quad[0]);
            for (k, axis) in [u, v].into_iter().enumerate() {
                lo[k] = lo[k].min(dot(d, axis));
                hi[k] = hi[k].max(dot(d, axis));
            }
        }
        let boxed = (hi[0] - lo[0]) * (hi[1] - lo[1]);
        let sum = area(&quads[came[0]]) + area(&quads[came[1]]);
        let a = area(parent_quad);
        assert!(
            a >= sum.min(boxed) * 0.99 && a <= sum.max(boxed) * 1.01,
            "split at level {i}: {a} from {sum} summed, {boxed} bounding"
        );
    }
    // Each level is a cut of the collapse forest: every original leaf is represented once.
    let step = (rows.len() / 25).max(1);
    for i in (0..rows.len()).step_by(step).chain([rows.len() - 1]) {
        let level: std::collections::HashSet<usize> = drawn(&rows[i]).into_iter().collect();
        for leaf in 0..originals {
            let mut n = leaf;
            let mut hits = usize::from(level.contains(&n));
            while let Some(&p) = parent.get(&n) {
                n = p;
                hits += usize::from(level.contains(&n));
            }
            assert_eq!(hits, 1, "leaf {leaf} at level {i}");
        }
    }
    // The coarsest level still has the crown's extent.
    let all: Vec<&Quad> = quads[..originals].iter().collect();
    let coarse: Vec<&Quad> = drawn(&rows[0]).into_iter().map(|k| &quads[k]).collect();
    let (lo, hi) = bounds(&all);
    let (clo, chi) = bounds(&coarse);
    for k in 0..3 {
        let extent = hi[k] - lo[k];
        assert!(
            (clo[k] - lo[k]).abs() < 0.2 * extent && (chi[k] - hi[k]).abs() < 0.2 * extent,
            "axis {k}: crown {}..{}, coarsest {}..{}",
            lo[k],
            hi[k],
            clo[k],
            chi[k]
        );
    }
    // Deterministic, bytes included.
    let (again, _) = run(script, dir.path(), "again", &small);
    assert_eq!(again, glb);
}

#[test]
fn sectors_and_the_atlas_are_written() {
    let dir = tempfile::tempdir().expect("tempdir");
    let args = [
        "--set",
        "points=600",
        "--set",
        "sectors=4",
        "--set",
        "atlas=1",
    ];
    let (glb, _) = run("scripts/examples/lod.lua", dir.path(), "sectors", &args);
    let (quads, indexed, extras) = leaf_mesh(&glb);
    let lod = &extras["lod"];
    let sectors = lod["sectors"].as_array().expect("sectors");
    assert_eq!(sectors.len(), 4);
    let mut offset = 0;
    let (mut leaves, mut roots) = (0, 0);
    for s in sectors {
        assert_eq!(s["offset"].as_u64(), Some(offset as u64));
        let (o, r) = (
            s["leaves"].as_u64().expect("leaves") as usize,
            s["roots"].as_u64().expect("roots") as usize,
        );
        let rows = table(s);
        for (i, &[a, b, c]) in rows.iter().enumerate() {
            assert_eq!(a + c, r + i);
            assert!(b + c <= 2 * o - r);
        }
        offset += 2 * o - r;
        leaves += o;
        roots += r;
    }
    assert_eq!(offset, quads.len());
    // The index buffer draws each sector's original leaves, sector after sector.
    let finest: Vec<Quad> = sectors
        .iter()
        .flat_map(|s| {
            let at = s["offset"].as_u64().expect("offset") as usize;
            quads[at..at + s["leaves"].as_u64().expect("leaves") as usize].to_vec()
        })
        .collect();
    assert_eq!(indexed, finest);
    assert_eq!(lod["leaves"].as_u64(), Some(leaves as u64));
    assert_eq!(lod["roots"].as_u64(), Some(roots as u64));
    let (doc, _, images) = gltf::import_slice(&glb).expect("glb");
    let leaf_image = doc
        .meshes()
        .find(|m| m.name() == Some("leaves"))
        .and_then(|m| m.primitives().next())
        .and_then(|p| p.material().pbr_metallic_roughness().base_color_texture())
        .map(|t| t.texture().source().index())
        .expect("a leaf texture");
    assert_eq!(
        (images[leaf_image].width, images[leaf_image].height),
        (pge_lod::ATLAS_SIZE, pge_lod::ATLAS_SIZE),
        "the atlas is the leaf texture"
    );
}

/// Pixel `i` of a decoded glTF image as RGBA (RGB images opaque).
fn rgba(image: &gltf::image::Data, i: usize) -> [u8; 4] {
    match image.format {
        gltf::image::Format::R8G8B8A8 => {
            let p = &image.pixels[4 * i..4 * i + 4];
            [p[0], p[1], p[2], p[3]]
        }
        gltf::image::Format::R8G8B8 => {
            let p = &image.pixels[3 * i..3 * i + 3];
            [p[0], p[1], p[2], 255]
        }
        other => panic!("unexpected image format {other:?}"),
    }
}

#[test]
fn the_atlas_keeps_the_leaf_normal_and_roughness_maps() {
    let dir = tempfile::tempdir().expect("tempdir");
    let args = ["--set", "points=600", "--set", "atlas=1"];
    let (glb, _) = run("scripts/examples/lod.lua", dir.path(), "maps", &args);
    let (doc, _, images) = gltf::import_slice(&glb).expect("glb");
    let material = doc
        .meshes()
        .find(|m| m.name() == Some("leaves"))
        .and_then(|m| m.primitives().next())
        .map(|p| p.material())
        .expect("a leaf material");
    let pbr = material.pbr_metallic_roughness();
    let image = |t: Option<gltf::Texture>, what: &str| {
        let index = t.unwrap_or_else(|| panic!("no {what}")).source().index();
        (index, &images[index])
    };
    let (ci, color) = image(pbr.base_color_texture().map(|t| t.texture()), "base colour");
    let (ni, normal) = image(
        material.normal_texture().map(|t| t.texture()),
        "normalTexture",
    );
    let (ri, rough) = image(
        pbr.metallic_roughness_texture().map(|t| t.texture()),
        "metallicRoughnessTexture",
    );
    assert!(ci != ni && ni != ri && ci != ri, "three images");
    for img in [color, normal, rough] {
        assert_eq!(
            (img.width, img.height),
            (pge_lod::ATLAS_SIZE, pge_lod::ATLAS_SIZE),
            "every map is an atlas"
        );
    }
    // The three line up: between leaves (the colour's alpha below half) the flat normal and
    // one roughness; on the leaves, the leaf's normals and roughness.
    let pixels = (color.width * color.height) as usize;
    let fill = rgba(rough, 0);
    let (mut covered, mut tilted, mut varied) = (0, 0, 0);
    for i in 0..pixels {
        let (n, r) = (rgba(normal, i), rgba(rough, i));
        if rgba(color, i)[3] < 128 {
            assert_eq!(&n[..3], &[128, 128, 255], "pixel {i}: flat between leaves");
            assert_eq!(r, fill, "pixel {i}: one roughness between leaves");
        } else {
            covered += 1;
            tilted += usize::from(n[..3] != [128, 128, 255]);
            varied += usize::from(r != fill);
        }
    }
    assert!(
        covered > pixels / 8,
        "{covered} of {pixels} pixels show leaves"
    );
    assert!(
        tilted > covered / 4,
        "{tilted} of {covered} leaf pixels tilted"
    );
    assert!(
        varied > covered / 4,
        "{varied} of {covered} leaf pixels rough"
    );
    let path = dir.path().join("maps.glb");
    let (passed, report) = common::run_validator(&[path]);
    assert!(passed, "the glTF validator found errors:\n{report}");
    assert!(report.contains(": 0 errors"), "{report}");
}

#[test]
fn the_budget_runs_from_a_script() {
    let dir = tempfile::tempdir().expect("tempdir");
    run("tests/scripts/lod/budget.lua", dir.path(), "budget", &[]);
}

#[test]
fn lod_without_leaves_is_a_warning() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (glb, stderr) = run("tests/scripts/lod/no_leaves.lua", dir.path(), "bare", &[]);
    assert!(
        stderr.contains("no_leaves.lua:2: warning: lod: the tree has no leaves"),
        "{stderr}"
    );
    let (doc, _, _) = gltf::import_slice(&glb).expect("glb");
    assert!(doc.meshes().all(|m| m.name() != Some("leaves")));
}

#[test]
fn bad_lod_input_is_a_located_error() {
    for (script, line, message) in [
        ("unknown_key.lua", 2, "unknown option 'lod.sector'"),
        (
            "sectors_range.lua",
            2,
            "lod.sectors' must be an integer between 1 and 64, got 65",
        ),
        (
            "budget_nan.lua",
            2,
            "pge.lod.budget: distances[2] must be a number >= 0, got NaN",
        ),
        (
            "sectors_zero.lua",
            2,
            "lod.sectors' must be an integer between 1 and 64, got 0",
        ),
        (
            "budget_negative.lua",
            2,
            "pge.lod.budget: distances[3] must be a number >= 0, got -2",
        ),
        (
            "budget_near.lua",
            2,
            "pge.lod.budget: near must be a number >= 0, got -1",
        ),
        (
            "budget_order.lua",
            2,
            "pge.lod.budget: near must be at most far, got near = 100 and far = 10",
        ),
    ] {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("out.glb");
        let path = format!("tests/scripts/lod/{script}");
        let o = pge(&["run", &path, "-o", &out.to_string_lossy(), "-q"]);
        assert!(!out.exists(), "{script}: nothing written");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{script}: {stderr}");
        assert!(
            stderr.contains(&format!("{script}:{line}: ")) && stderr.contains(message),
            "{script}: {stderr}"
        );
    }
}

#[test]
fn a_preview_level_outside_the_range_is_a_usage_error() {
    for bad in ["0", "1.5", "NaN", "x"] {
        let o = pge(&["preview", "scripts/examples/lod.lua", "--lod-level", bad]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{bad}: {stderr}");
        assert!(
            stderr.contains("--lod-level") && stderr.contains("between 0.01 and 1"),
            "{bad}: {stderr}"
        );
    }
}
