//! A forest's triangle budget in the preview: which instances of which variant mesh are
//! drawn, and how finely, in one frame.
//!
//! A forest is drawn with instanced draws, one set per variant mesh. Every frame (when the
//! camera or the budget changes) the instances in view are found and given a level:
//!
//! - a leaf mesh with levels of detail gets a number of leaves from its distance by the
//!   thesis' Scaling ([`pge_lod::assign_into`], `near` and `far` the nearest and farthest
//!   instance in view), the leaf budget T shared between the leaf meshes in proportion to
//!   what their instances ask for; that number is rounded down to one of a few *bands*
//!   (leaf counts halving from the original leaves to the coarsest level), each drawn with
//!   the two ranges of V per sector of its level;
//! - any other mesh (bark, leaves without levels) is drawn whole for the nearest instances,
//!   as its coarse version (its largest eighth of triangles, or an eighth of its leaves)
//!   for the next, and not at all beyond, within a budget of T triangles.
//!
//! So a frame draws at most 2T leaf triangles plus T others, whatever the forest's size.
//! Instances are grouped per (mesh, band): each mesh's instance buffer is rewritten in band
//! order and a band is one instanced draw per range; the geometry itself never changes.

use std::ops::Range;

use glam::{Mat4, Vec3, Vec4};
use pge_lod::{Budget, assign_into};
use rayon::prelude::*;

use super::lod::LeafLod;

/// The leaf budget (T) of a frame at rest when none is given. Measured on
/// `scripts/forests/big.lua` (106,605 trees, framed whole) with Mesa's software renderer:
/// every tree in view needs about 1.2 million leaves at its fewest; 2 million draw all of
/// them, the nearest finer, in about 6 million triangles (the whole `--screenshot` run
/// 15 s, of which 7 to 9 s generation); 4 million took 26 s.
pub const DEFAULT_LEAF_BUDGET: u64 = 2_000_000;

/// The fewest leaves of a far tree are its coarsest level's over this, drawn grown.
pub const SUB_ROOTS: u32 = 8;

/// How much leaves are grown (in width and length) for bands below the coarsest level: the
/// fewest leaves keep about the coarsest level's leaf area.
pub const GROWN: f32 = 2.83;

/// While the camera moves, frames draw this share of the budget. Measured on
/// `scripts/forests/big.lua` with Mesa's software renderer (`--orbit-frames`, load 10 to
/// 14 on 2 cores): with a 32nd (62,500 leaves and as many bark triangles of the default
/// budget) the renderer took 110 to 400 ms per moving frame, with a 128th 13 to 120 ms.
pub const MOVING_SHARE: u64 = 128;

/// While the camera moves, plans are made for a view this much wider (and taller) than the
/// frame's: a plan is drawn a frame or two after the camera it was made for, and the margin
/// keeps the trees at the frame's edges that came into view meanwhile.
pub const MOVING_MARGIN: f32 = 1.25;

/// The leaf budgets `--leaf-budget` and the side panel's slider allow.
pub const LEAF_BUDGETS: std::ops::RangeInclusive<u64> = 100..=100_000_000;

/// One leaf count a leaf mesh is drawn at: the ranges of its sequential quads (six indices
/// per leaf) and the leaves they draw.
#[derive(Clone, Debug, PartialEq)]
pub struct LeafBand {
    /// Leaves drawn.
    pub leaves: u32,
    /// Part of the coarsest level only, drawn with grown leaves ([`LeafLod::grown`],
    /// [`GROWN`]).
    pub grown: bool,
    /// Index ranges into [`LeafLod::quad_indices`].
    pub ranges: Vec<Range<u32>>,
}

/// What a forest mesh can draw for one instance.
#[derive(Clone, Debug, PartialEq)]
pub enum Detail {
    /// Leaves with levels of detail: bands by decreasing leaf count, with the mesh's
    /// original leaf count and the fewest leaves a band draws.
    Leaves {
        /// The bands, finest first.
        bands: Vec<LeafBand>,
        /// Original leaves (|O|).
        leaves: u32,
        /// Leaves of the last band: what the Scaling treats as the coarsest level.
        least: u32,
    },
    /// A mesh without levels: its `full` index count, or the index count of its coarse
    /// version (`None`: it has none, and is drawn whole or not at all).
    Rigid {
        /// Indices of the whole mesh.
        full: u32,
        /// Indices of its coarse version.
        coarse: Option<u32>,
    },
}

