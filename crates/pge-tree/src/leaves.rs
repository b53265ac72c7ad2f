//! Leaves (seed 000 ch. 4): double-sided quads hung by the middle of one edge near branch
//! tips, a random count per tip, a random orientation, and a colour per leaf drawn between
//! two colours. The quads are textured with an alpha-masked silhouette.

use glam::{Quat, Vec2, Vec3, Vec4};
use pge_engine::geometry::{LeafPoint, Mesh, Skeleton};
use pge_engine::math;
use rand_mt::Mt64;
use rayon::prelude::*;

use crate::options::{Along, LeafOptions};

/// A uniform draw in `[0, 1)` (53 random bits, rounded to `f32`).
pub(crate) fn uniform(rng: &mut Mt64) -> f32 {
    pge_engine::random::uniform64(rng) as f32
}

/// [`uniform`] of a draw already taken: the same number for the same draw.
fn uniform_of(draw: u64) -> f32 {
    ((draw >> 11) as f64 / (1u64 << 53) as f64) as f32
}

/// A uniform integer in `lo..=hi`.
fn int_in(rng: &mut Mt64, lo: u32, hi: u32) -> u32 {
    if hi <= lo {
        lo
    } else {
        lo + (rng.next_u64() % u64::from(hi - lo + 1)) as u32
    }
}

/// [`int_in`] of a draw already taken (none is taken when `hi <= lo`).
fn int_of(draw: u64, lo: u32, hi: u32) -> u32 {
    lo + (draw % u64::from(hi - lo + 1)) as u32
}

/// Leaves fewer than this are made and meshed on the calling thread.
const PARALLEL_FROM: usize = 1 << 14;

/// Leaf points (cards) near the tips, and along the branches when `options.along` is set
/// (after every tip's, see [`along_branches`]): for every tip (in index order) a count drawn
/// in `options.per_tip`; each leaf hangs on one of the tip's last `max_depth + 1` segments (the
/// segment ending at the tip, its parent segment, ...), at a random place along it, pointing
/// away from the branch at 35-75 degrees with a random azimuth and a random roll. A tip that
/// is a root (no segment) bears no leaves.
///
/// When there may be many leaves and more than one thread, the draws are taken in that
/// order on the calling thread (the counts decide how many each tip takes) and the leaves
/// then made from them in parallel; otherwise each leaf is made as its draws are taken. The same leaves and the
/// same state of `rng` afterwards for any number of threads.
#[must_use]
pub fn tip_leaves(skeleton: &Skeleton, options: &LeafOptions, rng: &mut Mt64) -> Vec<LeafPoint> {
    tip_leaves_into(skeleton, options, rng, Vec::new())
}

/// [`tip_leaves`] pushed onto `out` (empty), whose room it uses.
pub(crate) fn tip_leaves_into(
    skeleton: &Skeleton,
    options: &LeafOptions,
    rng: &mut Mt64,
    out: Vec<LeafPoint>,
) -> Vec<LeafPoint> {
    let mut out = at_tips(skeleton, options, rng, out);
    if let Some(along) = &options.along {
        along_branches(skeleton, options, along, rng, &mut out);
    }
    out
}

/// The tip leaves of [`tip_leaves`], without the cards along the branches.
fn at_tips(
    skeleton: &Skeleton,
    options: &LeafOptions,
    rng: &mut Mt64,
    mut out: Vec<LeafPoint>,
) -> Vec<LeafPoint> {
    let (lo, hi) = options.per_tip;
    let per_leaf = 5 + usize::from(options.max_depth > 0);
    let tips = skeleton.tips();
    if rayon::current_num_threads() == 1 || tips.len() * hi.max(lo) as usize <= PARALLEL_FROM {
        // Every leaf from its draws as they are taken, without storing them.
        for &tip in &tips {
            if skeleton.parents[tip as usize].is_none() {
                continue;
            }
            for _ in 0..int_in(rng, lo, hi) {
                let mut d = [0u64; 6];
                d[..per_leaf].fill_with(|| rng.next_u64());
                out.push(leaf(skeleton, options, tip, &d[..per_leaf]));
            }
        }
        return out;
    }
    // The tip of every leaf, and every leaf's draws one after another.
    let mut owners = Vec::new();
    let mut draws = Vec::new();
    for tip in tips {
        if skeleton.parents[tip as usize].is_none() {
            continue;
        }
        let count = int_in(rng, lo, hi) as usize;
        draws.extend((0..count * per_leaf).map(|_| rng.next_u64()));
        owners.extend(std::iter::repeat_n(tip, count));
    }
    let leaf_of = |j: usize| {
        let d = &draws[j * per_leaf..(j + 1) * per_leaf];
        leaf(skeleton, options, owners[j], d)
    };
    if owners.len() < PARALLEL_FROM {
        out.extend((0..owners.len()).map(leaf_of));
    } else {
        (0..owners.len())
            .into_par_iter()
            .with_min_len(1024)
            .map(leaf_of)
            .collect_into_vec(&mut out);
    }
    out
}

