//! Skeleton to bark mesh: generalized cylinders after Bloomenthal ("Modeling the Mighty
//! Maple", 1985).
//!
//! The skeleton is cut into branches: a branch starts at a root, or at a fork for every child
//! but the one that continues the parent's branch (see [`main_children`]), and follows the
//! continuing children to a tip. Each branch is one tube: a ring of `sides` points (plus one
//! duplicated seam vertex, where the texture's `u` restarts) at every node, each ring
//! oriented between the incoming and the outgoing direction so joints stay continuous, and
//! framed by parallel transport so tubes do not twist (the seam, though, is turned away from
//! the light). Normals point from the ring centre to the vertex; UVs keep one texel density
//! everywhere (`u` around the circumference and `v` along the branch both in texture tiles
//! of `texture_scale` metres). A trunk flare widens the first metre of every root tube into
//! buttresses. A lateral branch starts with a ring of its own radius at the
//! fork node, inside its parent. Tips (and the base of each root) get a flat cap.

use std::f32::consts::TAU;

use glam::{Quat, Vec2, Vec3};
use pge_engine::geometry::{Mesh, Skeleton};
use rayon::prelude::*;

use crate::options::{Flare, MeshOptions};
use crate::radii::main_children;

/// Appends the bark tubes of `skeleton` to `mesh` (positions, normals, uvs, indices; the
/// mesh's other attributes must be empty or are left short). Radii are used as they are.
/// Of the options, `sides` (clamped to `3..=1024`), `caps`, `texture_scale`, `light` and
/// `flare` are used.
///
/// UVs keep a constant texel density: `u` runs around each ring over its circumference
/// divided by `texture_scale` (so `u` ends where the ring's bark ends, at the seam, not at
/// 1), `v` grows by the length travelled divided by `texture_scale`. The seam (`u = 0`)
/// faces away from `light` wherever the branch is not parallel to it. Every vertex is
/// finite when the skeleton is; a branch of zero length keeps the direction of the segment
/// before it.
pub fn append_bark(skeleton: &Skeleton, options: &MeshOptions, mesh: &mut Mesh) {
    let sides = options.sides.clamp(3, 1024) as usize;
    let caps = options.caps;
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
    let scale = if options.texture_scale > 0.0 && options.texture_scale.is_finite() {
        options.texture_scale
    } else {
        MeshOptions::default().texture_scale
    };
    let shape = Shape {
        trig: &trig,
        sides,
        scale,
        away: -options.light.try_normalize().unwrap_or(Vec3::ZERO),
    };
    let flare = options
        .flare
        .filter(|f| f.height > 0.0 && f.spread > 0.0 && f.roots > 0);

    // The tubes in the order they are written: a root's, then its node's laterals, node by
    // node.
    let mut tubes = Vec::new();
    for i in 0..skeleton.len() {
        if skeleton.parents[i].is_none() {
            tubes.push(TubeSpec {
                start: i,
                fork: None,
                base_cap: caps,
                tip_cap: caps,
                fallback: Vec3::Y,
                flare,
            });
        }
        for &c in &children[i] {
            if Some(c) != main[i] {
                let attach = skeleton.positions[i];
                let incoming = skeleton.parents[i]
                    .and_then(|p| (attach - skeleton.positions[p as usize]).try_normalize())
                    .unwrap_or(Vec3::Y);
                tubes.push(TubeSpec {
                    start: c as usize,
                    fork: Some(i),
                    base_cap: false,
                    tip_cap: caps,
                    fallback: incoming,
                    flare: None,
                });
            }
        }
    }

    // Two passes over the tubes, each in parallel: first every tube's rings and how many
    // vertices and indices it writes; then, a prefix sum having placed each tube in the
    // mesh, its vertices and indices, written into slices of its own. A tube's numbers
    // depend only on the tube: the same mesh for any number of threads.
    let points: Vec<Vec<(Vec3, f32, f32)>> = tubes
        .par_iter()
        .map(|t| tube_points(skeleton, &main, t))
        .collect();
    let counts: Vec<(usize, usize)> = tubes
        .iter()
        .zip(&points)
        .map(|(t, pts)| t.counts(pts, sides))
        .collect();
    let base = mesh.positions.len();
    let index_base = mesh.indices.len();
    let vertices: usize = counts.iter().map(|c| c.0).sum();
    let indices: usize = counts.iter().map(|c| c.1).sum();
    mesh.positions.resize(base + vertices, Vec3::ZERO);
    mesh.normals.resize(base + vertices, Vec3::ZERO);
    mesh.uvs.resize(base + vertices, Vec2::ZERO);
    mesh.indices.resize(index_base + indices, 0);
    let mut sinks = Vec::with_capacity(tubes.len());
    let mut positions = &mut mesh.positions[base..];
    let mut normals = &mut mesh.normals[base..];
    let mut uvs = &mut mesh.uvs[base..];
    let mut index_slots = &mut mesh.indices[index_base..];
    let mut first = base as u32;
    for &(v, i) in &counts {
        let (p, rest) = positions.split_at_mut(v);
        positions = rest;
        let (n, rest) = normals.split_at_mut(v);
        normals = rest;
        let (u, rest) = uvs.split_at_mut(v);
        uvs = rest;
        let (x, rest) = index_slots.split_at_mut(i);
        index_slots = rest;
        sinks.push(Sink {
            positions: p,
            normals: n,
            uvs: u,
            indices: x,
            first,
            vertices: 0,
            indices_written: 0,
        });
        first += v as u32;
    }
    tubes
        .par_iter()
        .zip(&points)
        .zip(sinks)
        .for_each(|((t, pts), mut sink)| shape.emit(t, pts, &mut sink));
}

