//! The nutrient-transport model of seed 001 (Nicholas McDonald, 2020), in plain Rust.
//!
//! A tree is a binary tree of branches, each a (tapered) cylinder with a length, a
//! cross-section area and a direction. One feeding pours `feed` into the root:
//! - a leaf branch grows in length by `cbrt(feed)`, spends `cbrt(feed) * area` on it, puts
//!   the rest into its area (`area += rest / length`) and splits when
//!   `length > splitsize * exp(-splitdecay * depth)`;
//! - an inner branch keeps `pass = (A.area + B.area) / (A.area + B.area + area)` of the feed
//!   for its girth (`area += pass * feed / length`; this feedback keeps the parent's area near
//!   the sum of its children's), and passes the rest to child A by `ratio` and to B by
//!   `1 - ratio`, unless it is below 1e-5 (it is then dropped).
//!
//! A split makes two children whose directions mix the parent's direction with the normal
//! `N` of the plane through the parent direction and the direction `D` to the highest local
//! leaf density: `A = normalize(mix(flip * spread * N, dir, ratio))`, `B =
//! normalize(mix(-flip * spread * N, dir, 1 - ratio))`, with a random `flip` of +-1. `D` is
//! found by climbing `localdepth + 1` ancestors (never past the trunk) and taking the
//! ratio-weighted leaf average of the ancestor's subtree relative to the splitting branch,
//! mixed with a random vector by `directedness`; the trunk (depth 0) takes the random
//! vector alone.
//!
//! # Cost
//! The seed computes each leaf average by a recursion over the ancestor's whole subtree,
//! which is quadratic in the tree size (an ancestor near the trunk owns most of the tree).
//! The average is linear in its subtree, `L(b) = length * dir + ratio * L(A) + (1 - ratio) *
//! L(B)`, so one backward pass over the branches (children are stored after their parents)
//! gives every `L` at once. A feeding records the leaves that must split and splits them
//! after the feeding, in the order the seed meets them, all from that one pass: a feeding
//! costs O(branches it reaches) plus O(branches) when something splits. A split's new
//! children have no length yet, so an earlier split of the same feeding never changes the
//! averages a later one reads; the only difference from the seed's in-place splitting is
//! that a split sees the lengths of the whole feeding rather than of the part of the tree
//! fed before it.
//!
//! # Accounting
//! Every unit of feed ends up somewhere: a leaf's volume `area * length` grows by exactly
//! the feed it receives, an inner branch's by the part it keeps, and a remainder below
//! 1e-5 is dropped. So after each feeding, `fed = growth in volume + dropped`
//! ([`Feeding`] reports both).

use glam::DVec3;
use pge_engine::OptionError;
use pge_engine::math;
use rand_mt::Mt;

/// "No branch".
pub const NONE: u32 = u32::MAX;

/// A feed below this is not passed on (the seed's guard against over-branching).
pub const MIN_FEED: f64 = 1e-5;

/// The area of a new branch (the seed's `area = 0.1`).
pub const INITIAL_AREA: f64 = 0.1;

/// The parameters of the transport model, with the seed's defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TransportParams {
    /// Share of the passed feed that goes to child A (the rest goes to B); in (0, 1).
    /// 0.5 splits evenly; far from 0.5 one child dominates (an evergreen's leader).
    pub ratio: f64,
    /// Weight of the perpendicular direction against the parent's at a split (>= 0).
    pub spread: f64,
    /// Length at which a depth-0 branch splits (> 0).
    pub splitsize: f64,
    /// The split length shrinks by `exp(-splitdecay * depth)` (>= 0).
    pub splitdecay: f64,
    /// How much a new branch turns away from the local leaf density rather than at random,
    /// in [0, 1].
    pub directedness: f64,
    /// How many ancestors the leaf-density query climbs beyond the first.
    pub localdepth: u32,
    /// The nutrient poured into the root at each feeding (> 0).
    pub feed: f64,
}

impl Default for TransportParams {
    /// The seed's values: ratio 0.6, spread 0.45, splitsize 2.5, splitdecay 0.01,
    /// directedness 0.5, localdepth 2, feed 1.
    fn default() -> Self {
        TransportParams {
            ratio: 0.6,
            spread: 0.45,
            splitsize: 2.5,
            splitdecay: 0.01,
            directedness: 0.5,
            localdepth: 2,
            feed: 1.0,
        }
    }
}