/// One leaf of `tip` from its draws (the depth, if `max_depth > 0`, then five uniforms).
fn leaf(skeleton: &Skeleton, options: &LeafOptions, tip: u32, draws: &[u64]) -> LeafPoint {
    let (depth, mut u) = if options.max_depth > 0 {
        (int_of(draws[0], 0, options.max_depth), draws[1..].iter())
    } else {
        (0, draws.iter())
    };
    let mut uniform = || uniform_of(u.next().copied().unwrap_or(0));
    // Climb up to `depth` segments, staying on a node that has a parent.
    let mut node = tip;
    for _ in 0..depth {
        match skeleton.parents[node as usize] {
            Some(p) if skeleton.parents[p as usize].is_some() => node = p,
            _ => break,
        }
    }
    let along = 0.35 + 0.65 * uniform();
    on_segment(skeleton, options, node, along, uniform)
}

/// Each node's Horton-Strahler order: 1 at a tip; a node whose children's highest order is
/// `k` has `k + 1` when two or more children have `k`, else `k`. Orders count from the
/// tips: a twig is 1, a branch bearing only twigs 2, and so on down to the trunk.
#[must_use]
pub fn strahler_orders(skeleton: &Skeleton) -> Vec<u32> {
    let n = skeleton.len();
    // The highest order among each node's children so far, and how many children have it.
    let mut best = vec![(0u32, 0u32); n];
    let mut orders = vec![0u32; n];
    for i in (0..n).rev() {
        let (k, count) = best[i];
        orders[i] = match (k, count) {
            (0, _) => 1,
            (k, c) if c >= 2 => k + 1,
            (k, _) => k,
        };
        if let Some(p) = skeleton.parents[i] {
            let b = &mut best[p as usize];
            if orders[i] > b.0 {
                *b = (orders[i], 1);
            } else if orders[i] == b.0 {
                b.1 += 1;
            }
        }
    }
    orders
}

/// Appends the cards along the branches of the last `along.orders` orders
/// ([`strahler_orders`]): every segment whose end node has such an order bears a card at
/// each multiple of `along.spacing` of path length from the root that falls on it, moved by
/// up to a third of the spacing either way, and turned, sized and tilted as tip leaves are.
/// The draws are taken in node order on the calling thread: five a card.
fn along_branches(
    skeleton: &Skeleton,
    options: &LeafOptions,
    along: &Along,
    rng: &mut Mt64,
    out: &mut Vec<LeafPoint>,
) {
    let spacing = along.spacing;
    if !(spacing > 0.0 && spacing.is_finite()) {
        return;
    }
    let orders = strahler_orders(skeleton);
    let pos = &skeleton.positions;
    let mut distance = vec![0.0f64; skeleton.len()];
    for i in 0..skeleton.len() {
        let Some(p) = skeleton.parents[i] else {
            continue;
        };
        let p = p as usize;
        let length = f64::from(pos[i].distance(pos[p]));
        distance[i] = distance[p] + length;
        if orders[i] > along.orders || length <= 0.0 {
            continue;
        }
        let step = f64::from(spacing);
        // The multiples of the spacing in (distance[p], distance[i]].
        let first = (distance[p] / step).floor() as u64 + 1;
        let last = (distance[i] / step).floor() as u64;
        for k in first..=last {
            let mut draw = || uniform(rng);
            let jitter = (draw() - 0.5) * 0.67 * spacing;
            let at = ((k as f64 * step - distance[p]) / length) as f32;
            let t = (at + jitter / length as f32).clamp(0.0, 1.0);
            out.push(on_segment(skeleton, options, i as u32, t, draw));
        }
    }
}

