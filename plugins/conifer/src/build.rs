//! The skeleton of a conifer at an age: the leader and its whorls as laid down year by year
//! ([`Whorl`]), the branches' geometry from the crown shape at that age, the flat sprays of
//! second and third order, and the radii (pipe model, clamped where a branch joins the
//! trunk).
//!
//! Nodes are written trunk first (root to apex), then each branch in turn: its axis, then
//! each of its shoots (the shoot's axis, then its own shoots). So a node's first child
//! continues its branch, and every first-order branch's subtree is one run of indices.

use glam::{Vec2, Vec3};
use pge_engine::geometry::Skeleton;
use pge_engine::math;

use crate::params::{ConiferParams, MAX_SEGMENTS, SprayPattern};

/// A stateless source of uniform numbers: the `n`-th draw of a key under a seed, the same
/// whatever else was drawn before (a whorl's branches keep their draws at every age).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Draws {
    key: u64,
    n: u64,
}

/// splitmix64's finaliser: a bijective mix of 64 bits.
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Draws {
    /// The draws of `key` under `seed`.
    pub(crate) fn new(seed: u64, key: u64) -> Draws {
        Draws {
            key: mix64(seed ^ mix64(key)),
            n: 0,
        }
    }

    /// A uniform number in `[0, 1)` (24 bits).
    pub(crate) fn unit(&mut self) -> f32 {
        self.n += 1;
        (mix64(self.key ^ self.n.wrapping_mul(0xd6e8_feb8_6659_fd93)) >> 40) as f32
            / (1u32 << 24) as f32
    }

    /// A uniform number in `[-1, 1)`.
    pub(crate) fn signed(&mut self) -> f32 {
        2.0 * self.unit() - 1.0
    }

    /// A uniform integer in `lo..=hi` (`lo` when `hi <= lo`).
    pub(crate) fn int(&mut self, lo: u32, hi: u32) -> u32 {
        let u = self.unit();
        if hi <= lo {
            return lo;
        }
        (lo + (u * (hi - lo + 1) as f32) as u32).min(hi)
    }

    /// A key for a thing of this draw source (a branch, a shoot), from a fresh draw.
    pub(crate) fn child_key(&mut self) -> u64 {
        self.n += 1;
        mix64(self.key ^ self.n.wrapping_mul(0x9e37_79b9_7f4a_7c15))
    }
}

/// A bud of a first-order branch as drawn when its whorl was laid down.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bud {
    /// Direction around the trunk, degrees.
    pub azimuth: f32,
    /// Added to the branch's angle from the trunk, degrees.
    pub angle: f32,
    /// Its length is the crown's length at its height times this.
    pub length: f32,
    /// Where along the internode below the whorl it sits (1: at the whorl).
    pub along: f32,
    /// The key of its shoots' draws.
    pub key: u64,
}

/// What one year laid down: the internode below the whorl, the whorl's node (its sideways
/// wander) and its buds, and the buds between the whorl below and this one.
#[derive(Clone, Debug, PartialEq)]
pub struct Whorl {
    /// Sideways offset of the whorl's node, as a fraction of the internode.
    pub wave: Vec2,
    /// The whorl's buds (`along == 1`), then the buds between whorls (`along < 1`, in
    /// increasing order).
    pub buds: Vec<Bud>,
}

impl Whorl {
    /// The whorl of `year` (1 for the first), drawn from `seed`.
    #[must_use]
    pub fn draw(params: &ConiferParams, seed: u64, year: u32) -> Whorl {
        let mut d = Draws::new(seed, u64::from(year));
        let wave = Vec2::new(d.signed(), d.signed()) * params.waviness;
        let count = d.int(params.per_whorl.0, params.per_whorl.1);
        let spacing = 360.0 / count as f32;
        let phase = params.twist * year as f32 + 0.5 * params.jitter * spacing * d.signed();
        let j = params.jitter;
        let mut buds = Vec::with_capacity(count as usize);
        for b in 0..count {
            buds.push(Bud {
                azimuth: phase + spacing * b as f32 + 0.35 * j * spacing * d.signed(),
                angle: 10.0 * j * d.signed(),
                length: 1.0 + j * d.signed(),
                along: 1.0,
                key: d.child_key(),
            });
        }
        let between = d.int(params.interwhorl.0, params.interwhorl.1);
        let mut small: Vec<Bud> = (0..between)
            .map(|_| Bud {
                azimuth: 360.0 * d.unit(),
                angle: 10.0 * j * d.signed(),
                // Small: a third of a whorl branch's length at most.
                length: 0.15 + 0.2 * d.unit(),
                along: 0.2 + 0.6 * d.unit(),
                key: d.child_key(),
            })
            .collect();
        small.sort_by(|a, b| a.along.total_cmp(&b.along));
        buds.extend(small);
        Whorl { wave, buds }
    }
}

