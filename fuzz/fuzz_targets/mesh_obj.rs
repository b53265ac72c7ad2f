//! The Wavefront OBJ reader of `pge.shape.mesh`, then the mesh it builds (welding, the
//! closedness check, inside and distance queries).
#![no_main]

use libfuzzer_sys::fuzz_target;
use pge_spacecol::TriMesh;

fuzz_target!(|text: &str| {
    let Ok((positions, triangles)) = TriMesh::parse_obj(text) else {
        return;
    };
    let Ok(mesh) = TriMesh::new("fuzz.obj", &positions, &triangles) else {
        return;
    };
    let _ = mesh.closed();
    let (lo, hi) = mesh.bounds();
    let mid = (lo + hi) * 0.5;
    let _ = mesh.contains(mid);
    let _ = mesh.signed_distance(mid);
});
