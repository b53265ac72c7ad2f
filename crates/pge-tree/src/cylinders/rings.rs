//! One tube's rings written into the mesh: each ring oriented between the incoming and the
//! outgoing direction and framed as [`frames`](super::frames) found, its UVs a whole number
//! of tiles around, and the flat caps.

use std::f32::consts::TAU;

use glam::{Vec2, Vec3, Vec4};
use pge_engine::geometry::{DegenerateTest, Mesh};

use super::TubeSpec;
use super::flare::flared;
use super::frames::{Frame, segments};

/// Where a tube is written: the next vertex's index in the mesh, its vertices and its
/// triangles.
pub(super) trait Sink {
    /// The mesh index of the next vertex.
    fn next_index(&self) -> u32;

    /// Writes a vertex; `tangent` as glTF's `TANGENT` (see `Mesh::tangents`).
    fn vertex(&mut self, position: Vec3, normal: Vec3, tangent: Vec4, uv: Vec2);

    /// Writes triangles (three indices each).
    fn triangles<const N: usize>(&mut self, indices: [u32; N]);
}

/// The mesh's own arrays, appended to (so not zero-filled first).
pub(super) struct Appended<'a>(pub(super) &'a mut Mesh);

impl Sink for Appended<'_> {
    fn next_index(&self) -> u32 {
        self.0.positions.len() as u32
    }

    #[inline]
    fn vertex(&mut self, position: Vec3, normal: Vec3, tangent: Vec4, uv: Vec2) {
        self.0.positions.push(position);
        self.0.normals.push(normal);
        self.0.tangents.push(tangent);
        self.0.uvs.push(uv);
    }

    #[inline]
    fn triangles<const N: usize>(&mut self, indices: [u32; N]) {
        self.0.indices.extend_from_slice(&indices);
    }
}

/// Slices of the mesh's arrays of one tube's own, for tubes written in parallel.
pub(super) struct Slices<'a> {
    pub(super) positions: &'a mut [Vec3],
    pub(super) normals: &'a mut [Vec3],
    pub(super) tangents: &'a mut [Vec4],
    pub(super) uvs: &'a mut [Vec2],
    pub(super) indices: &'a mut [u32],
    /// The mesh index of the slices' first vertex.
    pub(super) first: u32,
    pub(super) vertices: usize,
    pub(super) indices_written: usize,
}

impl Sink for Slices<'_> {
    fn next_index(&self) -> u32 {
        self.first + self.vertices as u32
    }

    #[inline]
    fn vertex(&mut self, position: Vec3, normal: Vec3, tangent: Vec4, uv: Vec2) {
        self.positions[self.vertices] = position;
        self.normals[self.vertices] = normal;
        self.tangents[self.vertices] = tangent;
        self.uvs[self.vertices] = uv;
        self.vertices += 1;
    }

    #[inline]
    fn triangles<const N: usize>(&mut self, indices: [u32; N]) {
        let at = self.indices_written;
        self.indices[at..at + N].copy_from_slice(&indices);
        self.indices_written += N;
    }
}

/// What the bark's tubes are checked by as they are written, to show the mesh usable by
/// construction (see `Mesh::distinct_positions`): every triangle through a
/// [`DegenerateTest`], and each vertex made at the place of another by construction (a
/// ring's seam vertex, a cap's copy of a ring vertex) with that other, in increasing order.
#[derive(Default)]
pub(super) struct Checks {
    pub(super) test: DegenerateTest,
    pub(super) twins: Vec<(u32, u32)>,
}

/// A tube's scratch space: its segments' directions, the last two rings' positions by
/// coordinate (for [`DegenerateTest::strip`]), a ring's vertices and a cap's ring.
#[derive(Default)]
pub(super) struct Scratch {
    seg: Vec<Vec3>,
    below: [Vec<f32>; 3],
    above: [Vec<f32>; 3],
    cap: Vec<Vec3>,
    /// A ring's positions and normals.
    ring: Vec<(Vec3, Vec3)>,
}

/// What every tube shares: the ring's cosines and sines and how the texture wraps.
pub(super) struct Shape<'a> {
    pub(super) trig: &'a [(f32, f32)],
    pub(super) sides: usize,
    /// Texture tiles around every ring.
    pub(super) tiles: f32,
}

