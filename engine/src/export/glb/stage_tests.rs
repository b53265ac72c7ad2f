//! Tests of stages as scenes and of empty models.

use super::extras::SkeletonText;
use super::*;
use crate::export::{Instancing, Prepared, write_glb_with};
use crate::geometry::{Mesh, Skeleton};
use glam::{Mat4, Vec3};
use serde_json::Map;

#[test]
fn stages_are_named_scenes_sharing_their_textures() {
    let one = super::tests::textured_model();
    let mut two = super::tests::textured_model();
    two.add_model(
        &super::tests::textured_model(),
        Mat4::from_translation(Vec3::X),
    );
    let stages = vec![("step 1".to_string(), one), ("step 2".to_string(), two)];
    let bytes = glb_stages_bytes(&stages, &ExportMeta::default()).expect("glb");
    let (doc, _, _) = gltf::import_slice(&bytes).expect("parses");
    let names: Vec<_> = doc.scenes().map(|s| s.name().map(str::to_string)).collect();
    assert_eq!(names, [Some("step 1".into()), Some("step 2".into())]);
    assert_eq!(doc.default_scene().map(|s| s.index()), Some(1));
    let nodes: Vec<usize> = doc.scenes().map(|s| s.nodes().count()).collect();
    assert_eq!(nodes[1], 2 * nodes[0]);
    assert_eq!(doc.images().count(), 1, "one texture for every stage");
    let extras = doc
        .as_json()
        .extras
        .as_ref()
        .expect("extras")
        .get()
        .to_string();
    assert!(
        extras.contains("\"stages\":[{\"name\":\"step 1\""),
        "{extras}"
    );
    assert!(glb_stages_bytes(&[], &ExportMeta::default()).is_err());
}

#[test]
fn an_empty_model_has_a_scene_with_one_empty_node() {
    let bytes = glb_bytes(&Model::new(), &ExportMeta::default()).expect("exports");
    let gltf = gltf::Gltf::from_slice(&bytes).expect("parses");
    let scene = gltf.default_scene().expect("a default scene");
    let nodes: Vec<_> = scene.nodes().collect();
    assert_eq!(nodes.len(), 1);
    assert_eq!(nodes[0].name(), Some("empty"));
    assert!(nodes[0].mesh().is_none());
    assert_eq!(gltf.meshes().count(), 0);
}

#[test]
fn every_scene_carries_the_runs_extras() {
    let meta = ExportMeta {
        seed: 11,
        params: vec![("h".into(), json!(3))],
    };
    let stages = vec![
        ("step 1".to_string(), super::tests::textured_model()),
        ("step 2".to_string(), super::tests::textured_model()),
    ];
    for bytes in [
        glb_bytes(&super::tests::textured_model(), &meta).expect("glb"),
        glb_stages_bytes(&stages, &meta).expect("glb"),
    ] {
        let gltf = gltf::Gltf::from_slice(&bytes).expect("parses");
        let root = gltf.document.as_json().extras.as_ref().expect("root").get();
        for scene in gltf.scenes() {
            let extras = scene.extras().as_ref().expect("scene extras").get();
            assert_eq!(extras, root);
            let value: JsonValue = serde_json::from_str(extras).expect("json");
            assert_eq!(value["pge"]["generator"], GENERATOR);
            assert_eq!(value["pge"]["seed"], 11);
            assert_eq!(value["pge"]["params"]["h"], 3);
            assert_eq!(value["pge"]["stats"]["triangles"], 2);
        }
    }
}

