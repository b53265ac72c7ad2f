//! Every triangle a client gets has an area and comes once: the extruder's pointed tips
//! (`modellers/crystals.lua`) and the turtle's repeated strokes (`lsystems/hogeweg.lua`)
//! used to leave zero-area and duplicate triangles in the glb.

mod common;

use common::pge;

/// Per triangle of every mesh of `glb`: its corner positions.
fn triangles(glb: &[u8]) -> Vec<[[f32; 3]; 3]> {
    let (doc, buffers, _) = gltf::import_slice(glb).expect("the glb imports");
    let mut out = Vec::new();
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let p: Vec<[f32; 3]> = reader.read_positions().expect("positions").collect();
            let idx: Vec<u32> = reader.read_indices().expect("indices").into_u32().collect();
            out.extend(
                idx.chunks_exact(3)
                    .map(|t| [p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]]),
            );
        }
    }
    out
}

fn check(script: &str) -> usize {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out.glb");
    let out_s = out.to_string_lossy().to_string();
    let o = pge(&["run", script, "-o", &out_s, "-q", "--stats"]);
    assert!(
        o.status.success(),
        "{script}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let stats: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stats");
    let tris = triangles(&std::fs::read(&out).expect("glb"));
    assert!(!tris.is_empty(), "{script}: no triangles");
    assert_eq!(
        stats["triangles"].as_u64(),
        Some(tris.len() as u64),
        "{script}: --stats counts what the file holds"
    );
    let mut seen = std::collections::HashSet::new();
    for t in &tris {
        let [a, b, c] = t.map(glam::Vec3::from_array);
        let area2 = (b - a).cross(c - a).length();
        let longest = (b - a).length().max((c - b).length()).max((a - c).length());
        assert!(
            area2 > 1e-6 * longest * longest,
            "{script}: a zero-area triangle {t:?}"
        );
        // The same corners in the same turning order, whichever corner comes first.
        let keys = t.map(|p| p.map(|x| (x + 0.0).to_bits()));
        let first = (0..3).min_by_key(|&k| keys[k]).expect("three corners");
        let key = [keys[first], keys[(first + 1) % 3], keys[(first + 2) % 3]];
        assert!(seen.insert(key), "{script}: a duplicate triangle {t:?}");
    }
    tris.len()
}

#[test]
fn crystals_tips_have_no_zero_area_triangles() {
    check("scripts/modellers/crystals.lua");
}

#[test]
fn hogeweg_has_no_duplicate_triangles() {
    check("scripts/lsystems/hogeweg.lua");
}

#[test]
fn species_and_modellers_have_only_usable_triangles() {
    for script in [
        "scripts/species/oak.lua",
        "scripts/modellers/tower.lua",
        "scripts/modellers/sierpinski.lua",
        "scripts/lsystems/koch.lua",
    ] {
        check(script);
    }
}