/// A bark mesh of `skeleton` alone: [`append_bark`] into an empty mesh named `bark`, with the
/// default material.
#[must_use]
pub fn bark_mesh(skeleton: &Skeleton, options: &MeshOptions) -> Mesh {
    let mut mesh = Mesh {
        name: "bark".into(),
        ..Mesh::default()
    };
    append_bark(skeleton, options, &mut mesh);
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

/// Where a flared trunk gets rings of its own: fractions of the flare's height.
const FLARE_RINGS: [f32; 9] = [0.0, 0.03, 0.08, 0.15, 0.25, 0.38, 0.55, 0.75, 1.0];

/// The points of a tube with extra points in its first `height` metres (at
/// [`FLARE_RINGS`]), each with its distance from the start along the tube.
fn with_flare_rings(points: &[(Vec3, f32)], height: f32) -> Vec<(Vec3, f32, f32)> {
    let mut out = Vec::with_capacity(points.len() + FLARE_RINGS.len());
    let mut travelled = 0.0;
    out.push((points[0].0, points[0].1, 0.0));
    for w in points.windows(2) {
        let ((a, ra), (b, rb)) = (w[0], w[1]);
        let len = a.distance(b);
        for f in FLARE_RINGS {
            let s = f * height;
            if s > travelled + 1e-3 && s < travelled + len - 1e-3 {
                let t = (s - travelled) / len;
                out.push((a.lerp(b, t), ra + (rb - ra) * t, s));
            }
        }
        travelled += len;
        out.push((b, rb, travelled));
    }
    out
}

/// One tube of the bark: where it starts, its caps, the direction it takes while it has no
/// segment of non-zero length yet, and the flare widening its first metres.
struct TubeSpec {
    /// The tube's first node after the fork.
    start: usize,
    /// The fork node a lateral starts at (inside its parent); `None` for a root's tube.
    fork: Option<usize>,
    base_cap: bool,
    tip_cap: bool,
    fallback: Vec3,
    flare: Option<Flare>,
}

impl TubeSpec {
    /// The vertices and indices the tube writes through its rings `pts` (see
    /// [`tube_points`]).
    fn counts(&self, pts: &[(Vec3, f32, f32)], sides: usize) -> (usize, usize) {
        let (Some(&(_, base_radius, _)), Some(&(_, tip_radius, _))) = (pts.first(), pts.last())
        else {
            return (0, 0);
        };
        if pts.len() < 2 {
            return (0, 0);
        }
        let mut vertices = pts.len() * (sides + 1);
        let mut indices = (pts.len() - 1) * sides * 6;
        if self.base_cap && base_radius > 0.0 && self.flare.is_none() {
            vertices += sides + 1;
            indices += sides * 3;
        }
        if self.tip_cap && tip_radius > 0.0 {
            vertices += sides + 1;
            indices += sides * 3;
        }
        (vertices, indices)
    }
}

/// The rings of a tube: its points (from the fork for a lateral, then along the continuing
/// children to a tip) with their radii and distances from the start, and the flare's extra
/// rings; none when the tube has no segment.
fn tube_points(skeleton: &Skeleton, main: &[Option<u32>], t: &TubeSpec) -> Vec<(Vec3, f32, f32)> {
    let mut points = Vec::new();
    if let Some(fork) = t.fork {
        points.push((skeleton.positions[fork], skeleton.radii[t.start]));
    }
    walk(skeleton, main, t.start, &mut points);
    if points.len() < 2 {
        return Vec::new();
    }
    match t.flare {
        Some(f) => with_flare_rings(&points, f.height),
        None => {
            let mut travelled = 0.0;
            let mut prev = points[0].0;
            points
                .iter()
                .map(|&(p, r)| {
                    travelled += p.distance(prev);
                    prev = p;
                    (p, r, travelled)
                })
                .collect()
        }
    }
}

/// The part of the mesh one tube writes: slices of the attributes and indices of its own.
struct Sink<'a> {
    positions: &'a mut [Vec3],
    normals: &'a mut [Vec3],
    uvs: &'a mut [Vec2],
    indices: &'a mut [u32],
    /// The mesh index of the slices' first vertex.
    first: u32,
    vertices: usize,
    indices_written: usize,
}