/// A skeleton that would pass the node cap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooManyNodes {
    /// The cap.
    pub cap: usize,
}

/// The built skeleton and where its first-order branches are.
#[derive(Clone, Debug, Default)]
pub struct Built {
    /// The skeleton, with radii.
    pub skeleton: Skeleton,
    /// The trunk's nodes from the root to the apex.
    pub trunk: Vec<u32>,
    /// Each first-order branch: the range of its subtree's nodes and the trunk node it
    /// hangs on.
    pub branches: Vec<(std::ops::Range<u32>, u32)>,
}

struct Builder<'a> {
    p: &'a ConiferParams,
    seed: u64,
    s: Skeleton,
}

/// A unit direction of azimuth `h` (horizontal unit vector) raised `elevation` degrees.
fn raised(h: Vec3, elevation: f32) -> Vec3 {
    let e = elevation.to_radians();
    h * math::cos(e) + Vec3::Y * math::sin(e)
}

/// The horizontal unit vector and the elevation (degrees) of a direction.
fn split(v: Vec3, fallback: Vec3) -> (Vec3, f32) {
    let h = Vec3::new(v.x, 0.0, v.z).try_normalize().unwrap_or(fallback);
    (h, math::asin(v.y.clamp(-1.0, 1.0)).to_degrees())
}

/// The lowest elevation a bending branch reaches, degrees.
const LOWEST: f32 = -85.0;

impl Builder<'_> {
    fn push(&mut self, at: Vec3, parent: Option<u32>, order: u32) -> Result<u32, TooManyNodes> {
        if self.s.len() >= self.p.max_nodes {
            return Err(TooManyNodes {
                cap: self.p.max_nodes,
            });
        }
        Ok(self.s.push(at, parent, 0.0, order))
    }

    /// An axis of `length` from node `from`, heading along `h` raised `elevation` degrees
    /// and bending down by `droop * (s / length)^2` degrees at arc length `s`. Returns its
    /// nodes with their arc length and direction.
    fn axis(
        &mut self,
        from: u32,
        h: Vec3,
        elevation: f32,
        droop: f32,
        length: f32,
        order: u32,
    ) -> Result<Vec<(u32, f32, Vec3)>, TooManyNodes> {
        let segments = ((length / self.p.segment).ceil() as u32).clamp(1, MAX_SEGMENTS);
        let ds = length / segments as f32;
        let mut at = self.s.positions[from as usize];
        let mut parent = from;
        let mut nodes = Vec::with_capacity(segments as usize);
        for i in 1..=segments {
            let bend = |s: f32| (elevation - droop * (s / length).powi(2)).max(LOWEST);
            at += raised(h, bend((i as f32 - 0.5) * ds)) * ds;
            parent = self.push(at, Some(parent), order)?;
            nodes.push((parent, i as f32 * ds, raised(h, bend(i as f32 * ds))));
        }
        Ok(nodes)
    }

    /// The shoots along an axis of `length` (its nodes from [`Builder::axis`]) from arc
    /// length `bare` on: one or two per node but the first and the tip, in the plane of the axis and the
    /// horizontal, of order `order`; each carries shoots of its own while `order` is below
    /// the tree's `orders`.
    fn shoots(
        &mut self,
        nodes: &[(u32, f32, Vec3)],
        length: f32,
        bare: f32,
        order: u32,
        key: u64,
    ) -> Result<(), TooManyNodes> {
        if order > self.p.orders || nodes.len() < 2 {
            return Ok(());
        }
        let p = self.p;
        let mut d = Draws::new(self.seed, key);
        let first_side = if d.unit() < 0.5 { 1.0 } else { -1.0 };
        let ds = nodes[0].1;
        for (i, &(node, s, tangent)) in nodes[..nodes.len() - 1].iter().enumerate() {
            // Not on an axis's first node either: a tip's leaves, hung on its last few
            // segments, then stay off the axis's parent (the trunk, for a branch).
            if s < bare || i == 0 {
                continue;
            }
            let sides: &[f32] = match p.spray_pattern {
                SprayPattern::Paired => &[1.0, -1.0],
                SprayPattern::Alternate if i % 2 == 0 => &[1.0],
                SprayPattern::Alternate => &[-1.0],
            };
            for &side in sides {
                let side = side * first_side;
                let l = p.spray_length * (length - s + ds) * (1.0 + p.jitter * d.signed());
                let a = (p.spray_angle + 15.0 * p.jitter * d.signed()).to_radians();
                let shoot_key = d.child_key();
                if l <= 1e-3 {
                    continue;
                }
                let (h, _) = split(tangent, Vec3::X);
                let across = Vec3::new(h.z, 0.0, -h.x) * side;
                let start = tangent * math::cos(a) + across * math::sin(a);
                let (sh, elevation) = split(start, h);
                let droop = p.spray_droop;
                let axis = self.axis(node, sh, elevation, droop, l, order)?;
                self.shoots(&axis, l, 0.0, order + 1, shoot_key)?;
            }
        }
        Ok(())
    }
}

