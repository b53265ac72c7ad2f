//! Skeleton to bark mesh: generalized cylinders after Bloomenthal ("Modeling the Mighty
//! Maple", 1985).
//!
//! The skeleton is cut into branches: a branch starts at a root, or at a fork for every child
//! but the one that continues the parent's branch (see [`main_children`](crate::main_children)), and follows the
//! continuing children to a tip. Each branch is one tube: a ring of `sides` points (plus one
//! duplicated seam vertex, where the texture's `u` restarts) at every node, each ring
//! oriented between the incoming and the outgoing direction so joints stay continuous, and
//! framed by parallel transport so tubes do not twist. Normals point from the ring centre
//! to the vertex. UVs wrap the bark texture a whole number of tiles around every branch
//! (the same number on every branch, so the seam does not show and the texture's features
//! scale with the radius), `v` along the branch at the same texel size, and a lateral
//! carries on its parent's frame and `v` at the fork (see [`frames`]). A trunk flare widens
//! the first metre of every root tube into buttresses. A lateral branch starts with a ring
//! of its own radius at the fork node, inside its parent. Tips (and the base of each root)
//! get a flat cap.

use pge_engine::math;
mod flare;
mod frames;
mod rings;

use std::f32::consts::TAU;

use glam::{Vec2, Vec3, Vec4};
use pge_engine::geometry::{Mesh, Skeleton};
use rayon::prelude::*;

use crate::memory::BarkBuffers;
use crate::options::{Flare, MeshOptions};
use crate::radii::{Children, main_child};
use flare::with_flare_rings;
use frames::Wrap;
use rings::{Appended, Checks, Scratch, Shape, Slices};

/// Appends the bark tubes of `skeleton` to `mesh` (positions, normals, uvs, indices, and
/// tangents when the mesh's vertices all have one: around the ring, w = +1; the mesh's other
/// attributes must be empty or are left short). Radii are used as they are.
/// Of the options, `sides` (clamped to `3..=1024`), `caps`, `texture_scale`, `light` and
/// `flare` are used.
///
/// UVs: `u` runs around each ring from 0 at the seam to a whole number of tiles, the same
/// for every branch: the thickest ring's circumference over `texture_scale`, rounded (at
/// least 1); `v` grows along the branch by the length travelled over the ring's
/// circumference divided by the tiles, so texels stay square and the texture's features
/// scale with the radius. A root tube's seam (`u = 0`) starts on the side turned away from
/// `light`; a lateral's frame and `v` carry on from its parent at the fork. Every vertex is
/// finite when the skeleton is; a branch of zero length keeps the direction of the segment
/// before it.
pub fn append_bark(skeleton: &Skeleton, options: &MeshOptions, mesh: &mut Mesh) {
    append_checked_bark(skeleton, options, mesh, None);
}