impl Sink<'_> {
    /// The mesh index of the next vertex.
    fn next_index(&self) -> u32 {
        self.first + self.vertices as u32
    }

    fn vertex(&mut self, position: Vec3, normal: Vec3, uv: Vec2) {
        self.positions[self.vertices] = position;
        self.normals[self.vertices] = normal;
        self.uvs[self.vertices] = uv;
        self.vertices += 1;
    }

    fn indices(&mut self, indices: &[u32]) {
        let at = self.indices_written;
        self.indices[at..at + indices.len()].copy_from_slice(indices);
        self.indices_written += indices.len();
    }
}

/// What every tube shares: the ring's cosines and sines, the UV scale and the seam's side.
struct Shape<'a> {
    trig: &'a [(f32, f32)],
    sides: usize,
    /// Metres of bark per texture tile.
    scale: f32,
    /// The unit direction the seams face (away from the light), or zero.
    away: Vec3,
}

impl Shape<'_> {
    /// Emits one tube through its rings `pts` (see [`tube_points`]) into `out`.
    fn emit(&self, tube: &TubeSpec, pts: &[(Vec3, f32, f32)], out: &mut Sink) {
        if pts.len() < 2 {
            return;
        }
        let flare = tube.flare;
        // Segment directions, each falling back to the previous one.
        let first_dir = pts
            .windows(2)
            .find_map(|w| (w[1].0 - w[0].0).try_normalize())
            .unwrap_or(tube.fallback);
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
            self.cap(out, (pts[0].0, pts[0].1), (side, dir), -1.0, v);
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
                out.vertex(
                    centre + shape * radius * widen,
                    normal,
                    Vec2::new(around * k as f32 / self.sides as f32, v),
                );
            }
            if j > 0 {
                let a0 = first_index + (j as u32 - 1) * stride;
                let b0 = a0 + stride;
                for k in 0..self.sides as u32 {
                    let (a, b, c, d) = (a0 + k, a0 + k + 1, b0 + k + 1, b0 + k);
                    out.indices(&[a, b, c, a, c, d]);
                }
            }
        }
        let (centre, radius, _) = pts[pts.len() - 1];
        if tube.tip_cap && radius > 0.0 {
            self.cap(out, (centre, radius), (side, dir), 1.0, v);
        }
    }

    /// A flat cap of the ring at `centre` with `radius`, framed by `side` and `dir`: a
    /// centre vertex and one ring of `sides` vertices facing `sign * dir`.
    fn cap(
        &self,
        out: &mut Sink,
        (centre, radius): (Vec3, f32),
        (side, dir): (Vec3, Vec3),
        sign: f32,
        v: f32,
    ) {
        let binormal = dir.cross(side);
        let normal = dir * sign;
        let base = out.next_index();
        let r = radius / self.scale;
        out.vertex(centre, normal, Vec2::new(0.5, v));
        for &(c, s) in &self.trig[..self.sides] {
            out.vertex(
                centre + (side * c + binormal * s) * radius,
                normal,
                Vec2::new(0.5 + r * c, v + r * s),
            );
        }
        let n = self.sides as u32;
        for k in 0..n {
            let (a, b) = (base + 1 + k, base + 1 + (k + 1) % n);
            if sign > 0.0 {
                out.indices(&[base, a, b]);
            } else {
                out.indices(&[base, b, a]);
            }
        }
    }
}