impl Detail {
    /// The bands of a leaf mesh with levels: its original leaves, then halving down to its
    /// coarsest level and on below it to an eighth of it ([`SUB_ROOTS`]), those drawn grown
    /// ([`LeafLod::leaf_ranges`]; bands that would draw as many leaves as a finer one are
    /// left out).
    #[must_use]
    pub fn leaves(lod: &LeafLod) -> Detail {
        let (leaves, roots) = (lod.leaves(), lod.roots());
        let fewest = (roots / SUB_ROOTS).max(1);
        let mut bands: Vec<LeafBand> = Vec::new();
        let mut want = leaves;
        while want >= fewest {
            let (ranges, drawn) = lod.leaf_ranges(want);
            if drawn > 0 && bands.last().is_none_or(|b| drawn < b.leaves) {
                bands.push(LeafBand {
                    leaves: drawn,
                    grown: want < roots,
                    ranges,
                });
            }
            // The coarsest level is a band of its own.
            want = if want > roots && want / 2 < roots {
                roots
            } else {
                want / 2
            };
        }
        let least = bands.last().map_or(0, |b| b.leaves);
        Detail::Leaves {
            bands,
            leaves,
            least,
        }
    }
}

/// One instanced mesh of a forest as the planner sees it.
#[derive(Clone, Copy, Debug)]
pub struct ForestMesh<'a> {
    /// Column-major local-to-world matrices, one per instance.
    pub instances: &'a [[f32; 16]],
    /// Centre of a sphere around the mesh, in its own frame.
    pub centre: Vec3,
    /// Radius of that sphere.
    pub radius: f32,
    /// What it can draw.
    pub detail: &'a Detail,
}

/// Which index buffer a draw reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// The mesh's own indices.
    Full,
    /// Its coarse version's indices (and vertices).
    Coarse,
    /// The sequential quads over V of a leaf mesh with levels.
    Quads,
    /// The same quads over grown leaves ([`LeafLod::grown`]).
    Grown,
}

/// One instanced draw.
#[derive(Clone, Debug, PartialEq)]
pub struct Draw {
    /// The index buffer.
    pub source: Source,
    /// Indices drawn.
    pub indices: Range<u32>,
    /// Instances drawn: positions in [`MeshPlan::order`].
    pub instances: Range<u32>,
}

impl Draw {
    /// Triangles this draw contains.
    #[must_use]
    pub fn triangles(&self) -> u64 {
        u64::from(self.indices.len() as u32 / 3) * u64::from(self.instances.len() as u32)
    }
}

/// What one mesh draws in a frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshPlan {
    /// Indices of the instances drawn, grouped by band: what the instance buffer holds.
    pub order: Vec<u32>,
    /// The draws, each over a run of `order`.
    pub draws: Vec<Draw>,
}

/// A frame's plan for every forest mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Plan {
    /// One per mesh given to [`plan`], in the same order.
    pub meshes: Vec<MeshPlan>,
    /// Leaves drawn by leaf meshes with levels.
    pub leaves: u64,
    /// Triangles drawn, counted as the bands are filled.
    pub triangles: u64,
}

/// Where the camera is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// The eye.
    pub eye: Vec3,
    /// Projection times view (depth in [0, 1]).
    pub view_proj: Mat4,
}

/// The six planes of the view frustum, `(normal, d)` with `normal . p + d >= 0` inside.
fn frustum(m: Mat4) -> [Vec4; 6] {
    let r = m.transpose();
    let (r0, r1, r2, r3) = (r.x_axis, r.y_axis, r.z_axis, r.w_axis);
    [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2].map(|p| {
        let n = p.truncate().length();
        if n > 0.0 { p / n } else { p }
    })
}