impl TransportParams {
    /// Checks every range; the error names the option and the range it needs.
    pub fn validate(&self) -> Result<(), OptionError> {
        let check = |option: &'static str, expected: &'static str, v: f64, ok: bool| {
            if !v.is_finite() {
                Err(OptionError::out_of_range(option, "a finite number", v))
            } else if ok {
                Ok(())
            } else {
                Err(OptionError::out_of_range(option, expected, v))
            }
        };
        let r = self.ratio;
        check(
            "ratio",
            "a number between 0 and 1 (exclusive)",
            r,
            r > 0.0 && r < 1.0,
        )?;
        check("spread", "a number >= 0", self.spread, self.spread >= 0.0)?;
        check(
            "splitsize",
            "a number > 0",
            self.splitsize,
            self.splitsize > 0.0,
        )?;
        check(
            "splitdecay",
            "a number >= 0",
            self.splitdecay,
            self.splitdecay >= 0.0,
        )?;
        let d = self.directedness;
        check(
            "directedness",
            "a number between 0 and 1",
            d,
            (0.0..=1.0).contains(&d),
        )?;
        check("feed", "a number > 0", self.feed, self.feed > 0.0)
    }
}

/// What one feeding did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Feeding {
    /// Nutrient poured in (the feed, over every root).
    pub fed: f64,
    /// Nutrient turned into volume (`area * length` summed over the branches).
    pub grown: f64,
    /// Nutrient not passed on because it fell below [`MIN_FEED`].
    pub dropped: f64,
    /// Branches that split.
    pub splits: u32,
}

/// The feeding would take the tree past its branch cap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CapExceeded {
    /// The cap.
    pub cap: usize,
    /// Branches the tree would have had.
    pub would_have: usize,
}

/// A growing tree (or several, one per root).
///
/// Branches live in flat arrays indexed by branch number; a branch's children always come
/// after it, so a backward pass visits children before parents.
#[derive(Clone, Debug)]
pub struct TransportTree {
    params: TransportParams,
    /// Parent branch, [`NONE`] for a root.
    pub parent: Vec<u32>,
    /// Children A and B, [`NONE`] for a leaf.
    pub children: Vec<[u32; 2]>,
    /// Depth: 0 for a root, parent + 1 otherwise.
    pub depth: Vec<u32>,
    /// Unit growth direction.
    pub dir: Vec<DVec3>,
    /// Length.
    pub length: Vec<f64>,
    /// Cross-section area.
    pub area: Vec<f64>,
    /// The root branches, each with where it starts and its share of the feed.
    pub roots: Vec<(u32, DVec3, f64)>,
    rng: Mt,
    /// The split length of each depth, `splitsize * exp(-splitdecay * depth)`, for every
    /// depth a branch has.
    split_length: Vec<f64>,
    /// Per-branch ratio-weighted leaf average (scratch of the density query).
    average: Vec<DVec3>,
    stack: Vec<(u32, f64)>,
    splits: Vec<u32>,
    steps: u32,
}

impl TransportTree {
    /// A tree with one root branch per `(origin, direction, share)`; each feeding pours
    /// `share * feed` into that root. Directions are normalised (a zero one becomes +Y).
    /// `seed` seeds the MT19937 that draws the noise and flips.
    ///
    /// # Panics
    /// If `params` fail [`TransportParams::validate`] (check them first).
    #[must_use]
    pub fn new(params: TransportParams, roots: &[(DVec3, DVec3, f64)], seed: u32) -> TransportTree {
        assert!(params.validate().is_ok(), "checked transport parameters");
        let mut t = TransportTree {
            params,
            parent: Vec::new(),
            children: Vec::new(),
            depth: Vec::new(),
            dir: Vec::new(),
            length: Vec::new(),
            area: Vec::new(),
            roots: Vec::new(),
            rng: Mt::new(seed),
            split_length: Vec::new(),
            average: Vec::new(),
            stack: Vec::new(),
            splits: Vec::new(),
            steps: 0,
        };
        for &(origin, direction, share) in roots {
            let b = t.push(NONE, 0, direction.try_normalize().unwrap_or(DVec3::Y));
            t.roots.push((b, origin, share));
        }
        t
    }

