//! Leaf-collapse simplification (seed 003, §2.4.1 "Criterio de selección", after the FSA of
//! Remolar et al.): repeatedly collapse the pair of leaves that minimises a weighted
//! distance, within bounds that forbid far or differently oriented pairs, until no pair is
//! allowed. The result is the collapse forest ([`Chain`]).
//!
//! The thesis evaluates every pair at every step (cubic in the number of leaves). Here the
//! candidates of a leaf are the living leaves in the 8 cells of a uniform grid nearest it
//! (the grid is rebuilt coarser as leaves merge), each leaf keeps its best candidate in a
//! priority queue, and stale entries are refreshed lazily when popped: a pair whose partner
//! has gone makes the survivor look for a new best, and a new leaf looks for its own. Costs
//! never change while both leaves live, so every collapse joins the cheapest pair the queue
//! knows of; the result is deterministic (ties go to the lower label).

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::hash::{BuildHasherDefault, Hasher};

use glam::Vec3;

use crate::leaf::Leaf;

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
            max_growth: 1.3,
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

/// A queue entry: the cost bits (non-negative floats order like their bits), the leaf and
/// its best partner.
type Entry = Reverse<(u32, u32, u32)>;

struct Simplifier {
    leaves: Vec<Leaf>,
    children: Vec<[u32; 2]>,
    alive: Vec<bool>,
    alive_count: usize,
    grid: Grid,
    built_with: usize,
    heap: BinaryHeap<Entry>,
    weights: Weights,
    max_distance: f32,
    min_cos: f32,
    max_growth: f32,
    min_density: f32,
    max_overhang: f32,
    axis: Axis,
    inv_crown: f32,
}

impl Simplifier {
    fn new(leaves: &[Leaf], selection: &Selection) -> Simplifier {
        let axis = selection.axis.unwrap_or_else(|| {
            let (lo, hi) = leaves.iter().fold(
                (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
                |(lo, hi), l| (lo.min(l.center), hi.max(l.center)),
            );
            let mid = (lo + hi) * 0.5;
            Axis {
                origin: Vec3::new(mid.x, lo.y, mid.z),
                direction: Vec3::Y,
            }
        });
        let crown = leaves
            .iter()
            .map(|l| axis.distance(l.center))
            .fold(0.0f32, f32::max);
        let mut s = Simplifier {
            leaves: leaves.to_vec(),
            children: Vec::with_capacity(leaves.len()),
            alive: vec![true; leaves.len()],
            alive_count: leaves.len(),
            grid: Grid::new(1.0),
            built_with: 0,
            heap: BinaryHeap::with_capacity(leaves.len() * 2),
            weights: selection.weights,
            max_distance: selection.bounds.max_distance.max(0.0),
            max_growth: selection.bounds.max_growth,
            min_density: selection.bounds.min_density,
            max_overhang: selection.bounds.max_overhang,
            min_cos: selection
                .bounds
                .max_angle
                .clamp(0.0, 90.0)
                .to_radians()
                .cos()
                - 1e-6,
            axis,
            inv_crown: if crown > 0.0 { 1.0 / crown } else { 0.0 },
        };
        s.rebuild_grid();
        s
    }

    fn run(&mut self) {
        for i in 0..self.leaves.len() as u32 {
            self.push_best(i);
        }
        while let Some(Reverse((_, a, b))) = self.heap.pop() {
            if !self.alive[a as usize] {
                continue;
            }
            if !self.alive[b as usize] {
                self.push_best(a);
                continue;
            }
            let leaf = Leaf::collapse(&self.leaves[a as usize], &self.leaves[b as usize]);
            let label = self.leaves.len() as u32;
            for old in [a, b] {
                self.alive[old as usize] = false;
                self.grid.remove(old, self.leaves[old as usize].center);
            }
            // The thesis' figure 2.3 keeps the lower label on the left.
            self.children.push([a.min(b), a.max(b)]);
            self.leaves.push(leaf);
            self.alive.push(true);
            self.alive_count -= 1;
            if self.alive_count * 2 <= self.built_with {
                self.rebuild_grid();
            } else {
                self.grid.insert(label, &leaf);
            }
            self.push_best(label);
        }
    }

    /// A grid whose cells hold a few living leaves each, twice as wide as the distance
    /// bound between leaves of the mean size, so that the eight cells nearest a leaf reach
    /// its allowed partners of similar size.
    fn rebuild_grid(&mut self) {
        let living: Vec<u32> = (0..self.leaves.len() as u32)
            .filter(|&i| self.alive[i as usize])
            .collect();
        let mean_radius = living
            .iter()
            .map(|&i| f64::from(self.leaves[i as usize].radius()))
            .sum::<f64>()
            / living.len().max(1) as f64;
        let reach = (self.max_distance as f64 * 4.0 * mean_radius) as f32;
        let cell = if reach > 0.0 && reach.is_finite() {
            reach
        } else {
            1.0
        };
        let mut grid = Grid::new(cell);
        for &i in &living {
            grid.insert(i, &self.leaves[i as usize]);
        }
        self.grid = grid;
        self.built_with = living.len();
    }

    fn push_best(&mut self, a: u32) {
        if let Some((cost, b)) = self.best(a) {
            self.heap.push(Reverse((cost.to_bits(), a, b)));
        }
    }

    /// The allowed partner of `a` with the least cost among the living leaves in the 8
    /// cells nearest it (ties: the lower label).
    fn best(&self, a: u32) -> Option<(f32, u32)> {
        let la = &self.leaves[a as usize];
        let me = Slot {
            center: la.center,
            radius: la.radius(),
            normal: la.normal,
            area: la.area(),
            count: la.count,
            label: a,
        };
        let mut candidates: Vec<(f32, u32)> = Vec::new();
        for cell in self.grid.around(la.center) {
            for slot in cell {
                // The distance bound first: it needs no square root.
                let reach = self.max_distance * (me.radius + slot.radius);
                if slot.label == a || me.center.distance_squared(slot.center) > reach * reach {
                    continue;
                }
                if let Some(cost) = self.cost(&me, slot) {
                    candidates.push((cost, slot.label));
                }
            }
        }
        // The area bounds need the new leaf: check the cheapest candidates first (usually
        // the first passes, so no sort).
        while !candidates.is_empty() {
            let (k, &(cost, b)) = candidates
                .iter()
                .enumerate()
                .min_by(|x, y| x.1.0.total_cmp(&y.1.0).then(x.1.1.cmp(&y.1.1)))?;
            let lb = &self.leaves[b as usize];
            let new = Leaf::collapse(la, lb);
            let area = new.area();
            let slack = (new.hi - new.lo) * self.max_overhang;
            let (lo, hi) = (new.lo - slack, new.hi + slack);
            let inside = new
                .corners()
                .iter()
                .all(|c| c.cmpge(lo).all() && c.cmple(hi).all());
            if area <= self.max_growth * (la.area() + lb.area())
                && new.leaf_area >= self.min_density * area
                && inside
            {
                return Some((cost, b));
            }
            candidates.swap_remove(k);
        }
        None
    }

    /// The weighted distance of seed 003 §2.4.1 between two leaves within the distance
    /// bound, or `None` when the angle bound forbids the pair.
    fn cost(&self, a: &Slot, b: &Slot) -> Option<f32> {
        let cos = a.normal.dot(b.normal).abs();
        if cos < self.min_cos {
            return None;
        }
        let d = a.center.distance(b.center) / (a.radius + b.radius);
        let w = &self.weights;
        let (na, nb) = (a.count as f32, b.count as f32);
        let (aa, ab) = (a.area, b.area);
        let mid = (a.center + b.center) * 0.5;
        let cost = w.distance * d
            + w.coplanarity * (1.0 - cos.min(1.0))
            + w.count * (na - nb).abs() / (na + nb)
            + w.area * (aa - ab).abs() / (aa + ab)
            + w.interiority * self.axis.distance(mid) * self.inv_crown;
        (cost.is_finite() && cost >= 0.0).then_some(cost)
    }
}

/// A grid cell's copy of what the first test of a candidate needs, so the scan reads
/// contiguous memory.
#[derive(Clone, Copy)]
struct Slot {
    center: Vec3,
    radius: f32,
    normal: Vec3,
    area: f32,
    count: u32,
    label: u32,
}

/// A uniform grid of living leaves by cell.
struct Grid {
    inv_cell: f32,
    cells: HashMap<[i32; 3], Vec<Slot>, BuildHasherDefault<CellHasher>>,
}

impl Grid {
    fn new(cell: f32) -> Grid {
        Grid {
            inv_cell: 1.0 / cell,
            cells: HashMap::default(),
        }
    }