/// [`append_bark`], checked by `checks` (when given and the mesh is written on the calling
/// thread) as it is written; whether it was (`false` when the mesh was written in parallel
/// and `checks` left as they were).
fn append_checked_bark(
    skeleton: &Skeleton,
    options: &MeshOptions,
    mesh: &mut Mesh,
    mut checks: Option<&mut Checks>,
) -> bool {
    let sides = options.sides.clamp(3, 1024) as usize;
    let caps = options.caps;
    let trig: Vec<(f32, f32)> = (0..=sides)
        .map(|k| {
            if k == sides {
                (1.0, 0.0)
            } else {
                let a = TAU * k as f32 / sides as f32;
                (math::cos(a), math::sin(a))
            }
        })
        .collect();
    let children = Children::of(skeleton);
    let main: Vec<Option<u32>> = (0..skeleton.len())
        .map(|i| main_child(skeleton, i, children.of_node(i)))
        .collect();
    let scale = if options.texture_scale > 0.0 && options.texture_scale.is_finite() {
        options.texture_scale
    } else {
        MeshOptions::default().texture_scale
    };
    let thickest = skeleton.radii.iter().fold(0.0f32, |a, &r| a.max(r));
    let wrap = Wrap::new(thickest, scale);
    let shape = Shape {
        trig: &trig,
        sides,
        tiles: wrap.tiles,
    };
    let flare = options
        .flare
        .filter(|f| f.height > 0.0 && f.spread > 0.0 && f.roots > 0);

    // The tubes in the order they are written: a root's, then its node's laterals, node by
    // node.
    let mut tubes = Vec::new();
    for (i, &main_child) in main.iter().enumerate() {
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
        for &c in children.of_node(i) {
            if Some(c) != main_child {
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

    // Every tube's rings, one after another, and how many vertices and indices it writes;
    // then, a prefix sum having placed each tube in the mesh, its vertices and indices,
    // written into slices of its own, in parallel when the mesh is large. A tube's numbers
    // depend only on the tube: the same mesh for any number of threads.
    let mut points = Vec::new();
    let mut nodes = Vec::new();
    let mut ends = Vec::with_capacity(tubes.len());
    let mut walked = Vec::new();
    for t in &tubes {
        tube_points(skeleton, &main, t, &mut walked, &mut points, &mut nodes);
        ends.push(points.len());
    }
    let range = |k: usize| if k == 0 { 0 } else { ends[k - 1] }..ends[k];
    let rings = |k: usize| &points[range(k)];
    let away = -options.light.try_normalize().unwrap_or(Vec3::ZERO);
    let frames = frames::frames(&tubes, &points, &nodes, range, skeleton.len(), wrap, away);
    let frames_of = |k: usize| &frames[range(k)];
    let counts: Vec<(usize, usize)> = tubes
        .iter()
        .enumerate()
        .map(|(k, t)| t.counts(rings(k), sides))
        .collect();
    let vertices: usize = counts.iter().map(|c| c.0).sum();
    let indices: usize = counts.iter().map(|c| c.1).sum();
    if vertices < PARALLEL_FROM {
        // Appended: written once, not zero-filled first.
        let base = mesh.positions.len();
        let tangents_before = mesh.tangents.len() == base;
        mesh.normals.resize(base, Vec3::ZERO);
        mesh.uvs.resize(base, Vec2::ZERO);
        mesh.tangents.resize(base, Vec4::ZERO);
        mesh.positions.reserve(vertices);
        mesh.normals.reserve(vertices);
        mesh.tangents.reserve(vertices);
        mesh.uvs.reserve(vertices);
        mesh.indices.reserve(indices);
        let mut out = Appended(mesh);
        let mut scratch = Scratch::default();
        for (k, t) in tubes.iter().enumerate() {
            let (pts, frames) = (rings(k), frames_of(k));
            shape.emit(
                t,
                pts,
                frames,
                &mut scratch,
                &mut out,
                checks.as_deref_mut(),
            );
        }
        if !tangents_before {
            // Vertices before these had none: the mesh's tangents are derived at export.
            mesh.tangents.clear();
        }
        return true;
    }
    // Fresh memory zeroed in parallel: its pages are touched by both threads.
    let base = mesh.positions.len();
    let tangents_before = mesh.tangents.len() == base;
    mesh.tangents.resize(base, Vec4::ZERO);
    let index_base = mesh.indices.len();
    let zeros = |n: usize| rayon::iter::repeat_n(0u8, n).with_min_len(1 << 14);
    mesh.positions
        .par_extend(zeros(vertices).map(|_| Vec3::ZERO));
    mesh.normals.par_extend(zeros(vertices).map(|_| Vec3::ZERO));
    mesh.uvs.par_extend(zeros(vertices).map(|_| Vec2::ZERO));
    mesh.tangents
        .par_extend(zeros(vertices).map(|_| Vec4::ZERO));
    mesh.indices.par_extend(zeros(indices).map(|_| 0));
    let mut sinks = Vec::with_capacity(tubes.len());
    let mut positions = &mut mesh.positions[base..];
    let mut normals = &mut mesh.normals[base..];
    let mut uvs = &mut mesh.uvs[base..];
    let mut tangents = &mut mesh.tangents[base..];
    let mut index_slots = &mut mesh.indices[index_base..];
    let mut first = base as u32;
    for &(v, i) in &counts {
        let (p, rest) = positions.split_at_mut(v);
        positions = rest;
        let (n, rest) = normals.split_at_mut(v);
        normals = rest;
        let (u, rest) = uvs.split_at_mut(v);
        uvs = rest;
        let (t, rest) = tangents.split_at_mut(v);
        tangents = rest;
        let (x, rest) = index_slots.split_at_mut(i);
        index_slots = rest;
        sinks.push(Slices {
            positions: p,
            normals: n,
            tangents: t,
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
        .enumerate()
        .zip(sinks)
        .with_min_len(16)
        .for_each_init(Scratch::default, |scratch, ((k, t), mut sink)| {
            shape.emit(t, rings(k), frames_of(k), scratch, &mut sink, None);
        });
    if !tangents_before {
        // Vertices before these had none: the mesh's tangents are derived at export.
        mesh.tangents.clear();
    }
    false
}

/// Bark meshes with fewer vertices are written on the calling thread: handing tubes to
/// other threads costs more than it saves.
const PARALLEL_FROM: usize = 1 << 16;

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

/// [`bark_mesh`] written into `memory`'s arrays, and whether it is shown to have no
/// unusable triangle by construction ([`Mesh::usable_by_construction`]: its tubes' triangles
/// are distinct, so only degenerate triangles and vertices at one place can make one; the
/// triangles are tested as they are written); `false` when that was not shown (then search
/// it).
pub(crate) fn clean_bark_mesh(
    skeleton: &Skeleton,
    options: &MeshOptions,
    memory: BarkBuffers,
) -> (Mesh, bool) {
    let BarkBuffers {
        positions,
        normals,
        uvs,
        indices,
    } = memory;
    let mut mesh = Mesh {
        name: "bark".into(),
        positions,
        normals,
        uvs,
        indices,
        ..Mesh::default()
    };
    let mut checks = Checks::default();
    let clean = append_checked_bark(skeleton, options, &mut mesh, Some(&mut checks))
        && !checks.test.found()
        && mesh.distinct_positions(&checks.twins);
    (mesh, clean)
}

/// Follows the continuing children from `start` to a tip, pushing positions, radii and
/// node indices.
fn walk(
    skeleton: &Skeleton,
    main: &[Option<u32>],
    start: usize,
    out: &mut Vec<(Vec3, f32, Option<u32>)>,
) {
    let mut cur = start;
    loop {
        out.push((
            skeleton.positions[cur],
            skeleton.radii[cur],
            Some(cur as u32),
        ));
        match main[cur] {
            Some(next) => cur = next as usize,
            None => break,
        }
    }
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

/// Appends the rings of a tube to `out`: its points (from the fork for a lateral, then along
/// the continuing children to a tip) with their radii and distances from the start, and the
/// flare's extra rings; none when the tube has no segment. `nodes` gets each ring's node
/// (`None` for a lateral's first ring, at its fork inside the parent, and for the flare's
/// rings). `walked` is scratch space.
fn tube_points(
    skeleton: &Skeleton,
    main: &[Option<u32>],
    t: &TubeSpec,
    walked: &mut Vec<(Vec3, f32, Option<u32>)>,
    out: &mut Vec<(Vec3, f32, f32)>,
    nodes: &mut Vec<Option<u32>>,
) {
    walked.clear();
    if let Some(fork) = t.fork {
        walked.push((skeleton.positions[fork], skeleton.radii[t.start], None));
    }
    walk(skeleton, main, t.start, walked);
    if walked.len() < 2 {
        return;
    }
    match t.flare {
        Some(f) => with_flare_rings(walked, f.height, out, nodes),
        None => {
            let mut travelled = 0.0;
            let mut prev = walked[0].0;
            out.extend(walked.iter().map(|&(p, r, _)| {
                travelled += p.distance(prev);
                prev = p;
                (p, r, travelled)
            }));
            nodes.extend(walked.iter().map(|w| w.2));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::assert_approx_eq;

    pub(super) fn mesh_of(s: &Skeleton, sides: u32, caps: bool) -> Mesh {
        bark_mesh(
            s,
            &MeshOptions {
                sides,
                caps,
                ..MeshOptions::default()
            },
        )
    }

    pub(super) fn column() -> Skeleton {
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
                assert_approx_eq!(radial.normalize(), *n);
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
        assert_approx_eq!(centre, Vec3::Y);
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

    /// A branching skeleton of `n` nodes with pipe-model radii: every fifth node starts a
    /// lateral from a node a third of its number.
    fn branching(n: u32) -> Skeleton {
        let mut s = Skeleton::new();
        s.push(Vec3::ZERO, None, 0.0, 0);
        for i in 1..n {
            let parent = if i % 5 == 0 { i / 3 } else { i - 1 };
            let t = i as f32 * 0.37;
            let p = s.positions[parent as usize]
                + Vec3::new(math::sin(t) * 0.2, 0.3, math::cos(t) * 0.2);
            s.push(p, Some(parent), 0.0, u32::from(i % 5 == 0));
        }
        crate::pipe_radii(&mut s, 0.01, 2.3);
        s
    }

    #[test]
    fn any_thread_count_gives_the_same_mesh_appended_after_another() {
        // A branching skeleton of a few thousand nodes: many tubes, some with caps.
        let s = branching(3000);
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
    fn a_bark_shown_clean_by_construction_has_no_unusable_triangle() {
        let shown = |s: &Skeleton, options: &MeshOptions| {
            let (mesh, clean) = clean_bark_mesh(s, options, BarkBuffers::default());
            assert_eq!(mesh, bark_mesh(s, options));
            let unusable = mesh.unusable_triangles();
            assert!(!clean || unusable.is_empty(), "clean, yet {unusable:?}");
            clean
        };
        let flared = MeshOptions {
            flare: Some(Flare {
                roots: 5,
                spread: 0.9,
                height: 1.0,
            }),
            ..MeshOptions::default()
        };
        let s = branching(2000);
        for options in [MeshOptions::default(), flared.clone()] {
            assert!(shown(&s, &options));
            assert!(shown(&column(), &options));
        }
        // Two laterals from one fork to one point: the same tube twice, every triangle a
        // repeat.
        let mut twins = column();
        twins.push(Vec3::new(1.0, 3.0, 0.0), Some(1), 0.1, 1);
        twins.push(Vec3::new(1.0, 3.0, 0.0), Some(1), 0.1, 1);
        assert!(!shown(&twins, &MeshOptions::default()));
        // A zero-length segment: a flat ring of triangles where the radius changes,
        // degenerate ones where it does not.
        let mut flat = column();
        flat.push(Vec3::new(0.0, 2.0, 0.0), Some(1), 0.2, 0);
        assert!(shown(&flat, &flared));
        flat.radii[2] = flat.radii[1];
        assert!(!shown(&flat, &flared));
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