impl Shape<'_> {
    /// Emits one tube through its rings `pts` (see [`tube_points`](super::tube_points)),
    /// framed by `frames` (one a ring, see [`frames`](super::frames::frames)), into `out`,
    /// checked by `checks` when given.
    pub(super) fn emit(
        &self,
        tube: &TubeSpec,
        pts: &[(Vec3, f32, f32)],
        frames: &[Frame],
        scratch: &mut Scratch,
        out: &mut impl Sink,
        mut checks: Option<&mut Checks>,
    ) {
        if pts.len() < 2 || frames.len() != pts.len() {
            return;
        }
        let flare = tube.flare;
        let Scratch {
            seg,
            below,
            above,
            cap: cap_ring,
            ring,
        } = scratch;
        segments(pts, tube.fallback, seg);
        let stride = (self.sides + 1) as u32;
        let first = frames[0];
        if tube.base_cap && pts[0].1 > 0.0 && flare.is_none() {
            // The first ring follows the cap.
            let ring = out.next_index() + 1 + self.sides as u32;
            let cap = (pts[0].0, pts[0].1, ring);
            self.cap(
                out,
                cap,
                (first.side, first.dir),
                -1.0,
                first.v,
                cap_ring,
                checks.as_deref_mut(),
            );
        }
        let first_index = out.next_index();
        for j in 0..pts.len() {
            let Frame { dir, side, v } = frames[j];
            let binormal = dir.cross(side);
            let (centre, radius, travelled) = pts[j];
            // At a bend the ring cuts the tube obliquely: stretch it along the bend by
            // 1/cos(half the turn) (Bloomenthal) so the joint keeps the branch's thickness.
            let (bend, stretch) = if j > 0 && j < seg.len() {
                let turn = (seg[j] - seg[j - 1]).try_normalize().unwrap_or(Vec3::ZERO);
                let cos_half = dir.dot(seg[j]).clamp(0.5, 1.0);
                (turn, 1.0 / cos_half - 1.0)
            } else {
                (Vec3::ZERO, 0.0)
            };
            std::mem::swap(below, above);
            above.iter_mut().for_each(Vec::clear);
            // The ring first, then its vertices: a vertex's tangent reads its neighbours.
            ring.clear();
            for (k, &(c, s)) in self.trig.iter().enumerate() {
                let offset = side * c + binormal * s;
                let shape = offset + bend * (stretch * offset.dot(bend));
                let (widen, normal) = match flare {
                    Some(f) if travelled < f.height => flared(
                        f,
                        travelled,
                        k as f32 / self.sides as f32,
                        radius,
                        offset,
                        binormal * c - side * s,
                        dir,
                    ),
                    _ => (1.0, offset),
                };
                ring.push((centre + shape * radius * widen, normal));
            }
            for (k, &(position, normal)) in ring.iter().enumerate() {
                // The tangent: along the ring (where `u` grows; `v` is the ring's own), the
                // mean of the directions of its two chords at the vertex (those on either
                // side of the seam for the seam's two copies, so the seam does not show),
                // across the normal. `v` grows along `dir`, which `cross(normal, tangent)`
                // points along: w = +1.
                let before = ring[if k == 0 { self.sides - 1 } else { k - 1 }].0;
                let after = ring[if k == self.sides { 1 } else { k + 1 }].0;
                let along = (position - before).normalize_or_zero()
                    + (after - position).normalize_or_zero();
                let (c, s) = self.trig[k];
                let tangent = (along - normal * along.dot(normal))
                    .try_normalize()
                    .unwrap_or(binormal * c - side * s);
                out.vertex(
                    position,
                    normal,
                    tangent.extend(1.0),
                    Vec2::new(self.tiles * k as f32 / self.sides as f32, v),
                );
                if checks.is_some() {
                    for (axis, coordinates) in above.iter_mut().enumerate() {
                        coordinates.push(position[axis]);
                    }
                }
            }
            if let Some(checks) = checks.as_deref_mut() {
                let ring = first_index + j as u32 * stride;
                checks.twins.push((ring + self.sides as u32, ring));
                if j > 0 {
                    let [x, y, z] = &*below;
                    let [ax, ay, az] = &*above;
                    checks.test.strip([x, y, z], [ax, ay, az]);
                }
            }
            if j > 0 {
                let a0 = first_index + (j as u32 - 1) * stride;
                let b0 = a0 + stride;
                for k in 0..self.sides as u32 {
                    let (a, b, c, d) = (a0 + k, a0 + k + 1, b0 + k + 1, b0 + k);
                    out.triangles([a, b, c, a, c, d]);
                }
            }
        }
        let (centre, radius, _) = pts[pts.len() - 1];
        if tube.tip_cap && radius > 0.0 {
            let ring = first_index + (pts.len() as u32 - 1) * stride;
            let cap = (centre, radius, ring);
            let last = frames[frames.len() - 1];
            self.cap(
                out,
                cap,
                (last.side, last.dir),
                1.0,
                last.v,
                cap_ring,
                checks,
            );
        }
    }

    /// A flat cap of the ring at `centre` with `radius` (whose first vertex is `ring`),
    /// framed by `side` and `dir`: a centre vertex and one ring of `sides` vertices facing
    /// `sign * dir`, checked by `checks` when given (each ring vertex a twin of the ring's
    /// vertex it copies). `positions` is scratch space.
    #[allow(clippy::too_many_arguments)]
    fn cap(
        &self,
        out: &mut impl Sink,
        (centre, radius, ring): (Vec3, f32, u32),
        (side, dir): (Vec3, Vec3),
        sign: f32,
        v: f32,
        positions: &mut Vec<Vec3>,
        checks: Option<&mut Checks>,
    ) {
        let binormal = dir.cross(side);
        let normal = dir * sign;
        let base = out.next_index();
        // The ring's texel size: its circumference over the tiles.
        let r = self.tiles / TAU;
        // `u` grows along `side` and `v` along `binormal`: `cross(normal, side)` is
        // `sign * binormal`, so w = sign.
        let tangent = side.extend(sign);
        out.vertex(centre, normal, tangent, Vec2::new(0.5, v));
        positions.clear();
        for &(c, s) in &self.trig[..self.sides] {
            let position = centre + (side * c + binormal * s) * radius;
            out.vertex(position, normal, tangent, Vec2::new(0.5 + r * c, v + r * s));
            positions.push(position);
        }
        let n = self.sides as u32;
        for k in 0..n {
            let (a, b) = (base + 1 + k, base + 1 + (k + 1) % n);
            if sign > 0.0 {
                out.triangles([base, a, b]);
            } else {
                out.triangles([base, b, a]);
            }
        }
        if let Some(checks) = checks {
            checks
                .twins
                .extend((0..n).map(|k| (base + 1 + k, ring + k)));
            for (k, &a) in positions.iter().enumerate() {
                let b = positions[(k + 1) % positions.len()];
                checks.test.push(if sign > 0.0 {
                    [centre, a, b]
                } else {
                    [centre, b, a]
                });
            }
        }
    }
}
#[cfg(test)]
mod tests {
    use glam::Vec3;
    use pge_engine::geometry::{Mesh, Skeleton};
    use pge_engine::math;