/// The mesh extras as a `serde_json::Value` map would write them (the skeleton first,
/// the mesh's extras after it, floats widened to f64): the streamed extras must match.
#[test]
fn streamed_mesh_extras_match_a_value_tree() {
    let mut s = Skeleton::new();
    let root = s.push(Vec3::new(0.1, -0.0, 1e-7), None, 0.3, 0);
    let a = s.push(Vec3::new(f32::NAN, 2.5, f32::INFINITY), Some(root), -0.0, 1);
    s.push(Vec3::new(1e30, -3.75, 0.2), Some(a), f32::NAN, 7);
    let mut mesh =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
    mesh.skeleton = Some(Arc::new(s.clone()));
    mesh.extras
        .insert("zz".into(), json!({ "a": [0.1, 2, "b"] }));
    mesh.extras.insert("aa".into(), json!(null));
    let expected = |mesh: &Mesh| {
        let mut pge = Map::new();
        if let Some(s) = &mesh.skeleton {
            let parents: Vec<i64> = s.parents.iter().map(|p| p.map_or(-1, i64::from)).collect();
            let positions: Vec<f32> = s.positions.iter().flat_map(|p| p.to_array()).collect();
            pge.insert(
                "skeleton".into(),
                json!({ "parents": parents, "positions": positions,
                    "radii": s.radii, "orders": s.orders }),
            );
        }
        for (k, v) in &mesh.extras {
            pge.insert(k.clone(), v.clone());
        }
        serde_json::to_string(&json!({ "pge": pge })).expect("json")
    };
    let streamed = |mesh: &Mesh| {
        let mut b = Builder::new();
        let mesh = Arc::new(mesh.clone());
        let (_, pge) = b.primitive(&mesh).expect("primitive");
        let mut skeletons = Vec::new();
        let marked = pge.extras(&mut skeletons).expect("extras").expect("some");
        let text = JsonText::new(
            marked.get().as_bytes().to_vec(),
            &skeletons,
            &Prepared::default(),
        )
        .expect("text");
        String::from_utf8(text.into_vec()).expect("utf-8")
    };
    assert_eq!(streamed(&mesh), expected(&mesh));
    assert!(streamed(&mesh).contains("[-1,0,1]"), "{}", streamed(&mesh));
    // A skeleton of many pieces, with floats that are not finite (written `null`).
    let mut big = mesh.clone();
    let n = 20_000;
    let mut s = Skeleton::new();
    for k in 0..n {
        let parent = (k > 0).then(|| (k - 1) / 2);
        let radius = if k == 9_999 {
            f32::NAN
        } else {
            1.0 / (k + 1) as f32
        };
        s.push(
            Vec3::new(k as f32 * 0.1, (k as f32).sqrt(), -1e-7 * k as f32),
            parent,
            radius,
            k % 5,
        );
    }
    s.positions[12_345].y = f32::INFINITY;
    big.skeleton = Some(Arc::new(s));
    big.extras.shift_remove("skeleton");
    assert_eq!(streamed(&big), expected(&big));
    assert!(streamed(&big).contains("null"));
    // A mesh extra named `skeleton` replaces the skeleton where it stands.
    mesh.extras.insert("skeleton".into(), json!(1));
    assert_eq!(streamed(&mesh), expected(&mesh));
    // No skeleton, no extras: nothing written.
    let empty =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
    let mut b = Builder::new();
    let empty = Arc::new(empty);
    assert!(b.primitive(&empty).expect("primitive").1.0.is_empty());
}

/// A skeleton's text prepared ahead of the export takes the place of its marker, one of
/// other numbers (a zero of the other sign) is left aside: the file is the same either way,
/// and a model that shares the mesh (a second tile) reuses the text.
#[test]
fn prepared_skeleton_texts_give_the_same_file() {
    let mut s = Skeleton::new();
    for k in 0..3_000u32 {
        let parent = k.checked_sub(1);
        s.push(Vec3::new(k as f32 * 0.1, 1.0, -0.5), parent, 0.0, k % 3);
    }
    let mut mesh =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
    mesh.skeleton = Some(Arc::new(s.clone()));
    let model = Model::from_mesh(mesh);
    let plain = glb_bytes(&model, &ExportMeta::default()).expect("glb");
    let mut other = s.clone();
    other.radii[2_999] = -0.0;
    let text = SkeletonText::new(&s).expect("formatted");
    assert!(text.made_from(&s));
    assert!(!text.made_from(&other));
    let write = |model: &Model, prepared: &Prepared| {
        let meta = ExportMeta::default();
        write_glb_with(
            model,
            prepared,
            &meta,
            Instancing::Gpu,
            || Ok(()),
            |(), f| f.to_vec(),
        )
        .expect("glb")
    };
    for from in [&s, &other] {
        let mut mesh = (*model.meshes[0]).clone();
        mesh.skeleton = Some(Arc::new(from.clone()));
        let prepared = Prepared::new(&Model::from_mesh(mesh)).expect("prepared");
        assert_eq!(prepared.len(), 1);
        assert!(
            write(&model, &prepared) == plain,
            "prepared from another skeleton: {}",
            from == &other
        );
    }
    // A second model placing the same mesh twice: nothing new to format.
    let mut prepared = Prepared::new(&model).expect("prepared");
    let mut twice = Model::new();
    twice.add_model(&model, Mat4::IDENTITY);
    twice.add_model(&model, Mat4::from_translation(Vec3::X));
    prepared.extend(&twice).expect("extended");
    assert_eq!(prepared.len(), 1);
    assert_eq!(
        write(&twice, &prepared),
        glb_bytes(&twice, &ExportMeta::default()).expect("glb")
    );
}