/// A card on the segment ending at `node` (which has a parent), `along` of the way from the
/// parent, pointing away from the branch at 35-75 degrees: its azimuth, tilt, roll and size
/// from the next four uniforms.
fn on_segment(
    skeleton: &Skeleton,
    options: &LeafOptions,
    node: u32,
    along: f32,
    mut uniform: impl FnMut() -> f32,
) -> LeafPoint {
    let pos = &skeleton.positions;
    // The node has a parent (a tip that is not a root, or the climb from one).
    let parent = skeleton.parents[node as usize].unwrap_or(node);
    let (a, b) = (pos[parent as usize], pos[node as usize]);
    let position = a.lerp(b, along);
    let branch = (b - a).try_normalize().unwrap_or(Vec3::Y);
    let (e1, e2) = branch.any_orthonormal_pair();
    let azimuth = std::f32::consts::TAU * uniform();
    let out_dir = e1 * math::cos(azimuth) + e2 * math::sin(azimuth);
    let tilt = (35.0 + 40.0 * uniform()).to_radians();
    let direction = (branch * math::cos(tilt) + out_dir * math::sin(tilt)).normalize();
    let roll = (uniform() - 0.5) * 80f32.to_radians();
    let side0 = direction
        .cross(out_dir.cross(branch))
        .try_normalize()
        .unwrap_or(e1);
    let side = Quat::from_axis_angle(direction, roll) * side0;
    let size = options.size * (0.8 + 0.4 * uniform());
    LeafPoint {
        node,
        position,
        direction,
        side,
        size,
    }
}

/// Appends one quad per leaf point (a card) to `mesh` (positions, normals, uvs, colors,
/// indices, and tangents when the mesh's vertices all have one: the card's side, where `u`
/// grows, w = +1): the middle of the quad's stalk edge at the point, the quad extending the card's
/// length ([`LeafOptions::card_length`] of the leaf's `size`: `size` itself for one leaf a
/// card) along its direction and that times `options.width` wide along its side; `v` runs from 0 at the stalk to 1 at the tip.
/// Each leaf's colour is drawn between `options.colors`. A leaf of size 0 or less takes
/// `options.size`.
///
/// The colours are drawn in order on the calling thread; the quads are written in parallel
/// when there are many, the same for any number of threads.
pub fn append_leaf_quads(
    leaves: &[LeafPoint],
    options: &LeafOptions,
    rng: &mut Mt64,
    mesh: &mut Mesh,
) {
    let mixes: Vec<f32> = leaves.iter().map(|_| uniform(rng)).collect();
    let base = mesh.positions.len() as u32;
    let quad_of = |k: usize| quad(&leaves[k], options, mixes[k]);
    let corners = |q: &Quad, c: usize| q.positions[c];
    let indices = |k: usize| {
        let v = base + 4 * k as u32;
        [v, v + 1, v + 2, v, v + 2, v + 3]
    };
    let tangents = mesh.tangents.len() == mesh.positions.len();
    if leaves.len() < PARALLEL_FROM || rayon::current_num_threads() == 1 {
        let n = leaves.len();
        mesh.positions.reserve(4 * n);
        mesh.normals.reserve(4 * n);
        mesh.uvs.reserve(4 * n);
        mesh.colors.reserve(4 * n);
        mesh.indices.reserve(6 * n);
        for k in 0..n {
            let q = quad_of(k);
            mesh.positions.extend_from_slice(&q.positions);
            mesh.normals.extend_from_slice(&[q.normal; 4]);
            if tangents {
                mesh.tangents.extend_from_slice(&[q.tangent; 4]);
            }
            mesh.uvs.extend_from_slice(&QUAD_UVS);
            mesh.colors.extend_from_slice(&[q.color; 4]);
            mesh.indices.extend_from_slice(&indices(k));
        }
    } else {
        // Written in parallel into fresh memory: the pages are touched by the threads that
        // fill them.
        let mut quads = Vec::new();
        (0..leaves.len())
            .into_par_iter()
            .with_min_len(1024)
            .map(quad_of)
            .collect_into_vec(&mut quads);
        let corner = |i: usize| (&quads[i / 4], i % 4);
        let n = 4 * leaves.len();
        mesh.positions
            .par_extend((0..n).into_par_iter().with_min_len(4096).map(|i| {
                let (q, c) = corner(i);
                corners(q, c)
            }));
        mesh.normals.par_extend(
            (0..n)
                .into_par_iter()
                .with_min_len(4096)
                .map(|i| corner(i).0.normal),
        );
        if tangents {
            mesh.tangents.par_extend(
                (0..n)
                    .into_par_iter()
                    .with_min_len(4096)
                    .map(|i| corner(i).0.tangent),
            );
        }
        mesh.uvs.par_extend(
            (0..n)
                .into_par_iter()
                .with_min_len(4096)
                .map(|i| QUAD_UVS[i % 4]),
        );
        mesh.colors.par_extend(
            (0..n)
                .into_par_iter()
                .with_min_len(4096)
                .map(|i| corner(i).0.color),
        );
        mesh.indices.par_extend(
            (0..6 * leaves.len())
                .into_par_iter()
                .with_min_len(4096)
                .map(|i| indices(i / 6)[i % 6]),
        );
    }
}

