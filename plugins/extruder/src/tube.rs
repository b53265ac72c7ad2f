//! The mesh of what an [`Extruder`](crate::Extruder) swept: rings joined into tubes by quads,
//! caps, normals and texture coordinates.

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};
use pge_engine::geometry::{Material, Mesh};

use crate::triangulate::triangulate;

/// One cross-section placed along the path.
#[derive(Clone, Debug)]
pub(crate) struct Ring {
    /// World positions, one per shape point.
    pub(crate) points: Vec<Vec3>,
    /// The shape points after the shape matrix, projected on the local XZ plane.
    pub(crate) local: Vec<Vec2>,
    /// The path's +Y axis (world) at this ring: the direction caps face.
    pub(crate) axis: Vec3,
    /// Vertex colour.
    pub(crate) color: Vec4,
    /// Distance travelled along the path from the piece's first ring (world units).
    pub(crate) length: f32,
}

/// A run of rings joined by quads: one tube.
#[derive(Clone, Debug, Default)]
pub(crate) struct Piece {
    /// The rings, in path order.
    pub(crate) rings: Vec<Ring>,
    /// Reverse the side winding (a clockwise shape or a mirroring matrix).
    pub(crate) flip: bool,
}

/// How the tubes are meshed (from [`ExtruderOptions`](crate::ExtruderOptions)).
#[derive(Clone, Debug)]
pub(crate) struct TubeStyle {
    /// Smooth normals instead of one per quad.
    pub(crate) smooth: bool,
    /// Close both ends of every piece.
    pub(crate) caps: bool,
    /// The mesh's material.
    pub(crate) material: Arc<Material>,
    /// Keep the vertex colours (else they are dropped).
    pub(crate) colored: bool,
}

/// Builds the mesh of `pieces` (each of at least two rings) in `style`.
#[must_use]
pub(crate) fn build_mesh<'a, I>(pieces: I, style: &TubeStyle) -> Mesh
where
    I: Iterator<Item = &'a Piece> + Clone,
{
    let mut mesh = Mesh {
        name: "extrusion".into(),
        material: style.material.clone(),
        ..Mesh::default()
    };
    // Reserve the exact sizes of the formulas (caps at most).
    let (mut vertices, mut indices) = (0usize, 0usize);
    for piece in pieces.clone() {
        let (n, r) = (piece.rings[0].points.len(), piece.rings.len());
        vertices += if style.smooth {
            (n + 1) * r
        } else {
            4 * n * (r - 1)
        };
        indices += 6 * n * (r - 1);
        if style.caps {
            vertices += 2 * n;
            indices += 6 * (n - 2);
        }
    }
    mesh.positions.reserve_exact(vertices);
    mesh.normals.reserve_exact(vertices);
    mesh.uvs.reserve_exact(vertices);
    mesh.colors.reserve_exact(vertices);
    mesh.indices.reserve_exact(indices);
    for piece in pieces {
        build_piece(piece, style, &mut mesh);
    }
    if !style.colored {
        mesh.colors.clear();
    }
    mesh
}

fn build_piece(piece: &Piece, style: &TubeStyle, mesh: &mut Mesh) {
    let n = piece.rings[0].points.len();
    let perimeter0 = perimeter(&piece.rings[0].points).max(1e-6);
    if style.smooth {
        build_smooth(piece, n, perimeter0, mesh);
    } else {
        build_flat(piece, n, perimeter0, mesh);
    }
    if style.caps {
        let first = &piece.rings[0];
        let last = &piece.rings[piece.rings.len() - 1];
        build_cap(first, -first.axis, mesh);
        build_cap(last, last.axis, mesh);
    }
}

/// The mean of the points.
pub(crate) fn centroid(points: &[Vec3]) -> Vec3 {
    points.iter().copied().sum::<Vec3>() / points.len().max(1) as f32
}

fn perimeter(points: &[Vec3]) -> f32 {
    (0..points.len())
        .map(|i| points[i].distance(points[(i + 1) % points.len()]))
        .sum()
}

/// `u` of each shape point around the perimeter, with the seam point (`u = 1`) appended.
fn perimeter_us(local: &[Vec2]) -> Vec<f32> {
    let n = local.len();
    let mut us = Vec::with_capacity(n + 1);
    let mut acc = 0.0;
    us.push(0.0);
    for i in 0..n {
        acc += local[i].distance(local[(i + 1) % n]);
        us.push(acc);
    }
    let total = acc;
    if total > 0.0 {
        for u in &mut us {
            *u /= total;
        }
    } else {
        for (i, u) in us.iter_mut().enumerate() {
            *u = i as f32 / n as f32;
        }
    }
    us
}

/// The two triangles of quad `(a0, a1)` on one ring and `(b0, b1)` on the next.
fn quad(a0: u32, a1: u32, b0: u32, b1: u32, flip: bool) -> [u32; 6] {
    if flip {
        [a0, b1, a1, a0, b0, b1]
    } else {
        [a0, a1, b1, a0, b1, b0]
    }
}

