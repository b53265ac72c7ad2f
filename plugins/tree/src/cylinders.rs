//! Skeleton to bark mesh: generalized cylinders after Bloomenthal ("Modeling the Mighty
//! Maple", 1985).
//!
//! The skeleton is cut into branches: a branch starts at a root, or at a fork for every child
//! but the one that continues the parent's branch (see [`main_children`]), and follows the
//! continuing children to a tip. Each branch is one tube: a ring of `sides` points (plus one
//! duplicated seam vertex, so `u` runs from 0 to 1 around it) at every node, each ring
//! oriented between the incoming and the outgoing direction so joints stay continuous, and
//! framed by parallel transport so tubes do not twist. Normals point from the ring centre to
//! the vertex; `v` grows with length along the branch (one unit per circumference, so the
//! texture keeps its aspect). A lateral branch starts with a ring of its own radius at the
//! fork node, inside its parent. Tips (and the base of each root) get a flat cap.

use std::f32::consts::TAU;

use glam::{Quat, Vec2, Vec3};
use pge_engine::geometry::{Mesh, Skeleton};

use crate::radii::main_children;

/// Appends the bark tubes of `skeleton` to `mesh` (positions, normals, uvs, indices; the
/// mesh's other attributes must be empty or are left short). Radii are used as they are.
///
/// `sides` is clamped to `3..=1024`. Every vertex is finite when the skeleton is; a branch
/// of zero length keeps the direction of the segment before it.
pub fn append_bark(skeleton: &Skeleton, sides: u32, caps: bool, mesh: &mut Mesh) {
    let sides = sides.clamp(3, 1024) as usize;
    let trig: Vec<(f32, f32)> = (0..=sides)
        .map(|k| {
            if k == sides {
                (1.0, 0.0)
            } else {
                let a = TAU * k as f32 / sides as f32;
                (a.cos(), a.sin())
            }
        })
        .collect();
    let children = skeleton.children();
    let main = main_children(skeleton, &children);
    let forks = children
        .iter()
        .map(|c| c.len().saturating_sub(1))
        .sum::<usize>();
    let rings = skeleton.len() + forks;
    let caps_count = if caps { skeleton.tips().len() * 2 } else { 0 };
    let verts = rings * (sides + 1) + caps_count * (sides + 1);
    mesh.positions.reserve(verts);
    mesh.normals.reserve(verts);
    mesh.uvs.reserve(verts);
    mesh.indices
        .reserve(rings * sides * 6 + caps_count * sides * 3);

    let mut builder = Tube {
        trig: &trig,
        sides,
        mesh,
        points: Vec::new(),
    };
    for i in 0..skeleton.len() {
        if skeleton.parents[i].is_none() {
            builder.points.clear();
            walk(skeleton, &main, i, &mut builder.points);
            builder.emit(caps, caps, Vec3::Y);
        }
        for &c in &children[i] {
            if Some(c) != main[i] {
                builder.points.clear();
                let attach = skeleton.positions[i];
                builder.points.push((attach, skeleton.radii[c as usize]));
                walk(skeleton, &main, c as usize, &mut builder.points);
                let incoming = skeleton.parents[i]
                    .and_then(|p| (attach - skeleton.positions[p as usize]).try_normalize())
                    .unwrap_or(Vec3::Y);
                builder.emit(false, caps, incoming);
            }
        }
    }
}

/// A bark mesh of `skeleton` alone: [`append_bark`] into an empty mesh named `bark`, with the
/// default material.
#[must_use]
pub fn bark_mesh(skeleton: &Skeleton, sides: u32, caps: bool) -> Mesh {
    let mut mesh = Mesh {
        name: "bark".into(),
        ..Mesh::default()
    };
    append_bark(skeleton, sides, caps, &mut mesh);
    mesh
}