/// The instances of `mesh` whose sphere is in view, with their distances to the eye.
fn in_view(mesh: &ForestMesh, view: &View, planes: &[Vec4; 6]) -> Vec<(u32, f32)> {
    mesh.instances
        .iter()
        .enumerate()
        .filter_map(|(i, m)| {
            let m = Mat4::from_cols_array(m);
            let centre = m.transform_point3(mesh.centre);
            let scale = m.x_axis.truncate().length();
            let r = mesh.radius * scale;
            let inside = planes.iter().all(|p| p.truncate().dot(centre) + p.w >= -r);
            let origin = m.w_axis.truncate();
            let d = origin.distance(view.eye);
            (inside && d.is_finite()).then_some((i as u32, d))
        })
        .collect()
}

/// What planning keeps from one plan to the next (the planner thread holds one), so that
/// the leaf meshes' Scaling allocates nothing once its buffers have grown to the instances
/// in view. Their contents never carry over: a plan is the same with new buffers.
#[derive(Debug, Default)]
pub struct PlanBuffers {
    /// Per mesh given to [`plan`], in the same order: its instances' distances and leaf
    /// counts ([`assign_into`]).
    meshes: Vec<LeafBuffers>,
}

#[derive(Debug, Default)]
struct LeafBuffers {
    distances: Vec<f32>,
    counts: Vec<u32>,
}

/// Plans a frame: every instance in view of every mesh gets at most one band; the leaves
/// drawn are at most `leaf_budget`, the other meshes' triangles at most `leaf_budget` too.
/// `buffers` are reused from earlier plans.
#[must_use]
pub fn plan(
    meshes: &[ForestMesh],
    view: &View,
    leaf_budget: u64,
    buffers: &mut PlanBuffers,
) -> Plan {
    let planes = frustum(view.view_proj);
    let visible: Vec<Vec<(u32, f32)>> = meshes
        .par_iter()
        .map(|m| in_view(m, view, &planes))
        .collect();
    let mut out = Plan {
        meshes: vec![MeshPlan::default(); meshes.len()],
        ..Plan::default()
    };
    let (near, far) = visible
        .iter()
        .flatten()
        .fold((f32::INFINITY, 0.0f32), |(lo, hi), &(_, d)| {
            (lo.min(d), hi.max(d))
        });
    if near > far {
        return out; // nothing in view
    }
    let budget = Budget {
        near,
        far,
        total: 0,
    };
    plan_leaves(meshes, &visible, budget, leaf_budget, buffers, &mut out);
    plan_rigid(meshes, &visible, leaf_budget, &mut out);
    out
}

/// The leaf meshes with levels: each its share of the budget by Scaling, then bands.
fn plan_leaves(
    meshes: &[ForestMesh],
    visible: &[Vec<(u32, f32)>],
    budget: Budget,
    total: u64,
    buffers: &mut PlanBuffers,
    out: &mut Plan,
) {
    // What each mesh's instances ask for (the tentative counts) and need at least (all
    // at their fewest leaves), to share T by.
    let (asked, least): (Vec<u64>, Vec<u64>) = meshes
        .iter()
        .zip(visible)
        .map(|(m, seen)| match m.detail {
            Detail::Leaves { leaves, least, .. } => (
                seen.iter()
                    .map(|&(_, d)| u64::from(budget.tentative(d, *leaves, *least)))
                    .sum(),
                seen.len() as u64 * u64::from(*least),
            ),
            Detail::Rigid { .. } => (0, 0),
        })
        .unzip();
    let shares = share(total, &asked, &least);
    // Each mesh on its own (in parallel, merged in order).
    buffers
        .meshes
        .resize_with(meshes.len(), LeafBuffers::default);
    let planned: Vec<Option<(MeshPlan, u64)>> = meshes
        .par_iter()
        .zip(visible)
        .zip(&shares)
        .zip(&mut buffers.meshes)
        .map(|(((mesh, seen), &share), buffers)| plan_leaf_mesh(mesh, seen, budget, share, buffers))
        .collect();
    for (k, planned) in planned.into_iter().enumerate() {
        if let Some((plan, leaves)) = planned {
            out.leaves += leaves;
            out.triangles += 2 * leaves;
            out.meshes[k] = plan;
        }
    }
}

