//! The engine's glTF/glb reader of `pge.shape.mesh` (`import::scene_triangles`), then the
//! mesh it builds.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pge_spacecol::TriMesh;

fuzz_target!(|bytes: &[u8]| {
    let Ok((positions, triangles)) = pge_engine::import::scene_triangles(bytes) else {
        return;
    };
    let Ok(mesh) = TriMesh::new("fuzz.glb", &positions, &triangles) else {
        return;
    };
    let _ = mesh.closed();
    let (lo, hi) = mesh.bounds();
    let mid = (lo + hi) * 0.5;
    let _ = mesh.contains(mid);
    let _ = mesh.signed_distance(mid);
});
