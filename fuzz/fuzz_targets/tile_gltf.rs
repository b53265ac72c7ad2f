//! The glTF importer as `pge merge` and `pge run --tile --variants` use it, on tampered
//! tiles: a glb opened with its indices checked, its buffers (the binary chunk) checked
//! against every view and accessor, then every mesh, instancing node and leaf count read
//! back; and the same bytes' JSON read as a shared variants description. Errors are
//! expected; a panic, an abort or a hang is a finding. Seeds: real tiles of the test forest.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pge_engine::import::{check_bounds, leaf_counts, open, read_instances, read_mesh};
use serde_json::Value;

fuzz_target!(|bytes: &[u8]| {
    if let Ok(glb) = gltf::binary::Glb::from_slice(bytes) {
        let _ = pge_engine::export::SharedVariants::parse(&glb.json);
    }
    let _ = pge_engine::export::SharedVariants::parse(bytes);
    let Ok(gltf) = open(bytes) else {
        return;
    };
    // Buffer 0 is the binary chunk; files beside the tile are not read here.
    let data: Vec<Option<&[u8]>> = gltf
        .document
        .buffers()
        .map(|b| (b.index() == 0).then_some(gltf.blob.as_deref()).flatten())
        .collect();
    if check_bounds(&gltf.document, &data).is_err() {
        return;
    }
    let json: Value = match gltf::binary::Glb::from_slice(bytes) {
        Ok(glb) => serde_json::from_slice(&glb.json).unwrap_or(Value::Null),
        Err(_) => serde_json::from_slice(bytes).unwrap_or(Value::Null),
    };
    let buffer = |b: gltf::Buffer| data.get(b.index()).copied().flatten();
    for mesh in gltf.document.meshes() {
        let _ = read_mesh(&mesh, &buffer, &json);
    }
    for node in gltf.document.nodes() {
        let at = |p: &str| {
            json.get("nodes")
                .and_then(|n| n.get(node.index()))
                .and_then(|n| n.pointer(p))
        };
        let placements = match at("/extensions/EXT_mesh_gpu_instancing/attributes") {
            Some(attributes) => match read_instances(&gltf, attributes, &buffer) {
                Ok(t) => t.len(),
                Err(_) => continue,
            },
            None => 1,
        };
        let _ = leaf_counts(at("/extras/pge/lod/leaves"), placements);
    }
});
