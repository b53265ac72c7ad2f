//! Tests of the leaf counts of instance groups in the node extras.

use super::*;
use crate::geometry::{InstanceGroup, InstanceTransform, PlacementLeaves};
use glam::Vec3;

/// A group of three placements of one triangle, drawing 9, 0 and 4 leaves of a tree whose
/// coarsest level has 4.
fn budgeted() -> Model {
    let mesh =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
    let mut model = Model::new();
    model.meshes.push(Arc::new(mesh));
    let at = |x: f32| InstanceTransform {
        translation: [x, 0.0, 0.0],
        rotation: [0.0, 0.0, 0.0, 1.0],
        scale: 1.0,
    };
    model.groups.push(InstanceGroup {
        name: "tree/0".into(),
        meshes: vec![0],
        transforms: vec![at(1.0), at(2.0), at(3.0)],
        leaves: Some(PlacementLeaves {
            roots: 4,
            counts: vec![9, 0, 4],
        }),
    });
    model
}

fn node_extras(bytes: &[u8]) -> Vec<JsonValue> {
    let gltf = gltf::Gltf::from_slice(bytes).expect("parses");
    gltf.nodes()
        .map(|n| {
            n.extras().as_ref().map_or(JsonValue::Null, |e| {
                serde_json::from_str(e.get()).expect("json")
            })
        })
        .collect()
}

#[test]
fn an_instancing_node_carries_every_placements_leaves_and_level() {
    let bytes = glb_bytes(&budgeted(), &ExportMeta::default()).expect("exports");
    let extras = node_extras(&bytes);
    assert_eq!(extras.len(), 1);
    assert_eq!(
        extras[0],
        json!({ "pge": { "lod": { "leaves": [9, 0, 4], "level": [5, -1, 0] } } })
    );
}

#[test]
fn one_node_per_placement_carries_its_own_leaves_and_level() {
    let bytes =
        glb_bytes_with(&budgeted(), &ExportMeta::default(), Instancing::Nodes).expect("exports");
    let extras = node_extras(&bytes);
    assert_eq!(
        extras,
        vec![
            json!({ "pge": { "lod": { "leaves": 9, "level": 5 } } }),
            json!({ "pge": { "lod": { "leaves": 0, "level": -1 } } }),
            json!({ "pge": { "lod": { "leaves": 4, "level": 0 } } }),
        ]
    );
}

#[test]
fn counts_that_do_not_match_the_placements_are_an_error() {
    let mut model = budgeted();
    if let Some(leaves) = &mut model.groups[0].leaves {
        leaves.counts.pop();
    }
    let e = glb_bytes(&model, &ExportMeta::default()).expect_err("invalid");
    assert!(e.to_string().contains("group leaf counts"), "{e}");
}
