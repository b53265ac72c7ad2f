//! The mesher's own tangents against MikkTSpace's, which the glb carried before the mesher
//! wrote its own: the same directions (within the angles below), unit, across the normals,
//! with the same handedness.

use std::sync::Arc;

use glam::Vec3;
use pge_engine::geometry::{LeafPoint, Material, Mesh, Skeleton, Texture};
use pge_engine::math::{cos, sin};
use rand_mt::Mt64;

use crate::cylinders::bark_mesh;
use crate::leaves::append_leaf_quads;
use crate::options::{Flare, LeafOptions, MeshOptions};

/// The angle in degrees between each vertex's own tangent and MikkTSpace's, checking that
/// the own ones are one per vertex, unit, across the normal and of the same `w`.
fn against_mikktspace(mut mesh: Mesh) -> (Mesh, Vec<f32>) {
    assert_eq!(mesh.tangents.len(), mesh.positions.len(), "one per vertex");
    let normal = Texture::from_rgba("n", 1, 1, &[128, 128, 255, 255]).expect("png");
    mesh.material = Arc::new(Material {
        normal_texture: Some(Arc::new(normal)),
        ..Material::default()
    });
    mesh.validate().expect("valid");
    let own = mesh.tangents().expect("normal-mapped");
    for (i, (t, mine)) in own.iter().zip(&mesh.tangents).enumerate() {
        assert!(
            (*t - *mine).abs().max_element() < 1e-5,
            "vertex {i}: the mesh's own"
        );
    }
    let mut derived = mesh.clone();
    derived.tangents.clear();
    let mikk = derived.tangents().expect("normal-mapped");
    let angles = own
        .iter()
        .zip(&mikk)
        .zip(&mesh.normals)
        .enumerate()
        .map(|(i, ((t, m), n))| {
            let (t3, m3) = (t.truncate(), m.truncate());
            assert!((t3.length() - 1.0).abs() < 1e-5, "vertex {i}: {t}");
            assert!(t3.dot(*n).abs() < 1e-5, "vertex {i}: {t} along {n}");
            assert_eq!(t.w, m.w, "vertex {i}: {t} vs MikkTSpace's {m}");
            t3.angle_between(m3).to_degrees()
        })
        .collect();
    (mesh, angles)
}

#[test]
fn bark_tangents_run_around_the_rings_as_mikktspace_finds() {
    // A flared trunk bending twice, with a lateral, tapering, capped.
    let mut s = Skeleton::new();
    let r = s.push(Vec3::ZERO, None, 0.4, 0);
    let a = s.push(Vec3::new(0.0, 2.0, 0.0), Some(r), 0.3, 0);
    let b = s.push(Vec3::new(0.4, 3.5, 0.1), Some(a), 0.22, 0);
    s.push(Vec3::new(0.5, 5.0, -0.3), Some(b), 0.12, 0);
    s.push(Vec3::new(1.2, 3.0, 0.4), Some(a), 0.1, 1);
    let sides = 16;
    let options = MeshOptions {
        sides,
        caps: true,
        flare: Some(Flare::default()),
        ..MeshOptions::default()
    };
    let (mesh, angles) = against_mikktspace(bark_mesh(&s, &options));
    // In the flare (its first metre), where buttresses turn the ring sharply between
    // vertices (and the seam sits on a buttress's ridge), MikkTSpace's tangents (the
    // triangles' chords, mixed with those of the rings above and below) and the mesher's
    // (the mean of the ring's two chords at the vertex) part further.
    let last_u = mesh.uvs.iter().fold(0.0f32, |a, uv| a.max(uv.x));
    let seam = |i: usize| mesh.uvs[i].x == 0.0 || mesh.uvs[i].x == last_u;
    let flared = |i: usize| mesh.positions[i].y < Flare::default().height;
    let mut worst = [[0.0f32; 2]; 2];
    for (i, &angle) in angles.iter().enumerate() {
        let w = &mut worst[usize::from(flared(i))][usize::from(seam(i))];
        *w = w.max(angle);
    }
    eprintln!(
        "bark: worst degrees off MikkTSpace: {:.3} ({:.3} at the seam); in the flare {:.3} ({:.3} at the seam)",
        worst[0][0], worst[0][1], worst[1][0], worst[1][1]
    );
    assert!(worst[0][0] < 1.0 && worst[0][1] < 1.0, "{worst:?}");
    assert!(worst[1][0] < 20.0, "{worst:?}");
}

#[test]
fn leaf_card_tangents_run_along_their_side_as_mikktspace_finds() {
    let leaves: Vec<LeafPoint> = (0..40)
        .map(|k| {
            let t = k as f32 * 0.7;
            LeafPoint {
                node: 0,
                position: Vec3::new(cos(t), 0.1 * t, sin(t)),
                direction: Vec3::new(sin(t), 0.5 - (k % 3) as f32 * 0.5, -cos(t)),
                side: Vec3::new(1.0, cos(t), 0.3 * sin(t)),
                size: 0.1 + 0.01 * k as f32,
            }
        })
        .collect();
    let mut mesh = Mesh::default();
    append_leaf_quads(
        &leaves,
        &LeafOptions::default(),
        &mut Mt64::new(3),
        &mut mesh,
    );
    let (_, angles) = against_mikktspace(mesh);
    let worst = angles.iter().fold(0.0f32, |a, &b| a.max(b));
    eprintln!("leaf cards: worst {worst:.4} degrees off MikkTSpace");
    assert!(worst < 0.1, "{worst} degrees");
}