/// Follows the continuing children from `start` to a tip, pushing positions and radii.
fn walk(skeleton: &Skeleton, main: &[Option<u32>], start: usize, out: &mut Vec<(Vec3, f32)>) {
    let mut cur = start;
    loop {
        out.push((skeleton.positions[cur], skeleton.radii[cur]));
        match main[cur] {
            Some(next) => cur = next as usize,
            None => break,
        }
    }
}

struct Tube<'a> {
    trig: &'a [(f32, f32)],
    sides: usize,
    mesh: &'a mut Mesh,
    points: Vec<(Vec3, f32)>,
}

impl Tube<'_> {
    /// Emits one tube through `self.points`; `fallback` is the direction used while the tube
    /// has no segment of non-zero length yet.
    fn emit(&mut self, base_cap: bool, tip_cap: bool, fallback: Vec3) {
        let pts = &self.points;
        if pts.len() < 2 {
            return;
        }
        // Segment directions, each falling back to the previous one.
        let first_dir = pts
            .windows(2)
            .find_map(|w| (w[1].0 - w[0].0).try_normalize())
            .unwrap_or(fallback);
        let mut seg = Vec::with_capacity(pts.len() - 1);
        let mut last = first_dir;
        for w in pts.windows(2) {
            last = (w[1].0 - w[0].0).try_normalize().unwrap_or(last);
            seg.push(last);
        }
        let ring_dir = |j: usize| -> Vec3 {
            if j == 0 {
                seg[0]
            } else if j == seg.len() {
                seg[j - 1]
            } else {
                (seg[j - 1] + seg[j]).try_normalize().unwrap_or(seg[j])
            }
        };
        let stride = (self.sides + 1) as u32;
        let mut dir = ring_dir(0);
        let mut side = dir.any_orthonormal_vector();
        let mut v = 0.0f32;
        if base_cap && pts[0].1 > 0.0 {
            self.cap(pts[0].0, pts[0].1, side, dir, -1.0, v);
        }
        let pts = &self.points;
        let first_index = self.mesh.positions.len() as u32;
        for j in 0..pts.len() {
            if j > 0 {
                let next_dir = ring_dir(j);
                side = transport(side, dir, next_dir);
                dir = next_dir;
                let len = pts[j].0.distance(pts[j - 1].0);
                let circumference = TAU * 0.5 * (pts[j].1 + pts[j - 1].1);
                v += len / circumference.max(0.25 * len).max(f32::MIN_POSITIVE);
            }
            let binormal = dir.cross(side);
            let (centre, radius) = pts[j];
            // At a bend the ring cuts the tube obliquely: stretch it along the bend by
            // 1/cos(half the turn) (Bloomenthal) so the joint keeps the branch's thickness.
            let (bend, stretch) = if j > 0 && j < seg.len() {
                let turn = (seg[j] - seg[j - 1]).try_normalize().unwrap_or(Vec3::ZERO);
                let cos_half = dir.dot(seg[j]).clamp(0.5, 1.0);
                (turn, 1.0 / cos_half - 1.0)
            } else {
                (Vec3::ZERO, 0.0)
            };
            for (k, &(c, s)) in self.trig.iter().enumerate() {
                let offset = side * c + binormal * s;
                let shape = offset + bend * (stretch * offset.dot(bend));
                self.mesh.positions.push(centre + shape * radius);
                self.mesh.normals.push(offset);
                self.mesh
                    .uvs
                    .push(Vec2::new(k as f32 / self.sides as f32, v));
            }
            if j > 0 {
                let a0 = first_index + (j as u32 - 1) * stride;
                let b0 = a0 + stride;
                for k in 0..self.sides as u32 {
                    let (a, b, c, d) = (a0 + k, a0 + k + 1, b0 + k + 1, b0 + k);
                    self.mesh.indices.extend_from_slice(&[a, b, c, a, c, d]);
                }
            }
        }
        let (centre, radius) = self.points[self.points.len() - 1];
        if tip_cap && radius > 0.0 {
            self.cap(centre, radius, side, dir, 1.0, v);
        }
    }

    /// A flat cap: a centre vertex and one ring of `sides` vertices facing `sign * dir`.
    fn cap(&mut self, centre: Vec3, radius: f32, side: Vec3, dir: Vec3, sign: f32, v: f32) {
        let binormal = dir.cross(side);
        let normal = dir * sign;
        let base = self.mesh.positions.len() as u32;
        self.mesh.positions.push(centre);
        self.mesh.normals.push(normal);
        self.mesh.uvs.push(Vec2::new(0.5, v));
        for &(c, s) in &self.trig[..self.sides] {
            self.mesh
                .positions
                .push(centre + (side * c + binormal * s) * radius);
            self.mesh.normals.push(normal);
            self.mesh.uvs.push(Vec2::new(0.5 + 0.5 * c, v + 0.5 * s));
        }
        let n = self.sides as u32;
        for k in 0..n {
            let (a, b) = (base + 1 + k, base + 1 + (k + 1) % n);
            if sign > 0.0 {
                self.mesh.indices.extend_from_slice(&[base, a, b]);
            } else {
                self.mesh.indices.extend_from_slice(&[base, b, a]);
            }
        }
    }
}