/// The texture coordinates of a leaf quad's corners.
const QUAD_UVS: [Vec2; 4] = [
    Vec2::new(0.0, 0.0),
    Vec2::new(1.0, 0.0),
    Vec2::new(1.0, 1.0),
    Vec2::new(0.0, 1.0),
];

/// One leaf's quad: its corners, normal, tangent and colour.
struct Quad {
    positions: [Vec3; 4],
    normal: Vec3,
    tangent: Vec4,
    color: Vec4,
}

/// The quad of a leaf whose colour lies `mix` of the way between the options' two.
fn quad(leaf: &LeafPoint, options: &LeafOptions, mix: f32) -> Quad {
    let [c0, c1] = options.colors.map(Vec4::from_array);
    let size = options.card_length(if leaf.size > 0.0 && leaf.size.is_finite() {
        leaf.size
    } else {
        options.size
    });
    let axis = leaf.direction.try_normalize().unwrap_or(Vec3::Y);
    let side = (leaf.side - axis * leaf.side.dot(axis))
        .try_normalize()
        .unwrap_or_else(|| axis.any_orthonormal_vector());
    let l = axis * size;
    let s = side * (0.5 * size * options.width);
    let p = leaf.position;
    Quad {
        positions: [p - s, p + s, p + s + l, p - s + l],
        normal: side.cross(axis),
        // `u` grows along `side`, `v` along `axis`, which `cross(normal, side)` is: w = +1.
        tangent: side.extend(1.0),
        color: c0.lerp(c1, mix),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree() -> Skeleton {
        let mut s = Skeleton::new();
        let mut prev = s.push(Vec3::ZERO, None, 0.1, 0);
        for y in 1..=6 {
            prev = s.push(Vec3::new(0.0, y as f32, 0.0), Some(prev), 0.1, 0);
        }
        let fork = 3;
        let mut side = fork;
        for x in 1..=4 {
            side = s.push(
                Vec3::new(x as f32, 3.0 + x as f32, 0.0),
                Some(side),
                0.05,
                1,
            );
        }
        s
    }

    /// Parent steps from `node` down to a tip below it, if the node lies within `max` of one.
    fn depth_to_tip(s: &Skeleton, node: u32, max: u32) -> Option<u32> {
        s.tips().into_iter().find_map(|t| {
            let mut n = t;
            for d in 0..=max {
                if n == node {
                    return Some(d);
                }
                n = s.parents[n as usize]?;
            }
            None
        })
    }

    #[test]
    fn leaves_hang_near_tips_within_max_depth() {
        let s = tree();
        let opts = LeafOptions {
            per_tip: (5, 9),
            max_depth: 2,
            ..LeafOptions::default()
        };
        let mut rng = Mt64::new(3);
        let leaves = tip_leaves(&s, &opts, &mut rng);
        assert!(leaves.len() >= 10 && leaves.len() <= 18, "{}", leaves.len());
        for l in &leaves {
            assert!(
                depth_to_tip(&s, l.node, 2).is_some(),
                "leaf on node {}",
                l.node
            );
            let parent = s.parents[l.node as usize].expect("not a root");
            // The stalk point lies on the segment parent -> node.
            let (a, b) = (s.positions[parent as usize], s.positions[l.node as usize]);
            let t = (l.position - a).dot(b - a) / (b - a).length_squared();
            assert!((0.0..=1.0).contains(&t));
            assert!(((a + (b - a) * t) - l.position).length() < 1e-5);
            assert!((l.direction.length() - 1.0).abs() < 1e-5);
            assert!(l.direction.dot(l.side).abs() < 1e-5);
        }
        let zero = LeafOptions {
            max_depth: 0,
            ..opts
        };
        for l in tip_leaves(&s, &zero, &mut rng) {
            assert!(s.tips().contains(&l.node));
        }
    }

    /// The leaves by their definition: every draw taken where it is used, one leaf after
    /// another.
    fn tip_leaves_one_draw_at_a_time(
        skeleton: &Skeleton,
        options: &LeafOptions,
        rng: &mut Mt64,
    ) -> Vec<LeafPoint> {
        let mut out = Vec::new();
        for tip in skeleton.tips() {
            if skeleton.parents[tip as usize].is_none() {
                continue;
            }
            for _ in 0..int_in(rng, options.per_tip.0, options.per_tip.1) {
                let depth = int_in(rng, 0, options.max_depth);
                let draws: Vec<u64> = (0..5).map(|_| rng.next_u64()).collect();
                let with_depth: Vec<u64> = if options.max_depth > 0 {
                    // `leaf` reads the depth back from its first draw.
                    std::iter::once(u64::from(depth)).chain(draws).collect()
                } else {
                    draws
                };
                out.push(leaf(skeleton, options, tip, &with_depth));
            }
        }
        out
    }

    /// A skeleton of `n` nodes with a tip every few nodes.
    fn bushy(n: u32) -> Skeleton {
        let mut s = Skeleton::new();
        s.push(Vec3::ZERO, None, 0.1, 0);
        for i in 1..n {
            let parent = if i % 3 == 0 { i / 2 } else { i - 1 };
            let t = i as f32 * 0.7;
            let p = s.positions[parent as usize] + Vec3::new(math::sin(t), 0.5, math::cos(t)) * 0.3;
            s.push(p, Some(parent), 0.05, 1);
        }
        s
    }

    #[test]
    fn many_leaves_are_the_same_on_any_number_of_threads_and_as_drawn_one_by_one() {
        let s = bushy(3000);
        for max_depth in [0, 3] {
            let opts = LeafOptions {
                per_tip: (10, 30),
                max_depth,
                ..LeafOptions::default()
            };
            let mut reference_rng = Mt64::new(5);
            let reference = tip_leaves_one_draw_at_a_time(&s, &opts, &mut reference_rng);
            assert!(reference.len() > PARALLEL_FROM, "{}", reference.len());
            let on = |threads: usize| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("a pool")
                    .install(|| {
                        let mut rng = Mt64::new(5);
                        let leaves = tip_leaves(&s, &opts, &mut rng);
                        let mut mesh = Mesh::default();
                        append_leaf_quads(&leaves, &opts, &mut rng, &mut mesh);
                        (leaves, mesh, rng.next_u64())
                    })
            };
            let (leaves, mesh, next) = on(1);
            assert_eq!(leaves, reference);
            mesh.validate().expect("valid");
            assert_eq!(mesh.triangle_count(), 2 * leaves.len());
            // The colours took one draw a leaf after the leaves' own.
            let mut after = reference_rng;
            for _ in 0..reference.len() {
                after.next_u64();
            }
            assert_eq!(next, after.next_u64());
            for threads in [2, 4] {
                assert_eq!(
                    on(threads),
                    (leaves.clone(), mesh.clone(), next),
                    "{threads}"
                );
            }
        }
    }

    #[test]
    fn strahler_orders_count_from_the_tips() {
        // tree(): a trunk of 7 nodes and a side branch of 4 from node 3.
        let s = tree();
        let orders = strahler_orders(&s);
        // Two twigs (order 1) meet at node 3: it and the trunk below it are order 2.
        assert_eq!(orders, vec![2, 2, 2, 2, 1, 1, 1, 1, 1, 1, 1]);
        let mut s = s;
        // A third twig on the side branch makes no new order: 1 and 1 meet there, then 2
        // and 1 at node 3 keep 2.
        s.push(Vec3::new(2.0, 4.0, 1.0), Some(8), 0.05, 2);
        let orders = strahler_orders(&s);
        assert_eq!((orders[8], orders[3], orders[0]), (2, 2, 2));
    }

    #[test]
    fn cards_along_the_branches_follow_the_spacing_on_the_last_orders() {
        let s = tree();
        let tips_only = LeafOptions {
            per_tip: (0, 0),
            ..LeafOptions::default()
        };
        assert!(tip_leaves(&s, &tips_only, &mut Mt64::new(1)).is_empty());
        let along = |orders, spacing| LeafOptions {
            along: Some(Along { orders, spacing }),
            ..tips_only.clone()
        };
        // Order 1 only: the trunk above the fork (3 m) and the side branch (4 * sqrt 2 m),
        // a card every 0.5 m of path.
        let twigs = tip_leaves(&s, &along(1, 0.5), &mut Mt64::new(1));
        let path = 3.0 + 4.0 * 2f32.sqrt();
        assert!(
            (twigs.len() as f32 - path / 0.5).abs() <= 2.0,
            "{} cards on {path} m",
            twigs.len()
        );
        let orders = strahler_orders(&s);
        for l in &twigs {
            assert_eq!(orders[l.node as usize], 1, "node {}", l.node);
            assert!((l.direction.length() - 1.0).abs() < 1e-5);
        }
        // Two orders: the trunk below the fork too (3 m more).
        let both = tip_leaves(&s, &along(2, 0.5), &mut Mt64::new(1));
        assert!(
            both.len() >= twigs.len() + 5,
            "{} vs {}",
            both.len(),
            twigs.len()
        );
        // Halving the spacing doubles the cards; the same seed the same cards.
        let dense = tip_leaves(&s, &along(2, 0.25), &mut Mt64::new(1));
        assert!((dense.len() as i64 - 2 * both.len() as i64).abs() <= 2);
        assert_eq!(dense, tip_leaves(&s, &along(2, 0.25), &mut Mt64::new(1)));
        // Tip cards come first, then the cards along the branches.
        let with_tips = LeafOptions {
            per_tip: (2, 2),
            ..along(2, 0.5)
        };
        let all = tip_leaves(&s, &with_tips, &mut Mt64::new(1));
        assert_eq!(all.len(), 4 + both.len());
    }

    #[test]
    fn twig_cards_are_longer_than_their_leaves() {
        let leaf = LeafPoint {
            node: 0,
            position: Vec3::ZERO,
            direction: Vec3::Y,
            side: Vec3::X,
            size: 0.1,
        };
        let opts = LeafOptions {
            per_card: 9,
            ..LeafOptions::default()
        };
        let mut mesh = Mesh::default();
        append_leaf_quads(&[leaf], &opts, &mut Mt64::new(1), &mut mesh);
        let length = mesh.positions[3].distance(mesh.positions[0]);
        assert!((length - 0.1 / crate::textures::card_share(9)).abs() < 1e-6);
        assert!(length > 0.15 && length < 0.25, "{length}");
    }

    #[test]
    fn quads_are_hung_by_the_middle_of_an_edge() {
        let leaf = LeafPoint {
            node: 0,
            position: Vec3::new(1.0, 2.0, 3.0),
            direction: Vec3::Y,
            side: Vec3::X,
            size: 2.0,
        };
        let opts = LeafOptions {
            colors: [[1.0, 0.0, 0.0, 1.0]; 2],
            ..LeafOptions::default()
        };
        let mut mesh = Mesh::default();
        append_leaf_quads(&[leaf], &opts, &mut Mt64::new(1), &mut mesh);
        mesh.validate().expect("valid");
        assert_eq!(
            mesh.positions,
            vec![
                Vec3::new(0.0, 2.0, 3.0),
                Vec3::new(2.0, 2.0, 3.0),
                Vec3::new(2.0, 4.0, 3.0),
                Vec3::new(0.0, 4.0, 3.0)
            ]
        );
        assert_eq!((mesh.positions[0] + mesh.positions[1]) * 0.5, leaf.position);
        assert_eq!(mesh.normals[0], Vec3::Z);
        assert_eq!(mesh.colors[0], Vec4::new(1.0, 0.0, 0.0, 1.0));
        let [a, b, c] = [0, 1, 2].map(|i| mesh.positions[mesh.indices[i] as usize]);
        assert!(
            (b - a).cross(c - a).normalize().dot(Vec3::Z) > 0.99,
            "front face along the normal"
        );
    }

    #[test]
    fn colours_lie_between_the_two() {
        let opts = LeafOptions {
            colors: [[0.0, 0.2, 0.0, 1.0], [0.5, 0.6, 0.1, 1.0]],
            ..LeafOptions::default()
        };
        let s = tree();
        let mut rng = Mt64::new(9);
        let leaves = tip_leaves(&s, &opts, &mut rng);
        let mut mesh = Mesh::default();
        append_leaf_quads(&leaves, &opts, &mut rng, &mut mesh);
        for c in &mesh.colors {
            assert!(c.x >= 0.0 && c.x <= 0.5 && c.y >= 0.2 && c.y <= 0.6, "{c}");
            assert!(
                ((c.x / 0.5) - (c.y - 0.2) / 0.4).abs() < 1e-4,
                "on the segment between"
            );
        }
    }
}