fn build_smooth(piece: &Piece, n: usize, perimeter0: f32, mesh: &mut Mesh) {
    let r = piece.rings.len();
    // Area-weighted normals of the side quads, accumulated on the n x r grid.
    let mut acc = vec![Vec3::ZERO; n * r];
    for k in 0..r - 1 {
        let (a, b) = (&piece.rings[k].points, &piece.rings[k + 1].points);
        for j in 0..n {
            let j1 = (j + 1) % n;
            let mut normal = (a[j1] - a[j]).cross(b[j1] - a[j]) + (b[j1] - a[j]).cross(b[j] - a[j]);
            if piece.flip {
                normal = -normal;
            }
            for idx in [k * n + j, k * n + j1, (k + 1) * n + j, (k + 1) * n + j1] {
                acc[idx] += normal;
            }
        }
    }
    let base = mesh.positions.len() as u32;
    for (k, ring) in piece.rings.iter().enumerate() {
        let us = perimeter_us(&ring.local);
        let fallback = ring.axis;
        for (j, u) in us.iter().enumerate() {
            let jj = j % n;
            mesh.positions.push(ring.points[jj]);
            mesh.normals
                .push(acc[k * n + jj].try_normalize().unwrap_or(fallback));
            mesh.uvs.push(Vec2::new(*u, ring.length / perimeter0));
            mesh.colors.push(ring.color);
        }
    }
    let stride = (n + 1) as u32;
    for k in 0..(r - 1) as u32 {
        for j in 0..n as u32 {
            let a0 = base + k * stride + j;
            let b0 = a0 + stride;
            mesh.indices
                .extend(quad(a0, a0 + 1, b0, b0 + 1, piece.flip));
        }
    }
}

fn build_flat(piece: &Piece, n: usize, perimeter0: f32, mesh: &mut Mesh) {
    for k in 0..piece.rings.len() - 1 {
        let (ra, rb) = (&piece.rings[k], &piece.rings[k + 1]);
        let (ua, ub) = (perimeter_us(&ra.local), perimeter_us(&rb.local));
        for j in 0..n {
            let j1 = (j + 1) % n;
            let corners = [
                (
                    ra.points[j],
                    Vec2::new(ua[j], ra.length / perimeter0),
                    ra.color,
                ),
                (
                    ra.points[j1],
                    Vec2::new(ua[j + 1], ra.length / perimeter0),
                    ra.color,
                ),
                (
                    rb.points[j],
                    Vec2::new(ub[j], rb.length / perimeter0),
                    rb.color,
                ),
                (
                    rb.points[j1],
                    Vec2::new(ub[j + 1], rb.length / perimeter0),
                    rb.color,
                ),
            ];
            let [a0, a1, b0, b1] = [corners[0].0, corners[1].0, corners[2].0, corners[3].0];
            let mut normal = (a1 - a0).cross(b1 - a0) + (b1 - a0).cross(b0 - a0);
            if piece.flip {
                normal = -normal;
            }
            let normal = normal.try_normalize().unwrap_or_else(|| {
                // A degenerate quad (zero-length step): point away from the axis.
                let mid = (a0 + a1) * 0.5 - centroid(&ra.points);
                mid.try_normalize().unwrap_or(ra.axis)
            });
            let base = mesh.positions.len() as u32;
            for (p, uv, c) in corners {
                mesh.positions.push(p);
                mesh.normals.push(normal);
                mesh.uvs.push(uv);
                mesh.colors.push(c);
            }
            mesh.indices
                .extend(quad(base, base + 1, base + 2, base + 3, piece.flip));
        }
    }
}

/// A cap over `ring` facing `facing`; nothing when the ring has collapsed to a point.
fn build_cap(ring: &Ring, facing: Vec3, mesh: &mut Mesh) {
    let (lo, hi) = ring.local.iter().fold(
        (Vec2::splat(f32::MAX), Vec2::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let extent = (hi - lo).max_element();
    if extent <= 1e-9 || perimeter(&ring.points) <= 1e-9 {
        return;
    }
    let mut tris = triangulate(&ring.local);
    let total: Vec3 = tris
        .iter()
        .map(|t| {
            (ring.points[t[1]] - ring.points[t[0]]).cross(ring.points[t[2]] - ring.points[t[0]])
        })
        .sum();
    if total.dot(facing) < 0.0 {
        for t in &mut tris {
            t.swap(1, 2);
        }
    }
    let normal = if total.dot(facing) < 0.0 {
        -total
    } else {
        total
    };
    let normal = normal.try_normalize().unwrap_or(facing);
    let base = mesh.positions.len() as u32;
    for (p, l) in ring.points.iter().zip(&ring.local) {
        mesh.positions.push(*p);
        mesh.normals.push(normal);
        mesh.uvs.push((*l - lo) / extent);
        mesh.colors.push(ring.color);
    }
    for t in tris {
        mesh.indices.extend(t.map(|i| base + i as u32));
    }
}
