//! The sky dome written around a model with an environment.

use crate::math;
use glam::Vec3;

use crate::geometry::Mesh;

/// The name of the glTF extension the sky dome's material uses.
pub const UNLIT: &str = "KHR_materials_unlit";

/// The sky dome's radius for a model smaller than a few metres.
pub(super) const SKY_MIN_RADIUS: f32 = 50.0;
/// Columns of the sky dome's mesh.
pub(super) const SKY_SEGMENTS: u32 = 48;
/// Rows of the sky dome's mesh.
pub(super) const SKY_RINGS: u32 = 24;

/// A unit sphere seen from inside: `segments` columns and `rings` rows, texture coordinates
/// of an equirectangular image (v = 0 straight up; u = 0.5 along -Z, u = 0.75 along +X),
/// inward normals and counter-clockwise triangles as seen from the centre. The seam column
/// is doubled; each pole is one triangle per column (no zero-area triangles).
pub(super) fn sky_sphere(segments: u32, rings: u32) -> Mesh {
    use std::f32::consts::{PI, TAU};
    let mut mesh = Mesh {
        name: "sky".into(),
        ..Mesh::default()
    };
    for r in 0..=rings {
        let v = r as f32 / rings as f32;
        let polar = v * PI;
        for k in 0..=segments {
            let u = k as f32 / segments as f32;
            let azimuth = (u - 0.5) * TAU;
            let dir = Vec3::new(
                math::sin(polar) * math::sin(azimuth),
                math::cos(polar),
                -math::sin(polar) * math::cos(azimuth),
            );
            mesh.positions.push(dir);
            mesh.normals.push(-dir);
            mesh.uvs.push(glam::Vec2::new(u, v));
        }
    }
    let at = |r: u32, k: u32| r * (segments + 1) + k;
    for r in 0..rings {
        for k in 0..segments {
            let (a, b, c, d) = (at(r, k), at(r, k + 1), at(r + 1, k), at(r + 1, k + 1));
            // Seen from the centre, u grows to the right and v downwards.
            if r > 0 {
                mesh.indices.extend([a, c, b]);
            }
            if r + 1 < rings {
                mesh.indices.extend([b, c, d]);
            }
        }
    }
    mesh
}