/// A flared ring vertex at `travelled` metres up the trunk and `turn` turns around it: the
/// factor its offset from the axis is widened by, and its normal. The flare fades from
/// `1 + spread` on a buttress at the ground to nothing at `height`; buttresses are
/// `roots` lobes around the ring. `radial` and `tangent` are the vertex's unit directions
/// out of and around the ring, `dir` the trunk's.
fn flared(
    f: Flare,
    travelled: f32,
    turn: f32,
    radius: f32,
    radial: Vec3,
    tangent: Vec3,
    dir: Vec3,
) -> (f32, Vec3) {
    let h = (1.0 - travelled / f.height).clamp(0.0, 1.0);
    let fade = f.spread * h.powf(2.5);
    let dfade = -2.5 * f.spread / f.height * h.powf(1.5);
    let n = f.roots as f32;
    let wave = 0.5 + 0.5 * (TAU * n * turn).cos();
    let lobe = 0.2 + 0.8 * wave * wave;
    let dlobe = 0.8 * 2.0 * wave * (-0.5 * n * (TAU * n * turn).sin());
    let widen = 1.0 + fade * lobe;
    // The surface r(theta, s) = radius * widen: its normal leans back against the growth of
    // r around the ring and up the trunk.
    let normal = radial - tangent * (fade * dlobe / widen) - dir * (radius * dfade * lobe);
    (widen, normal.try_normalize().unwrap_or(radial))
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

    fn mesh_of(s: &Skeleton, sides: u32, caps: bool) -> Mesh {
        bark_mesh(
            s,
            &MeshOptions {
                sides,
                caps,
                ..MeshOptions::default()
            },
        )
    }

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
        let m = mesh_of(&column(), 4, true);
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
    fn a_flared_trunk_spreads_into_buttresses_over_its_first_metre() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.3, 0);
        s.push(Vec3::new(0.0, 4.0, 0.0), Some(r), 0.2, 0);
        let flare = Flare {
            roots: 5,
            spread: 1.0,
            height: 1.0,
        };
        let options = MeshOptions {
            sides: 40,
            flare: Some(flare),
            ..MeshOptions::default()
        };
        let m = bark_mesh(&s, &options);
        m.validate().expect("valid");
        assert!(m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-4));
        // Rings at the flare's heights, then the top.
        let rings = m.positions.len() / 41 - 1; // and the tip cap
        assert_eq!(rings, FLARE_RINGS.len() + 1);
        let reach = |y: f32| {
            m.positions
                .iter()
                .filter(|p| (p.y - y).abs() < 1e-4)
                .map(|p| Vec3::new(p.x, 0.0, p.z).length())
                .fold((f32::MAX, 0f32), |(lo, hi), r| (lo.min(r), hi.max(r)))
        };
        let (lo, hi) = reach(0.0);
        assert!(
            hi > 0.55 && lo < 0.4,
            "at the ground the buttresses reach {lo}..{hi}"
        );
        let (lo, hi) = reach(1.0);
        assert!(hi - lo < 1e-3, "round again at 1 m: {lo}..{hi}");
        // Five buttresses: the ground ring's radius has five maxima around.
        let ground: Vec<f32> = (0..40)
            .map(|k| Vec3::new(m.positions[k].x, 0.0, m.positions[k].z).length())
            .collect();
        let peaks = (0..40)
            .filter(|&k| ground[k] > ground[(k + 39) % 40] && ground[k] >= ground[(k + 1) % 40])
            .count();
        assert_eq!(peaks, 5);
        // Every face still points outward.
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
            let face = (m.positions[b] - m.positions[a]).cross(m.positions[c] - m.positions[a]);
            let avg = m.normals[a] + m.normals[b] + m.normals[c];
            assert!(face.dot(avg) > 0.0, "inward triangle {t:?}");
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

    #[test]
    fn forks_start_a_new_tube_inside_the_parent() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.2, 0);
        let a = s.push(Vec3::Y, Some(r), 0.2, 0);
        s.push(Vec3::new(0.0, 2.0, 0.0), Some(a), 0.15, 0);
        s.push(Vec3::new(1.0, 1.5, 0.0), Some(a), 0.1, 1);
        let m = mesh_of(&s, 5, true);
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
        let closed = mesh_of(&s, 7, true);
        assert!(is_closed(&closed), "caps close the tube");
        let open = mesh_of(&s, 7, false);
        assert!(!is_closed(&open), "without caps the ends are open");
    }

    #[test]
    fn any_thread_count_gives_the_same_mesh_appended_after_another() {
        // A branching skeleton of a few thousand nodes: many tubes, some with caps.
        let mut s = Skeleton::new();
        s.push(Vec3::ZERO, None, 0.0, 0);
        for i in 1..3000u32 {
            let parent = if i % 5 == 0 { i / 3 } else { i - 1 };
            let t = i as f32 * 0.37;
            let p = s.positions[parent as usize] + Vec3::new(t.sin() * 0.2, 0.3, t.cos() * 0.2);
            s.push(p, Some(parent), 0.0, u32::from(i % 5 == 0));
        }
        crate::pipe_radii(&mut s, 0.01, 2.3);
        let options = MeshOptions {
            flare: Some(Flare {
                roots: 4,
                spread: 0.5,
                height: 1.0,
            }),
            ..MeshOptions::default()
        };
        let on = |threads: usize, mesh: &mut Mesh| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool")
                .install(|| append_bark(&s, &options, mesh));
        };
        let mut one = Mesh::default();
        on(1, &mut one);
        one.validate().expect("valid");
        for threads in [2, 3, 8] {
            let mut other = Mesh::default();
            on(threads, &mut other);
            assert_eq!(other.positions, one.positions, "{threads} threads");
            assert_eq!(other.normals, one.normals, "{threads} threads");
            assert_eq!(other.uvs, one.uvs, "{threads} threads");
            assert_eq!(other.indices, one.indices, "{threads} threads");
        }
        // Appended after another mesh: the same vertices after it, indices shifted by its
        // vertex count.
        let mut two = column_mesh();
        let before = two.positions.len();
        on(2, &mut two);
        assert_eq!(two.positions[before..], one.positions[..]);
        let shifted: Vec<u32> = one.indices.iter().map(|i| i + before as u32).collect();
        assert_eq!(two.indices[column_mesh().indices.len()..], shifted[..]);
    }

    fn column_mesh() -> Mesh {
        mesh_of(&column(), 5, true)
    }

    #[test]
    fn degenerate_segments_stay_finite() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.1, 0);
        let a = s.push(Vec3::ZERO, Some(r), 0.1, 0);
        let b = s.push(Vec3::ZERO, Some(a), 0.0, 0);
        s.push(Vec3::X, Some(b), 0.0, 0);
        let m = mesh_of(&s, 3, true);
        m.validate().expect("finite");
        assert!(m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-4));
    }
}