    fn key(&self, p: Vec3) -> [i32; 3] {
        let k = (p * self.inv_cell).floor();
        [k.x as i32, k.y as i32, k.z as i32]
    }

    fn insert(&mut self, label: u32, leaf: &Leaf) {
        let key = self.key(leaf.center);
        self.cells.entry(key).or_default().push(Slot {
            center: leaf.center,
            radius: leaf.radius(),
            normal: leaf.normal,
            area: leaf.area(),
            count: leaf.count,
            label,
        });
    }

    fn remove(&mut self, label: u32, p: Vec3) {
        let key = self.key(p);
        if let Some(cell) = self.cells.get_mut(&key)
            && let Some(i) = cell.iter().position(|s| s.label == label)
        {
            cell.swap_remove(i);
        }
    }

    /// The eight cells nearest `p` (its own and the neighbours on the sides it is nearer
    /// to) that hold leaves: with cells twice the search radius, they hold every leaf
    /// within that radius.
    fn around(&self, p: Vec3) -> impl Iterator<Item = &Vec<Slot>> {
        let q = p * self.inv_cell;
        let k = q.floor();
        let step = |f: f32| if f < 0.5 { -1 } else { 1 };
        let base = [k.x as i32, k.y as i32, k.z as i32];
        let off = [step(q.x - k.x), step(q.y - k.y), step(q.z - k.z)];
        (0..8).filter_map(move |n| {
            let key = [
                base[0].saturating_add(if n & 1 == 0 { 0 } else { off[0] }),
                base[1].saturating_add(if n & 2 == 0 { 0 } else { off[1] }),
                base[2].saturating_add(if n & 4 == 0 { 0 } else { off[2] }),
            ];
            self.cells.get(&key)
        })
    }
}

/// A multiply-rotate hasher for grid keys (std's SipHash is needlessly slow here).
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        // The splitmix64 finaliser, so that every bit of the key reaches the low bits.
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }

    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(23) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
                    Vec3::new(t.sin() * 3.0, (i % 17) as f32 * 0.3, t.cos() * 3.0),
                    Vec3::new(t.cos(), 0.3, t.sin()).normalize(),
                )
            })
            .collect();
        let a = simplify(&leaves, &Selection::default());
        let b = simplify(&leaves, &Selection::default());
        assert_eq!(a, b);
        assert!(a.children.len() > 100, "{}", a.children.len());
    }
}