/// Carries `side` from a ring facing `from` to a ring facing `to` (parallel transport),
/// keeping it a unit vector perpendicular to `to`.
fn transport(side: Vec3, from: Vec3, to: Vec3) -> Vec3 {
    let rotated = Quat::from_rotation_arc(from, to) * side;
    (rotated - to * rotated.dot(to))
        .try_normalize()
        .unwrap_or_else(|| to.any_orthonormal_vector())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn approx(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    fn column() -> Skeleton {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.5, 0);
        s.push(Vec3::new(0.0, 2.0, 0.0), Some(r), 0.25, 0);
        s
    }

    #[test]
    fn a_single_segment_is_a_capped_cylinder() {
        let m = bark_mesh(&column(), 4, true);
        m.validate().expect("valid");
        // Two rings of 5 (seam duplicated) and two caps of 1 + 4.
        assert_eq!(m.positions.len(), 2 * 5 + 2 * 5);
        assert_eq!(m.triangle_count(), 4 * 2 + 2 * 4);
        // Ring vertices sit at their radius from the axis, normals point away from it.
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!((n.length() - 1.0).abs() < 1e-5);
            let radial = Vec3::new(p.x, 0.0, p.z);
            if n.y.abs() < 0.5 && radial.length() > 0.0 {
                let r = if p.y < 1.0 { 0.5 } else { 0.25 };
                assert!((radial.length() - r).abs() < 1e-5);
                assert!(approx(radial.normalize(), *n));
            }
        }
        // Every face points outward: the normal of each triangle agrees with its vertices'.
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
            let face = (m.positions[b] - m.positions[a]).cross(m.positions[c] - m.positions[a]);
            let avg = m.normals[a] + m.normals[b] + m.normals[c];
            assert!(face.dot(avg) > 0.0, "inward triangle {t:?}");
        }
    }

    #[test]
    fn the_seam_vertex_is_duplicated_with_u_0_and_1() {
        let m = bark_mesh(&column(), 6, false);
        assert_eq!(m.positions.len(), 2 * 7);
        for ring in 0..2 {
            let first = ring * 7;
            let last = first + 6;
            assert_eq!(m.positions[first], m.positions[last]);
            assert_eq!(m.uvs[first].x, 0.0);
            assert_eq!(m.uvs[last].x, 1.0);
            assert_eq!(m.uvs[first].y, m.uvs[last].y);
        }
        // v grows with length: 2 units over a mean circumference of 2*pi*0.375.
        assert!((m.uvs[7].y - 2.0 / (TAU * 0.375)).abs() < 1e-5);
        assert_eq!(m.uvs[0].y, 0.0);
    }

    #[test]
    fn joints_are_oriented_between_the_two_segments() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.1, 0);
        let a = s.push(Vec3::Y, Some(r), 0.1, 0);
        s.push(Vec3::new(1.0, 1.0, 0.0), Some(a), 0.1, 0);
        let m = bark_mesh(&s, 8, false);
        let bisector = Vec3::new(1.0, 1.0, 0.0).normalize();
        // The ring is an ellipse in the bisecting plane: 0.1 across the bend, stretched by
        // 1/cos(45 degrees) along it (Bloomenthal), so the joint keeps its thickness.
        let along = Vec3::new(1.0, -1.0, 0.0).normalize();
        for k in 0..9 {
            let p = m.positions[9 + k] - Vec3::Y;
            assert!(
                p.dot(bisector).abs() < 1e-5,
                "ring 1 is not in the bisecting plane"
            );
            let (a, b) = (p.dot(along) / (0.1 * 2f32.sqrt()), p.z / 0.1);
            assert!(
                (a * a + b * b - 1.0).abs() < 1e-4,
                "vertex {k} is off the ellipse"
            );
        }
    }

    #[test]
    fn forks_start_a_new_tube_inside_the_parent() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.2, 0);
        let a = s.push(Vec3::Y, Some(r), 0.2, 0);
        s.push(Vec3::new(0.0, 2.0, 0.0), Some(a), 0.15, 0);
        s.push(Vec3::new(1.0, 1.5, 0.0), Some(a), 0.1, 1);
        let m = bark_mesh(&s, 5, true);
        m.validate().expect("valid");
        // Main tube: 3 rings, lateral: 2 rings; caps: the root base and two tips.
        assert_eq!(m.positions.len(), 5 * 6 + 3 * 6);
        assert_eq!(m.triangle_count(), (2 + 1) * 10 + 3 * 5);
        // The lateral's first ring is centred on the fork node with the lateral's radius.
        let lateral_first = m.positions.len() - 6 - 2 * 6;
        let centre: Vec3 = m.positions[lateral_first..lateral_first + 5]
            .iter()
            .sum::<Vec3>()
            / 5.0;
        assert!(approx(centre, Vec3::Y));
        assert!((m.positions[lateral_first].distance(Vec3::Y) - 0.1).abs() < 1e-5);
    }

    /// Every edge, after welding equal positions, borders an even number of triangles.
    fn is_closed(m: &Mesh) -> bool {
        use std::collections::HashMap;
        let key = |p: Vec3| (p * 1e4).round().to_array().map(|c| c as i64);
        let mut ids: HashMap<[i64; 3], usize> = HashMap::new();
        let welded: Vec<usize> = m
            .positions
            .iter()
            .map(|p| {
                let n = ids.len();
                *ids.entry(key(*p)).or_insert(n)
            })
            .collect();
        let mut edges: HashMap<(usize, usize), u32> = HashMap::new();
        for t in m.indices.chunks_exact(3) {
            for k in 0..3 {
                let (a, b) = (welded[t[k] as usize], welded[t[(k + 1) % 3] as usize]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        edges.values().all(|c| c % 2 == 0)
    }

    #[test]
    fn a_capped_branch_is_closed() {
        let mut s = Skeleton::new();
        let mut prev = s.push(Vec3::ZERO, None, 0.3, 0);
        for (k, p) in [Vec3::Y, Vec3::new(0.5, 1.8, 0.1), Vec3::new(0.6, 2.9, -0.4)]
            .iter()
            .enumerate()
        {
            prev = s.push(*p, Some(prev), 0.25 - 0.05 * k as f32, 0);
        }
        let closed = bark_mesh(&s, 7, true);
        assert!(is_closed(&closed), "caps close the tube");
        let open = bark_mesh(&s, 7, false);
        assert!(!is_closed(&open), "without caps the ends are open");
    }

    #[test]
    fn degenerate_segments_stay_finite() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.1, 0);
        let a = s.push(Vec3::ZERO, Some(r), 0.1, 0);
        let b = s.push(Vec3::ZERO, Some(a), 0.0, 0);
        s.push(Vec3::X, Some(b), 0.0, 0);
        let m = bark_mesh(&s, 3, true);
        m.validate().expect("finite");
        assert!(m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-4));
    }
}
