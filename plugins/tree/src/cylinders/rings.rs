//! One tube's rings written into the mesh: each ring oriented between the incoming and the
//! outgoing direction and framed by parallel transport, its seam turned away from the light,
//! UVs at one texel density, and the flat caps.

use std::f32::consts::TAU;

use glam::{Quat, Vec2, Vec3};
use pge_engine::geometry::{DegenerateTest, Mesh};

use super::TubeSpec;
use super::flare::flared;

/// Where a tube is written: the next vertex's index in the mesh, its vertices and its
/// triangles.
pub(super) trait Sink {
    /// The mesh index of the next vertex.
    fn next_index(&self) -> u32;

    fn vertex(&mut self, position: Vec3, normal: Vec3, uv: Vec2);

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
    fn vertex(&mut self, position: Vec3, normal: Vec3, uv: Vec2) {
        self.0.positions.push(position);
        self.0.normals.push(normal);
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
    fn vertex(&mut self, position: Vec3, normal: Vec3, uv: Vec2) {
        self.positions[self.vertices] = position;
        self.normals[self.vertices] = normal;
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
/// coordinate (for [`DegenerateTest::strip`]) and a cap's ring.
#[derive(Default)]
pub(super) struct Scratch {
    seg: Vec<Vec3>,
    below: [Vec<f32>; 3],
    above: [Vec<f32>; 3],
    cap: Vec<Vec3>,
}

/// What every tube shares: the ring's cosines and sines, the UV scale and the seam's side.
pub(super) struct Shape<'a> {
    pub(super) trig: &'a [(f32, f32)],
    pub(super) sides: usize,
    /// Metres of bark per texture tile.
    pub(super) scale: f32,
    /// The unit direction the seams face (away from the light), or zero.
    pub(super) away: Vec3,
}

impl Shape<'_> {
    /// Emits one tube through its rings `pts` (see [`tube_points`](super::tube_points)) into
    /// `out`, checked by `checks` when given.
    pub(super) fn emit(
        &self,
        tube: &TubeSpec,
        pts: &[(Vec3, f32, f32)],
        scratch: &mut Scratch,
        out: &mut impl Sink,
        mut checks: Option<&mut Checks>,
    ) {
        if pts.len() < 2 {
            return;
        }
        let flare = tube.flare;
        // Segment directions, each falling back to the previous one.
        let first_dir = pts
            .windows(2)
            .find_map(|w| (w[1].0 - w[0].0).try_normalize())
            .unwrap_or(tube.fallback);
        let Scratch {
            seg,
            below,
            above,
            cap: cap_ring,
        } = scratch;
        seg.clear();
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
        // The seam faces away from the light where the ring's plane allows it; where the
        // branch runs along the light, the side is carried on from the ring before.
        let away = self.away;
        let seam_side = |dir: Vec3, carried: Vec3| -> Vec3 {
            let target = away - dir * away.dot(dir);
            if target.length_squared() > 0.0025 {
                target.normalize()
            } else {
                carried
            }
        };
        let stride = (self.sides + 1) as u32;
        let mut dir = ring_dir(0);
        let mut side = seam_side(dir, dir.any_orthonormal_vector());
        let mut v = 0.0f32;
        if tube.base_cap && pts[0].1 > 0.0 && flare.is_none() {
            // The first ring follows the cap.
            let ring = out.next_index() + 1 + self.sides as u32;
            let cap = (pts[0].0, pts[0].1, ring);
            self.cap(
                out,
                cap,
                (side, dir),
                -1.0,
                v,
                cap_ring,
                checks.as_deref_mut(),
            );
        }
        let first_index = out.next_index();
        for j in 0..pts.len() {
            if j > 0 {
                let next_dir = ring_dir(j);
                side = seam_side(next_dir, transport(side, dir, next_dir));
                dir = next_dir;
                v += pts[j].0.distance(pts[j - 1].0) / self.scale;
            }
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
            let around = TAU * radius / self.scale;
            std::mem::swap(below, above);
            above.iter_mut().for_each(Vec::clear);
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
                let position = centre + shape * radius * widen;
                out.vertex(
                    position,
                    normal,
                    Vec2::new(around * k as f32 / self.sides as f32, v),
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
            self.cap(out, cap, (side, dir), 1.0, v, cap_ring, checks);
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
        let r = radius / self.scale;
        out.vertex(centre, normal, Vec2::new(0.5, v));
        positions.clear();
        for &(c, s) in &self.trig[..self.sides] {
            let position = centre + (side * c + binormal * s) * radius;
            out.vertex(position, normal, Vec2::new(0.5 + r * c, v + r * s));
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
    use glam::Vec3;
    use pge_engine::geometry::{Mesh, Skeleton};

    use super::TAU;
    use crate::cylinders::bark_mesh;
    use crate::cylinders::tests::{column, mesh_of};
    use crate::options::MeshOptions;

    #[test]
    fn the_seam_vertex_is_duplicated_and_u_spans_the_circumference() {
        let m = mesh_of(&column(), 6, false);
        let scale = MeshOptions::default().texture_scale;
        assert_eq!(m.positions.len(), 2 * 7);
        for (ring, radius) in [(0, 0.5), (1, 0.25)] {
            let first = ring * 7;
            let last = first + 6;
            assert_eq!(m.positions[first], m.positions[last]);
            assert_eq!(m.uvs[first].x, 0.0);
            assert!((m.uvs[last].x - TAU * radius / scale).abs() < 1e-5);
            assert_eq!(m.uvs[first].y, m.uvs[last].y);
        }
        // v grows with length: 2 metres in tiles of `scale` metres.
        assert!((m.uvs[7].y - 2.0 / scale).abs() < 1e-5);
        assert_eq!(m.uvs[0].y, 0.0);
    }

    /// The texel density of each quad of a tube: UV area over world area, square-rooted
    /// (texture tiles per metre), with the quad's distance up the tube.
    fn densities(m: &Mesh, sides: usize, rings: usize) -> Vec<(f32, f32)> {
        let stride = sides + 1;
        let mut out = Vec::new();
        for j in 0..rings - 1 {
            for k in 0..sides {
                let [a, b, c, d] = [
                    j * stride + k,
                    j * stride + k + 1,
                    (j + 1) * stride + k + 1,
                    (j + 1) * stride + k,
                ];
                let area3 = |p: [usize; 3]| {
                    0.5 * (m.positions[p[1]] - m.positions[p[0]])
                        .cross(m.positions[p[2]] - m.positions[p[0]])
                        .length()
                };
                let area2 = |p: [usize; 3]| {
                    let (e1, e2) = (m.uvs[p[1]] - m.uvs[p[0]], m.uvs[p[2]] - m.uvs[p[0]]);
                    0.5 * (e1.x * e2.y - e1.y * e2.x).abs()
                };
                let world = area3([a, b, c]) + area3([a, c, d]);
                let uv = area2([a, b, c]) + area2([a, c, d]);
                out.push((m.positions[a].y, (uv / world).sqrt()));
            }
        }
        out
    }

    #[test]
    fn texel_density_is_constant_along_a_long_tapering_branch() {
        // A 12 m branch tapering from 0.4 m to 1 cm, in 24 segments of varying length, bent.
        let mut s = Skeleton::new();
        let mut prev = s.push(Vec3::ZERO, None, 0.4, 0);
        let mut y = 0.0;
        for i in 1..=24 {
            y += if i % 3 == 0 { 0.9 } else { 0.3 };
            let t = i as f32 / 24.0;
            let p = Vec3::new(0.3 * (t * 3.0).sin(), y, 0.2 * t * t);
            prev = s.push(p, Some(prev), 0.4 * (1.0 - t) + 0.01 * t, 0);
        }
        let sides = 12;
        let m = mesh_of(&s, sides, false);
        let d = densities(&m, sides as usize, 25);
        let (lo, hi) = d
            .iter()
            .fold((f32::MAX, 0f32), |(lo, hi), &(_, x)| (lo.min(x), hi.max(x)));
        assert!(
            hi / lo < 1.2,
            "texel density from {lo} to {hi} tiles per metre"
        );
        // And it is the one the options ask for.
        let want = 1.0 / MeshOptions::default().texture_scale;
        assert!(
            (lo / want - 1.0).abs() < 0.2 && (hi / want - 1.0).abs() < 0.2,
            "{lo}..{hi} vs {want}"
        );
    }

    #[test]
    fn the_seam_faces_away_from_the_light() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.3, 0);
        let a = s.push(Vec3::new(0.0, 2.0, 0.0), Some(r), 0.2, 0);
        s.push(Vec3::new(0.5, 3.8, 0.3), Some(a), 0.1, 0);
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
            for ring in 0..3 {
                let first = ring * 9;
                let centre: Vec3 = m.positions[first..first + 8].iter().sum::<Vec3>() / 8.0;
                let seam = (m.positions[first] - centre).normalize();
                // The seam is the ring's point most turned away from the light.
                for k in 1..8 {
                    let other = (m.positions[first + k] - centre).normalize();
                    assert!(
                        seam.dot(light) <= other.dot(light) + 1e-4,
                        "ring {ring}, light {light}: vertex {k} is darker than the seam"
                    );
                }
            }
        }
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