    fn push(&mut self, parent: u32, depth: u32, dir: DVec3) -> u32 {
        let b = self.parent.len() as u32;
        self.parent.push(parent);
        self.children.push([NONE, NONE]);
        self.depth.push(depth);
        self.dir.push(dir);
        self.length.push(0.0);
        self.area.push(INITIAL_AREA);
        while self.split_length.len() <= depth as usize {
            let d = self.split_length.len() as f64;
            let p = &self.params;
            self.split_length
                .push(p.splitsize * math::exp(-p.splitdecay * d));
        }
        b
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &TransportParams {
        &self.params
    }

    /// Number of branches.
    #[must_use]
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// Whether there is no branch (no root was given).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    /// Feedings so far.
    #[must_use]
    pub fn steps(&self) -> u32 {
        self.steps
    }

    /// Whether branch `b` is a leaf (has no children).
    #[must_use]
    pub fn is_leaf(&self, b: u32) -> bool {
        self.children[b as usize][0] == NONE
    }

    /// Radius of branch `b`: `sqrt(area / pi)`.
    #[must_use]
    pub fn radius(&self, b: u32) -> f64 {
        (self.area[b as usize] / std::f64::consts::PI).sqrt()
    }

    /// The total volume `sum(area * length)`, which grows by exactly what each feeding
    /// does not drop.
    #[must_use]
    pub fn volume(&self) -> f64 {
        self.area.iter().zip(&self.length).map(|(a, l)| a * l).sum()
    }

    /// Where each branch ends (its start is its parent's end, or its root's origin).
    #[must_use]
    pub fn ends(&self) -> Vec<DVec3> {
        let mut start = vec![DVec3::ZERO; self.len()];
        for &(b, origin, _) in &self.roots {
            start[b as usize] = origin;
        }
        let mut end = vec![DVec3::ZERO; self.len()];
        for b in 0..self.len() {
            if self.parent[b] != NONE {
                start[b] = end[self.parent[b] as usize];
            }
            end[b] = start[b] + self.length[b] * self.dir[b];
        }
        end
    }

    /// One feeding: `feed` poured into the roots (each its share), grown and split as the
    /// seed does. Refuses, before allocating, a feeding whose splits would take the tree
    /// past `cap` branches (the state is then that of the feeding without its splits; the
    /// caller stops).
    pub fn feed(&mut self, cap: usize) -> Result<Feeding, CapExceeded> {
        let p = self.params;
        let mut report = Feeding::default();
        // Scratch and arrays as locals, so the loop keeps them in registers.
        let mut stack = std::mem::take(&mut self.stack);
        let mut splits = std::mem::take(&mut self.splits);
        stack.clear();
        splits.clear();
        for &(b, _, share) in self.roots.iter().rev() {
            stack.push((b, p.feed * share));
            report.fed += p.feed * share;
        }
        let children = &self.children[..];
        let depth = &self.depth[..];
        let split_length = &self.split_length[..];
        let area = &mut self.area[..];
        let length = &mut self.length[..];
        while let Some((b, feed)) = stack.pop() {
            let i = b as usize;
            let [a, c] = children[i];
            let (old_area, old_length) = (area[i], length[i]);
            let before = old_area * old_length;
            if a == NONE {
                let grow = cbrt(feed);
                let l = old_length + grow;
                let rest = feed - grow * old_area;
                let r = old_area + rest / l;
                length[i] = l;
                area[i] = r;
                report.grown += r * l - before;
                if l > split_length[depth[i] as usize] {
                    splits.push(b);
                }
                continue;
            }
            let sum = area[a as usize] + area[c as usize];
            let pass = sum / (sum + old_area);
            let r = old_area + pass * feed / old_length;
            area[i] = r;
            report.grown += r * old_length - before;
            let feed = feed * (1.0 - pass);
            if feed < MIN_FEED {
                report.dropped += feed;
                continue;
            }
            // B below A on the stack: A's whole subtree is fed first, as the recursion does.
            stack.push((c, feed * (1.0 - p.ratio)));
            stack.push((a, feed * p.ratio));
        }
        self.stack = stack;
        let would_have = self.len() + 2 * splits.len();
        if would_have > cap {
            self.splits = splits;
            return Err(CapExceeded { cap, would_have });
        }
        if !splits.is_empty() {
            self.leaf_averages();
            for &b in &splits {
                self.split(b);
            }
            report.splits = splits.len() as u32;
        }
        self.splits = splits;
        self.steps += 1;
        Ok(report)
    }

    /// Every branch's ratio-weighted leaf average `L(b) = length * dir + ratio * L(A) +
    /// (1 - ratio) * L(B)`, in one backward pass.
    fn leaf_averages(&mut self) {
        let ratio = self.params.ratio;
        let n = self.len();
        // Every entry is written below, children (after their parents) first.
        self.average.resize(n, DVec3::ZERO);
        let average = &mut self.average[..n];
        let own = self.length.iter().zip(&self.dir).zip(&self.children);
        for (i, ((&length, &dir), &[a, b])) in own.enumerate().rev() {
            let own = length * dir;
            average[i] = if a == NONE {
                own
            } else {
                own + ratio * average[a as usize] + (1.0 - ratio) * average[b as usize]
            };
        }
    }

    /// A random vector with components in [-0.5, 0.49] by hundredths (the seed's
    /// `rand() % 100 / 100 - 0.5`).
    fn noise(&mut self) -> DVec3 {
        let mut c = || f64::from(self.rng.next_u32() % 100) / 100.0 - 0.5;
        let x = c();
        let y = c();
        let z = c();
        DVec3::new(x, y, z)
    }

    /// The direction toward the highest local leaf density as seen from branch `b`, mixed
    /// with noise (needs [`Self::leaf_averages`] to be current).
    fn leaf_density(&mut self, b: u32) -> DVec3 {
        let r = self.noise();
        if self.depth[b as usize] == 0 {
            return r;
        }
        let mut c = b as usize;
        let mut rel = DVec3::ZERO;
        let mut search = i64::from(self.params.localdepth);
        while self.depth[c] > 0 && {
            let go = search >= 0;
            search -= 1;
            go
        } {
            rel += self.length[c] * self.dir[c];
            c = self.parent[c] as usize;
        }
        let d = self.params.directedness;
        d * (self.average[c] - rel).normalize_or_zero() + (1.0 - d) * r
    }

    fn split(&mut self, b: u32) {
        let i = b as usize;
        let depth = self.depth[i] + 1;
        let dir = self.dir[i];
        let a = self.push(b, depth, dir);
        let c = self.push(b, depth, dir);
        self.children[i] = [a, c];
        // The new children add nothing to any leaf average (no length yet).
        self.average.push(DVec3::ZERO);
        self.average.push(DVec3::ZERO);
        let density = self.leaf_density(b);
        let n = dir
            .cross(density)
            .try_normalize()
            .unwrap_or_else(|| dir.any_orthonormal_vector());
        let flip = if self.rng.next_u32() % 2 == 1 {
            1.0
        } else {
            -1.0
        };
        let (ratio, spread) = (self.params.ratio, self.params.spread);
        // glm::mix(x, y, t) = x * (1 - t) + y * t.
        let mix = |x: DVec3, y: DVec3, t: f64| x * (1.0 - t) + y * t;
        self.dir[a as usize] = mix(flip * spread * n, dir, ratio)
            .try_normalize()
            .unwrap_or(dir);
        self.dir[c as usize] = mix(-flip * spread * n, dir, 1.0 - ratio)
            .try_normalize()
            .unwrap_or(dir);
    }
}

/// `x.cbrt()`, bit for bit, in about 60% of its instructions: the standard library's cube
/// root (CORE-MATH's) is correctly rounded, and took a third of a feeding. This one
/// takes two Halley iterations from a bit-level guess (a few ulps off), then one Newton
/// correction computed in double-double (error below 2^-45 ulp), and rounds it; when that
/// correction lies closer than 2^-30 ulp to a rounding boundary (about one call in 2^29)
/// or `x` is out of the range this is exact for, it asks the standard library. So every
/// result is the correctly rounded cube root, as the standard library's.
fn cbrt(x: f64) -> f64 {
    if !(1e-200..=1e200).contains(&x) {
        return math::cbrt(x);
    }
    // Bits of x / 3 plus a third of the exponent bias: within 6%.
    let mut y = f64::from_bits(x.to_bits() / 3 + 0x2A9F_7893_782D_A1CE);
    for _ in 0..2 {
        let y3 = y * y * y;
        y *= (y3 + 2.0 * x) / (2.0 * y3 + x);
    }
    // y^3 = y3 + e3 + e2 * y exactly (but for the last product's rounding).
    let (y2, e2) = two_product(y, y);
    let (y3, e3) = two_product(y2, y);
    let r = ((x - y3) - e3) - e2 * y;
    let delta = r / (3.0 * y2);
    let s = y + delta;
    // The part of y + delta that s lost, exactly (|delta| is a few ulps of y).
    let lost = delta - (s - y);
    let neighbour = if lost > 0.0 {
        f64::from_bits(s.to_bits() + 1)
    } else {
        f64::from_bits(s.to_bits() - 1)
    };
    let half = 0.5 * (neighbour - s).abs();
    if lost.abs() + half * 2f64.powi(-30) < half {
        s
    } else {
        math::cbrt(x)
    }
}

/// `a * b` as its rounded value and the exact rest (Dekker's product; no overflow for the
/// magnitudes [`cbrt`] passes).
fn two_product(a: f64, b: f64) -> (f64, f64) {
    const SPLIT: f64 = 134_217_729.0; // 2^27 + 1
    let split = |v: f64| {
        let c = SPLIT * v;
        let hi = c - (c - v);
        (hi, v - hi)
    };
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    (p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)
}

#[cfg(test)]
mod tests;