/// One leaf mesh's plan for its `share` of the leaves and the leaves it draws, with the
/// Scaling's `buffers`; `None` for a mesh without levels (or one the Scaling refused: not
/// drawn).
fn plan_leaf_mesh(
    mesh: &ForestMesh,
    seen: &[(u32, f32)],
    budget: Budget,
    share: u64,
    buffers: &mut LeafBuffers,
) -> Option<(MeshPlan, u64)> {
    let Detail::Leaves {
        bands,
        leaves,
        least,
    } = mesh.detail
    else {
        return None;
    };
    let LeafBuffers { distances, counts } = buffers;
    distances.clear();
    distances.extend(seen.iter().map(|&(_, d)| d));
    let budget = Budget {
        total: share,
        ..budget
    };
    // Distances are finite and non-negative and near <= far, so this cannot fail; if it
    // did, the mesh would simply not be drawn.
    assign_into(distances, *leaves, *least, &budget, counts).ok()?;
    // The finest band not above each instance's count (`bands.len()`: none).
    let none = bands.len();
    let mut chosen: Vec<usize> = counts
        .iter()
        .map(|&c| {
            if c == 0 {
                none
            } else {
                bands.iter().position(|b| b.leaves <= c).unwrap_or(none)
            }
        })
        .collect();
    let drawn: u64 = chosen
        .iter()
        .filter_map(|&b| bands.get(b))
        .map(|b| u64::from(b.leaves))
        .sum();
    upgrade(seen, &mut chosen, bands, share.saturating_sub(drawn));
    let chosen: Vec<Option<usize>> = chosen.iter().map(|&b| (b < none).then_some(b)).collect();
    let runs = group(seen, &chosen, bands.len());
    let mut plan = MeshPlan::default();
    let mut total = 0;
    for (band, instances) in bands.iter().zip(runs.ranges) {
        if instances.is_empty() {
            continue;
        }
        total += u64::from(band.leaves) * u64::from(instances.len() as u32);
        for r in &band.ranges {
            plan.draws.push(Draw {
                source: if band.grown {
                    Source::Grown
                } else {
                    Source::Quads
                },
                indices: r.clone(),
                instances: instances.clone(),
            });
        }
    }
    plan.order = runs.order;
    Some((plan, total))
}

/// Shares `total` leaves between meshes that ask for `asked` and need `least` (every
/// instance at its fewest leaves): each first gets what it needs, then the rest in
/// proportion to what it asks beyond that; when even the needs do not fit, each gets its
/// proportional part of them (and leaves out its farthest instances). The shares add up to
/// at most `total`.
fn share(total: u64, asked: &[u64], least: &[u64]) -> Vec<u64> {
    let need: u64 = least.iter().sum();
    let more: u64 = asked
        .iter()
        .zip(least)
        .map(|(a, l)| a.saturating_sub(*l))
        .sum();
    let part = |n: u64, of: u64, d: u64| {
        if d == 0 {
            0
        } else {
            (u128::from(n) * u128::from(of) / u128::from(d)) as u64
        }
    };
    asked
        .iter()
        .zip(least)
        .map(|(&a, &l)| {
            if total < need {
                part(total, l, need)
            } else {
                l + part(total - need, a.saturating_sub(l), more)
            }
        })
        .collect()
}

/// Spends what rounding down to bands left of a mesh's share, `left` leaves: the nearest
/// instances move one band finer each, in order of distance, until the next one cannot
/// afford it; again while that moves any. Moving a nearest run keeps nearer instances at no
/// fewer leaves than farther ones.
fn upgrade(seen: &[(u32, f32)], chosen: &mut [usize], bands: &[LeafBand], mut left: u64) {
    let leaves = |b: usize| bands.get(b).map_or(0, |b| u64::from(b.leaves));
    let mut by_distance: Vec<(u32, u32)> = seen
        .iter()
        .enumerate()
        .map(|(j, &(_, d))| (d.to_bits(), j as u32))
        .collect();
    by_distance.sort_unstable();
    for _ in 0..bands.len() {
        let mut moved = false;
        for &(_, j) in &by_distance {
            let b = chosen[j as usize];
            if b == 0 {
                continue;
            }
            let cost = leaves(b - 1) - leaves(b);
            if cost > left {
                break;
            }
            left -= cost;
            chosen[j as usize] = b - 1;
            moved = true;
        }
        if !moved {
            break;
        }
    }
}

