//! Leaf-collapse simplification (seed 003, §2.4.1 "Criterio de selección", after the FSA of
//! Remolar et al.): repeatedly collapse the pair of leaves that minimises a weighted
//! distance, within bounds that forbid far or differently oriented pairs, until no pair is
//! allowed. The result is the collapse forest ([`Chain`]).
//!
//! The thesis evaluates every pair at every step (cubic in the number of leaves). Here the
//! collapses come in rounds of greedy matching. A round lays the living leaves out in a
//! dense uniform grid; each leaf made by the last round (at first, every leaf) searches it
//! for its nearest partners within the distance and angle bounds (`NEAREST` of them) and
//! weighs each pair. The round's pairs are then taken cheapest first, and a pair whose two
//! leaves still live collapses if its new leaf keeps the area bounds; only then are the
//! bounds tested, as most pairs are reached after one of their leaves has gone (about a
//! quarter of them are tested, and the result is the same as testing every pair when
//! found). Most tested pairs that the overhang bound refuses are refused by a sound
//! pre-test without building their new leaf ([`Leaf::surely_reaches`]); the others build it
//! once ([`Leaf::collapse`]), for the full test, and a pair that passes keeps that leaf. A
//! pair a search has found needs no second look (one of its leaves has gone, or the round
//! that found it would have collapsed it, or the area bounds refused it), so later rounds
//! search only around the new leaves. Pairs beyond each other's nearest `NEAREST` are what
//! the sweeps are for: when a round makes nothing, a sweep searches again with more
//! partners (`SWEEP`) around every living leaf made since the last sweep began (the first
//! sweep: around every leaf); the simplification ends when a sweep makes nothing. This is a
//! heuristic, not an exhaustive search: a pair of two leaves that are beyond each other's
//! nearest `SWEEP` when a sweep searches around them is not tested again (the quality
//! figures in benches/README.md, not a proof, justify it). A refused pair is refused once,
//! in the round that found it: it never waits in a queue, and no leaf searches again
//! because of it.
//!
//! A pair of two leaves that both search in a round is looked at only by the one in the
//! earlier grid slot: each cell lays out the leaves made before the round first, so in the
//! cells before its own a search reads only those, about half the slots of the first rounds.
//! The searches of a round go cell by cell, so neighbouring searches read the same memory;
//! the grid keeps what the distance test reads (centre and radius) in one array and a copy
//! of each leaf beside it, cell after cell; a search skips the cells that cannot hold a
//! partner (by the cell's box and largest radius) and reads the slots of the cells it keeps
//! that lie side by side in memory (a row of a ring) as one run. Nothing is allocated per
//! collapse; the result is deterministic (pairs are ordered by cost, then by their labels).

use glam::Vec3;

use crate::leaf::Leaf;

mod driver;
mod grid;
mod search;

use driver::Simplifier;

/// The most partners of a leaf a search lists (its nearest within the distance and angle
/// bounds).
const NEAREST: usize = 16;

/// The same for the searches of a sweep, once the rounds have run out of pairs.
const SWEEP: usize = 64;

/// Weights of the collapse distance's terms (seed 003 §2.4.1). Every term is dimensionless,
/// so the weights compare directly; a weight of 0 switches its term off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weights {
    /// Euclidean distance between the centres, divided by the sum of both leaves' radii.
    pub distance: f32,
    /// Coplanarity: `1 - |cos|` of the angle between the normals (0 for parallel planes).
    pub coplanarity: f32,
    /// Difference of represented-leaf counts, `|na - nb| / (na + nb)`: balanced collapses.
    pub count: f32,
    /// Difference of areas, `|Aa - Ab| / (Aa + Ab)`: large leaves do not swallow small ones.
    pub area: f32,
    /// Interiority: distance from the pair's midpoint to the tree's axis over the crown's
    /// radius, so inner leaves (least visible from afar) collapse first.
    pub interiority: f32,
}