    use super::TAU;
    use crate::cylinders::bark_mesh;
    use crate::cylinders::tests::{column, mesh_of};
    use crate::options::MeshOptions;

    #[test]
    fn the_seam_vertex_is_duplicated_and_u_spans_whole_tiles() {
        let m = mesh_of(&column(), 6, false);
        // The thickest ring, 0.5 m, is 3.14 m around: 5 tiles of about 0.6 m.
        assert_eq!(m.positions.len(), 2 * 7);
        for ring in 0..2 {
            let first = ring * 7;
            let last = first + 6;
            assert_eq!(m.positions[first], m.positions[last]);
            assert_eq!(m.uvs[first].x, 0.0);
            assert_eq!(m.uvs[last].x, 5.0, "the seam is a whole tile on");
            assert_eq!(m.uvs[first].y, m.uvs[last].y);
        }
        // v grows with length over the mean circumference's tiles: 2 m over 2 pi 0.375 / 5.
        let want = 2.0 * 5.0 / (TAU * 0.375);
        assert!((m.uvs[7].y - want).abs() < 1e-4, "{} vs {want}", m.uvs[7].y);
        assert_eq!(m.uvs[0].y, 0.0);
    }

    /// Each quad of a tube's first `rings` rings: its texel sizes around and along (metres
    /// per tile), and its two rings' mean radius.
    fn texels(m: &Mesh, sides: usize, rings: usize, radii: &[f32]) -> Vec<(f32, f32, f32)> {
        let stride = sides + 1;
        let mut out = Vec::new();
        for j in 0..rings - 1 {
            for k in 0..sides {
                let (a, b, d) = (j * stride + k, j * stride + k + 1, (j + 1) * stride + k);
                // Around: the mean of the quad's two edges around.
                let chords = m.positions[a].distance(m.positions[b])
                    + m.positions[d].distance(m.positions[d + 1]);
                let around = 0.5 * chords / (m.uvs[b].x - m.uvs[a].x);
                let along = m.positions[a].distance(m.positions[d]) / (m.uvs[d].y - m.uvs[a].y);
                out.push((around, along, 0.5 * (radii[j] + radii[j + 1])));
            }
        }
        out
    }