/// Instances grouped by their band: the order and each band's run in it.
struct Runs {
    order: Vec<u32>,
    ranges: Vec<Range<u32>>,
}

/// Groups the `seen` instances by `chosen` band (a counting sort; `None` is left out).
fn group(seen: &[(u32, f32)], chosen: &[Option<usize>], bands: usize) -> Runs {
    let mut counts = vec![0u32; bands];
    for b in chosen.iter().flatten() {
        counts[*b] += 1;
    }
    let mut ranges = Vec::with_capacity(bands);
    let mut start = 0;
    for c in &counts {
        ranges.push(start..start + c);
        start += c;
    }
    let mut next: Vec<u32> = ranges.iter().map(|r| r.start).collect();
    let mut order = vec![0u32; start as usize];
    for (&(i, _), b) in seen.iter().zip(chosen) {
        if let Some(b) = b {
            order[next[*b] as usize] = i;
            next[*b] += 1;
        }
    }
    Runs { order, ranges }
}

/// The meshes without levels, over all of them by distance: the nearest whole, the next
/// coarse, within `budget` triangles. The coarse ones take at most half of it, unless the
/// whole meshes leave more.
fn plan_rigid(meshes: &[ForestMesh], visible: &[Vec<(u32, f32)>], budget: u64, out: &mut Plan) {
    let cost = |k: usize| match meshes[k].detail {
        Detail::Rigid { full, coarse } => {
            let full = u64::from(*full / 3);
            Some((full, coarse.map_or(full, |c| u64::from(c / 3))))
        }
        Detail::Leaves { .. } => None,
    };
    // (distance bits, mesh, position in its visible list): distances are non-negative, so
    // their bits order like them.
    let mut entries: Vec<(u32, u32, u32)> = Vec::new();
    for (k, seen) in visible.iter().enumerate() {
        if cost(k).is_some() {
            entries.extend(
                seen.iter()
                    .enumerate()
                    .map(|(j, &(_, d))| (d.to_bits(), k as u32, j as u32)),
            );
        }
    }
    if entries.is_empty() {
        return;
    }
    entries.sort_unstable();
    let costs: Vec<(u64, u64)> = entries
        .iter()
        .map(|&(_, k, _)| cost(k as usize).unwrap_or_default())
        .collect();
    // Coarse for the nearest that fit in half the budget...
    let mut coarse_sum = 0u64;
    let mut coarse_end = 0;
    for &(_, c) in &costs {
        if coarse_sum + c > budget / 2 {
            break;
        }
        coarse_sum += c;
        coarse_end += 1;
    }
    // ...then whole for the nearest of those while the rest of the budget lasts.
    let mut spent = coarse_sum;
    let mut full_end = 0;
    for &(f, c) in &costs[..coarse_end] {
        if spent - c + f > budget {
            break;
        }
        spent = spent - c + f;
        full_end += 1;
    }
    // Per mesh: band 0 whole, band 1 coarse.
    let mut chosen: Vec<Vec<Option<usize>>> =
        visible.iter().map(|seen| vec![None; seen.len()]).collect();
    for (rank, &(_, k, j)) in entries.iter().enumerate().take(coarse_end) {
        chosen[k as usize][j as usize] = Some(usize::from(rank >= full_end));
    }
    for (k, seen) in visible.iter().enumerate() {
        let Detail::Rigid { full, coarse } = meshes[k].detail else {
            continue;
        };
        // Without a coarse version, "coarse" instances draw whole: one band.
        if coarse.is_none() {
            for c in chosen[k].iter_mut().flatten() {
                *c = 0;
            }
        }
        let runs = group(seen, &chosen[k], 2);
        let plan = &mut out.meshes[k];
        for (band, instances) in runs.ranges.into_iter().enumerate() {
            if instances.is_empty() {
                continue;
            }
            let (source, count) = match (band, coarse) {
                (1, Some(c)) => (Source::Coarse, *c),
                _ => (Source::Full, *full),
            };
            let draw = Draw {
                source,
                indices: 0..count,
                instances,
            };
            out.triangles += draw.triangles();
            plan.draws.push(draw);
        }
        plan.order = runs.order;
    }
}

#[cfg(test)]
mod tests;