impl Default for Weights {
    fn default() -> Self {
        Weights {
            distance: 1.0,
            coplanarity: 0.5,
            count: 0.5,
            area: 0.25,
            interiority: 0.25,
        }
    }
}

/// The bounds that forbid a pair whatever its distance (seed 003 §2.4.1: "valores frontera
/// ... previene el emparejamiento de hojas muy alejadas ... u orientadas en direcciones muy
/// diferentes").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Largest centre distance, in units of the sum of both leaves' radii.
    pub max_distance: f32,
    /// Largest angle between the two leaves' planes, in degrees (0..=90; leaves are
    /// double-sided, so a normal and its opposite are the same plane).
    pub max_angle: f32,
    /// Largest area of the new leaf over the pair's summed areas: the thesis sets the new
    /// area halfway between the summed and the bounding area "to avoid a large increase";
    /// this refuses the pairs whose bounding quad is mostly empty (a large leaf swallowing a
    /// small one across its diagonal would otherwise grow without end).
    pub max_growth: f32,
    /// Smallest density (represented leaf area over the new leaf's area) of a new leaf:
    /// coarse leaves may thin out, but not into empty quads.
    pub min_density: f32,
    /// How far a new leaf's corners may reach past the box around the original leaves it
    /// represents, as a fraction of that box's size per axis: coarse leaves stay within the
    /// crown instead of compounding the bounding quads' slack level after level.
    pub max_overhang: f32,
}

impl Default for Bounds {
    fn default() -> Self {
        Bounds {
            max_distance: 1.5,
            max_angle: 75.0,
            max_growth: 2.0,
            min_density: 0.1,
            max_overhang: 0.1,
        }
    }
}

/// The vertical line the interiority term measures from: the tree's main axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axis {
    /// A point on the axis (the trunk's base).
    pub origin: Vec3,
    /// Its unit direction.
    pub direction: Vec3,
}

impl Axis {
    /// The default axis: vertical through the centre of the leaves' bounding box, from its
    /// bottom.
    pub(crate) fn through_crown(leaves: &[Leaf]) -> Axis {
        let (lo, hi) = leaves.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), l| (lo.min(l.center), hi.max(l.center)),
        );
        let mid = (lo + hi) * 0.5;
        Axis {
            origin: Vec3::new(mid.x, lo.y, mid.z),
            direction: Vec3::Y,
        }
    }

    /// Distance from `p` to the axis.
    #[must_use]
    pub fn distance(&self, p: Vec3) -> f32 {
        let d = p - self.origin;
        (d - self.direction * d.dot(self.direction)).length()
    }
}

/// The collapse forest (seed 003 §2.5.1, figure 2.3): the original leaves `0..originals`,
/// then each new leaf in the order it was made, with the two leaves it replaced.
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    /// Every leaf of the chain (the thesis' M), labelled by position.
    pub leaves: Vec<Leaf>,
    /// How many of `leaves` are original (the thesis' |O|).
    pub originals: usize,
    /// For new leaf `originals + k`, the labels of the two leaves it replaced.
    pub children: Vec<[u32; 2]>,
}

impl Chain {
    /// A chain without collapses.
    #[must_use]
    pub fn flat(leaves: Vec<Leaf>) -> Chain {
        Chain {
            originals: leaves.len(),
            leaves,
            children: Vec::new(),
        }
    }

    /// For every label, the leaf that replaced it (`None` for a root).
    #[must_use]
    pub fn parents(&self) -> Vec<Option<u32>> {
        let mut parents = vec![None; self.leaves.len()];
        for (k, pair) in self.children.iter().enumerate() {
            for &c in pair {
                parents[c as usize] = Some((self.originals + k) as u32);
            }
        }
        parents
    }

    /// The roots (leaves never collapsed, the thesis' R), by increasing label.
    #[must_use]
    pub fn roots(&self) -> Vec<u32> {
        self.parents()
            .iter()
            .enumerate()
            .filter(|(_, p)| p.is_none())
            .map(|(i, _)| i as u32)
            .collect()
    }
}