/// The skeleton after the years in `whorls` (`whorls[k]` laid down in year `k + 1`), with
/// the run's `seed` (the one the whorls were drawn with). Radii: the pipe model from the
/// mesh options' tip radius and exponent, each first-order branch's subtree then thinned so
/// that the branch is at most `joint_ratio` of the trunk above its joint.
pub fn build(params: &ConiferParams, whorls: &[Whorl], seed: u64) -> Result<Built, TooManyNodes> {
    let mut b = Builder {
        p: params,
        seed,
        s: Skeleton::new(),
    };
    let p = params;
    let age = whorls.len() as u32;
    let internode = p.height / p.years as f32;
    let height = internode * age as f32;
    let shed = p.crown_base * height;
    let depth = (height - shed).max(f32::MIN_POSITIVE);
    let reach = p.crown_radius * age as f32 / p.years as f32;

    // The trunk: the root, then for each year the buds between whorls and the whorl.
    let root = b.push(p.root, None, 0)?;
    let mut trunk = vec![root];
    // (trunk node, bud, height above the root) of every bud.
    let mut buds = Vec::new();
    let mut below = p.root;
    for (k, whorl) in whorls.iter().enumerate() {
        let w = whorl.wave * internode;
        let top = p.root + Vec3::new(w.x, internode * (k + 1) as f32, w.y);
        let h0 = internode * k as f32;
        for bud in whorl.buds.iter().filter(|bud| bud.along < 1.0) {
            let node = b.push(below.lerp(top, bud.along), trunk.last().copied(), 0)?;
            trunk.push(node);
            buds.push((node, *bud, h0 + internode * bud.along));
        }
        let node = b.push(top, trunk.last().copied(), 0)?;
        trunk.push(node);
        for bud in whorl.buds.iter().filter(|bud| bud.along >= 1.0) {
            buds.push((node, *bud, h0 + internode));
        }
        below = top;
    }
    // Lowest first, as the trunk's nodes.
    buds.sort_by_key(|(node, _, _)| *node);

    let mut branches = Vec::new();
    for (node, bud, h) in buds {
        if h < shed {
            continue;
        }
        let t = (height - h) / depth;
        let length = reach * p.crown.length_at(t) * bud.length;
        if length <= 1e-3 {
            continue;
        }
        let angle = (p.angle.0 + (p.angle.1 - p.angle.0) * t + bud.angle).clamp(0.0, 180.0);
        let az = bud.azimuth.to_radians();
        let heading = Vec3::new(math::cos(az), 0.0, math::sin(az));
        let droop = p.droop * (length / p.crown_radius.max(f32::MIN_POSITIVE)).min(1.5);
        let start = b.s.len() as u32;
        let axis = b.axis(node, heading, 90.0 - angle, droop, length, 1)?;
        b.shoots(&axis, length, p.bare * length, 2, bud.key)?;
        branches.push((start..b.s.len() as u32, node));
    }

    let mut s = b.s;
    pge_tree::pipe_radii(
        &mut s,
        p.tree.mesh.tip_radius,
        p.tree.mesh.exponent.clamp(1.0, 4.0),
    );
    // The trunk keeps the pipe model's radii; each branch is thinned, subtree alike, to
    // `joint_ratio` of the trunk just above its joint (so the trunk stays the thickest
    // child at every whorl).
    let next_on_trunk: std::collections::BTreeMap<u32, u32> =
        trunk.windows(2).map(|w| (w[0], w[1])).collect();
    for (range, joint) in &branches {
        let above = next_on_trunk.get(joint).copied().unwrap_or(*joint);
        let cap = p.joint_ratio * s.radii[above as usize];
        let r = s.radii[range.start as usize];
        if r > cap && r > 0.0 {
            let k = cap / r;
            for i in range.clone() {
                s.radii[i as usize] *= k;
            }
        }
    }
    Ok(Built {
        skeleton: s,
        trunk,
        branches,
    })
}

#[cfg(test)]
mod tests;