    #[test]
    fn texels_stay_square_and_scale_with_the_radius_along_a_tapering_branch() {
        // A 12 m branch tapering from 0.4 m to 1 cm, in 24 segments of varying length, bent.
        let mut s = Skeleton::new();
        let mut prev = s.push(Vec3::ZERO, None, 0.4, 0);
        let mut y = 0.0;
        for i in 1..=24 {
            y += if i % 3 == 0 { 0.9 } else { 0.3 };
            let t = i as f32 / 24.0;
            let p = Vec3::new(0.3 * math::sin(t * 3.0), y, 0.2 * t * t);
            prev = s.push(p, Some(prev), 0.4 * (1.0 - t) + 0.01 * t, 0);
        }
        let sides = 12;
        let m = mesh_of(&s, sides, false);
        let texels = texels(&m, sides as usize, 25, &s.radii);
        for &(around, along, radius) in &texels {
            // Square, within what a polygon's chords and a tapering segment allow.
            assert!(
                (along / around - 1.0).abs() < 0.25,
                "{around} x {along} at {radius}"
            );
            // A tile is the ring's circumference over the 4 tiles (2 pi 0.4 / 0.6, rounded).
            let tile = TAU * radius / 4.0;
            assert!((around / tile - 1.0).abs() < 0.25, "{around} vs {tile}");
        }
    }

    #[test]
    fn a_root_seam_faces_away_from_the_light_and_rings_do_not_twist() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.3, 0);
        let a = s.push(Vec3::new(0.0, 2.0, 0.0), Some(r), 0.2, 0);
        s.push(Vec3::new(0.0, 3.8, 0.0), Some(a), 0.1, 0);
        for light in [
            Vec3::new(0.45, 0.8, 0.35),
            Vec3::new(-1.0, 0.2, 0.0),
            Vec3::Z,
        ] {
            let options = MeshOptions {
                sides: 8,
                caps: false,
                light,
                ..MeshOptions::default()
            };
            let m = bark_mesh(&s, &options);
            let seam = |ring: usize| {
                let first = ring * 9;
                let centre: Vec3 = m.positions[first..first + 8].iter().sum::<Vec3>() / 8.0;
                (m.positions[first] - centre).normalize()
            };
            // The seam is the first ring's point most turned away from the light.
            for k in 1..8 {
                let other =
                    (m.positions[k] - m.positions[..8].iter().sum::<Vec3>() / 8.0).normalize();
                assert!(
                    seam(0).dot(light) <= other.dot(light) + 1e-4,
                    "light {light}: vertex {k} is darker than the seam"
                );
            }
            // A straight branch: every ring's seam on the same side.
            for ring in 1..3 {
                assert!(seam(ring).distance(seam(0)) < 1e-4, "ring {ring} turned");
            }
        }
    }

    #[test]
    fn a_lateral_carries_on_its_parents_frame_and_v_at_the_fork() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.3, 0);
        let fork = s.push(Vec3::new(0.0, 2.0, 0.0), Some(r), 0.25, 0);
        s.push(Vec3::new(0.0, 4.0, 0.0), Some(fork), 0.2, 0);
        // Nearly as thick as the main branch, leaning 30 degrees off it.
        s.push(Vec3::new(1.0, 3.732, 0.0), Some(fork), 0.18, 1);
        let m = mesh_of(&s, 8, false);
        // The main tube's ring at the fork is its second; the lateral's first ring follows
        // the main tube's three.
        let (main_fork, lateral) = (9, 27);
        assert_eq!(m.uvs[lateral].y, m.uvs[main_fork].y, "v runs on");
        let seam = |first: usize| {
            let centre: Vec3 = m.positions[first..first + 8].iter().sum::<Vec3>() / 8.0;
            (m.positions[first] - centre).normalize()
        };
        // The lateral's seam is the parent's, turned with the branch (within the 30 degrees
        // between the rings' planes).
        assert!(seam(lateral).dot(seam(main_fork)) > 0.85);
        // The same tiles around, so the texture's features follow the radius.
        assert_eq!(m.uvs[lateral + 8].x, m.uvs[main_fork + 8].x);
    }

    #[test]
    fn joints_are_oriented_between_the_two_segments() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.1, 0);
        let a = s.push(Vec3::Y, Some(r), 0.1, 0);
        s.push(Vec3::new(1.0, 1.0, 0.0), Some(a), 0.1, 0);
        let m = mesh_of(&s, 8, false);
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
}