/// Everything the selection needs besides the leaves.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Selection {
    /// The distance's weights.
    pub weights: Weights,
    /// The bounds.
    pub bounds: Bounds,
    /// The tree's axis; `None`: the vertical through the centre of the leaves' bounding box.
    pub axis: Option<Axis>,
    /// When the run must stop (`--time-limit`): the simplification stops there, its chain
    /// unfinished ([`crate::lod_mesh`] then fails with the time limit). `None`: no limit.
    pub deadline: Option<pge_engine::clock::Instant>,
}

/// Simplifies `leaves` into a collapse chain: until no allowed pair is left, collapse the
/// pair minimising the weighted distance of [`Weights`] within [`Bounds`] into
/// [`Leaf::collapse`]. Leaves must be finite with positive areas ([`Leaf::from_quad`]
/// builds such leaves).
#[must_use]
pub fn simplify(leaves: &[Leaf], selection: &Selection) -> Chain {
    let mut s = Simplifier::new(leaves, selection);
    s.run();
    Chain {
        leaves: s.leaves,
        originals: leaves.len(),
        children: s.children,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::math;

    fn leaf(center: Vec3, normal: Vec3) -> Leaf {
        Leaf {
            center,
            normal,
            axis: normal.any_orthonormal_vector(),
            half_length: 0.5,
            half_width: 0.5,
            count: 1,
            leaf_area: 1.0,
            lo: center - Vec3::splat(0.75),
            hi: center + Vec3::splat(0.75),
        }
    }

    #[test]
    fn the_closest_pair_collapses_first_and_far_pairs_never() {
        let leaves = [
            leaf(Vec3::new(0.0, 0.0, 0.0), Vec3::Z),
            leaf(Vec3::new(10.0, 0.0, 0.0), Vec3::Z),
            leaf(Vec3::new(0.5, 0.0, 0.0), Vec3::Z),
            leaf(Vec3::new(100.0, 0.0, 0.0), Vec3::Z),
        ];
        let chain = simplify(&leaves, &Selection::default());
        assert_eq!(chain.children[0], [0, 2]);
        // Leaf 1 is 10 m away (bound: 2 x the radii), leaf 3 further: both stay roots.
        assert_eq!(chain.children.len(), 1);
        assert_eq!(chain.roots(), vec![1, 3, 4]);
        assert_eq!(chain.parents()[0], Some(4));
    }

    #[test]
    fn perpendicular_leaves_do_not_collapse() {
        let leaves = [
            leaf(Vec3::ZERO, Vec3::Z),
            leaf(Vec3::new(0.5, 0.0, 0.0), Vec3::X),
        ];
        let chain = simplify(&leaves, &Selection::default());
        assert!(chain.children.is_empty());
        let loose = Selection {
            bounds: Bounds {
                max_angle: 90.0,
                ..Bounds::default()
            },
            ..Selection::default()
        };
        assert_eq!(simplify(&leaves, &loose).children.len(), 1);
    }

    #[test]
    fn a_row_of_leaves_collapses_into_one_balanced_tree() {
        let leaves: Vec<Leaf> = (0..16)
            .map(|i| leaf(Vec3::new(i as f32 * 0.9, 0.0, 0.0), Vec3::Z))
            .collect();
        let chain = simplify(&leaves, &Selection::default());
        assert_eq!(chain.children.len(), 15);
        assert_eq!(chain.roots(), vec![30]);
        let root = chain.leaves[30];
        assert_eq!(root.count, 16);
        // Every leaf is represented exactly once below the root.
        let mut seen = [0; 16];
        let mut stack = vec![30u32];
        while let Some(n) = stack.pop() {
            if (n as usize) < 16 {
                seen[n as usize] += 1;
            } else {
                stack.extend(chain.children[n as usize - 16]);
            }
        }
        assert!(seen.iter().all(|&c| c == 1));
    }

    #[test]
    fn simplification_is_deterministic() {
        let leaves: Vec<Leaf> = (0..200)
            .map(|i| {
                let t = i as f32 * 0.37;
                leaf(
                    Vec3::new(
                        math::sin(t) * 3.0,
                        (i % 17) as f32 * 0.3,
                        math::cos(t) * 3.0,
                    ),
                    Vec3::new(math::cos(t), 0.3, math::sin(t)).normalize(),
                )
            })
            .collect();
        let a = simplify(&leaves, &Selection::default());
        let b = simplify(&leaves, &Selection::default());
        assert_eq!(a, b);
        assert!(a.children.len() > 100, "{}", a.children.len());
    }

    /// `n` leaves of a small round crown: random centres in a shell, random orientations
    /// and sizes (the refusals of the area bounds are most pairs there).
    fn crown(n: usize, seed: u64) -> Vec<Leaf> {
        let mut rng = rand_mt::Mt64::new(seed);
        let mut u = move || (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        (0..n)
            .map(|_| {
                let dir = Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize_or(Vec3::Y);
                let center = dir * (2.0 + u());
                let normal = (dir + Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5)).normalize();
                let (e1, e2) = normal.any_orthonormal_pair();
                let (l, w) = (0.1 + 0.2 * u(), 0.05 + 0.1 * u());
                let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                    .map(|(x, y)| center + e1 * (x * w) + e2 * (y * l));
                Leaf::from_quad(corners, Some(normal)).expect("leaf")
            })
            .collect()
    }

    /// The area bounds are tested once for a pair, when its round's matching reaches it
    /// with both leaves living: every collapse of the chain must keep them, checked here on
    /// the chain's own leaves with the corners themselves.
    #[test]
    fn every_collapse_keeps_the_area_bounds() {
        let bounds = Bounds::default();
        for seed in 1..=4 {
            let chain = simplify(&crown(1500, seed), &Selection::default());
            assert!(chain.roots().len() * 10 <= chain.originals, "seed {seed}");
            for (k, &[a, b]) in chain.children.iter().enumerate() {
                let new = &chain.leaves[chain.originals + k];
                let (la, lb) = (&chain.leaves[a as usize], &chain.leaves[b as usize]);
                let area = new.area();
                let tolerance = 1e-5 * (1.0 + area);
                assert!(area <= bounds.max_growth * (la.area() + lb.area()) + tolerance);
                assert!(new.leaf_area + tolerance >= bounds.min_density * area);
                assert_eq!(new.count, la.count + lb.count);
                let size = new.hi - new.lo;
                let slack = size * bounds.max_overhang + Vec3::splat(1e-5 * size.max_element());
                for c in new.corners() {
                    assert!(c.cmpge(new.lo - slack).all() && c.cmple(new.hi + slack).all());
                }
            }
        }
    }

    /// The overhang pre-test refuses no pair the full test keeps: every pair of leaves near
    /// each other among the original leaves of a crown and the leaves its chain makes (of
    /// every size and count), tested both ways.
    #[test]
    fn the_pre_test_refuses_only_what_the_full_test_refuses() {
        let chain = simplify(&crown(700, 5), &Selection::default());
        let s = Simplifier::new(&chain.leaves, &Selection::default());
        let (mut refused, mut pre_refused) = (0, 0);
        for (i, a) in chain.leaves.iter().enumerate() {
            for b in &chain.leaves[i + 1..] {
                let reach = 3.0 * (a.radius() + b.radius());
                if a.center.distance_squared(b.center) > reach * reach {
                    continue;
                }
                for (a, b) in [(a, b), (b, a)] {
                    let keeps = s.keeps_bounds(a, b);
                    assert_eq!(s.fits(a, b), keeps, "{a:?} {b:?}");
                    refused += usize::from(keeps.is_none());
                    pre_refused += usize::from(s.surely_overhangs(a, b));
                }
            }
        }
        // And it refuses most of what the full test refuses.
        assert!(pre_refused * 2 >= refused, "{pre_refused} of {refused}");
    }
}
