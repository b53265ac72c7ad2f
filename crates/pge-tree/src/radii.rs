//! Branch radii by the pipe model and branch orders.

use pge_engine::geometry::Skeleton;
use pge_engine::math;

/// Sets every radius by the pipe model: tips get `tip_radius`, and a node with children gets
/// `r = (r1^n + r2^n + ...)^(1/n)` over its children (`n = exponent`, 2.3 in seed 002). A
/// node with one child has that child's radius, so non-branching chains are cylinders.
///
/// Runs backwards over the topologically ordered nodes, children before parents: O(nodes).
/// `r^n` is computed once for all tips, and a node with one child takes the child's radius
/// and `r^n` as they are: `(r^n)^(1/n)` rounded to `f32` is `r` whenever `r^n` is a normal
/// `f64` and `n` is in `[1, 4]` (the error of two `powf` is some 1e-14 of `r`, far under half
/// an `f32` step), so only forks pay the two `powf`, and the radii are the same bits.
pub fn pipe_radii(skeleton: &mut Skeleton, tip_radius: f32, exponent: f32) {
    let n = skeleton.len();
    // Sum of r^n over the children of each node, and how many children (up to 2).
    let mut sums = vec![0.0f64; n];
    let mut children = vec![0u8; n];
    let e = f64::from(exponent);
    let inverse = 1.0 / e;
    let tip_power = math::powf(f64::from(tip_radius), e);
    let chains_exact = (1.0..=4.0).contains(&e);
    for i in (0..n).rev() {
        let (r, power) = match children[i] {
            0 => (tip_radius, tip_power),
            // `radii[i]` holds the only child's radius (set below), `sums[i]` its `r^n`.
            1 if chains_exact && sums[i].is_normal() => (skeleton.radii[i], sums[i]),
            _ => {
                let r = math::powf(sums[i], inverse) as f32;
                (r, math::powf(f64::from(r), e))
            }
        };
        skeleton.radii[i] = r;
        if let Some(p) = skeleton.parents[i] {
            let p = p as usize;
            sums[p] += power;
            children[p] = children[p].saturating_add(1);
            skeleton.radii[p] = r;
        }
    }
}

/// The child that continues each node's branch: the child with the parent's order if any
/// (a turtle marks lateral branches with a higher order), then the thickest, then the one
/// that turns least, then the first. `None` for tips.
#[must_use]
pub fn main_children(skeleton: &Skeleton, children: &[Vec<u32>]) -> Vec<Option<u32>> {
    children
        .iter()
        .enumerate()
        .map(|(i, kids)| main_child(skeleton, i, kids))
        .collect()
}

/// The child of node `i` among `kids` (in increasing order) that continues its branch: see
/// [`main_children`].
pub(crate) fn main_child(skeleton: &Skeleton, i: usize, kids: &[u32]) -> Option<u32> {
    let pos = &skeleton.positions;
    let (&first, rest) = kids.split_first()?;
    if rest.is_empty() {
        return Some(first);
    }
    // Compared as the tuple (same order, radius, turn) compares, but the turn (and the
    // incoming direction) computed only when order and radius tie.
    let head = |c: u32| {
        let c = c as usize;
        (skeleton.orders[c] == skeleton.orders[i], skeleton.radii[c])
    };
    let mut incoming = None;
    let mut turn = |c: u32| {
        let incoming = *incoming.get_or_insert_with(|| {
            skeleton.parents[i]
                .and_then(|p| (pos[i] - pos[p as usize]).try_normalize())
                .unwrap_or(glam::Vec3::Y)
        });
        (pos[c as usize] - pos[i])
            .try_normalize()
            .map_or(-2.0, |d| d.dot(incoming))
    };
    let (mut best, mut best_head, mut best_turn) = (first, head(first), None);
    for &c in rest {
        let h = head(c);
        match h.partial_cmp(&best_head) {
            Some(std::cmp::Ordering::Equal) => {
                let t = turn(c);
                let b = match best_turn {
                    Some(b) => b,
                    None => turn(best),
                };
                if t > b {
                    (best, best_head, best_turn) = (c, h, Some(t));
                } else {
                    best_turn = Some(b);
                }
            }
            Some(std::cmp::Ordering::Greater) => (best, best_head, best_turn) = (c, h, None),
            _ => {}
        }
    }
    Some(best)
}

/// Sets branch orders from the radii: a root has order 0, the main child of a node (see
/// [`main_children`], decided by radius and direction here) keeps its parent's order and every
/// other child gets one more. For skeletons whose generator does not know orders (space
/// colonization); call it after [`pipe_radii`].
pub fn assign_orders(skeleton: &mut Skeleton) {
    for o in &mut skeleton.orders {
        *o = 0;
    }
    let children = Children::of(skeleton);
    let main: Vec<Option<u32>> = (0..skeleton.len())
        .map(|i| main_child(skeleton, i, children.of_node(i)))
        .collect();
    for (i, &continuing) in main.iter().enumerate() {
        let order = skeleton.orders[i];
        for &c in children.of_node(i) {
            skeleton.orders[c as usize] = if Some(c) == continuing {
                order
            } else {
                order + 1
            };
        }
    }
}

/// Each node's children, in increasing order, in one array.
pub(crate) struct Children {
    /// Where each node's children start in `nodes`, and one past the last node's.
    starts: Vec<u32>,
    nodes: Vec<u32>,
}

impl Children {
    pub(crate) fn of(skeleton: &Skeleton) -> Children {
        let mut starts = vec![0u32; skeleton.len() + 1];
        for p in skeleton.parents.iter().flatten() {
            starts[*p as usize + 1] += 1;
        }
        for i in 0..skeleton.len() {
            starts[i + 1] += starts[i];
        }
        let mut next = starts.clone();
        let mut nodes = vec![0u32; starts[skeleton.len()] as usize];
        for (i, p) in skeleton.parents.iter().enumerate() {
            if let Some(p) = p {
                nodes[next[*p as usize] as usize] = i as u32;
                next[*p as usize] += 1;
            }
        }
        Children { starts, nodes }
    }

    pub(crate) fn of_node(&self, i: usize) -> &[u32] {
        &self.nodes[self.starts[i] as usize..self.starts[i + 1] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A trunk of two nodes forking into two tips, one of which forks again.
    fn fork() -> Skeleton {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.0, 0);
        let a = s.push(Vec3::Y, Some(r), 0.0, 0);
        s.push(Vec3::new(-1.0, 2.0, 0.0), Some(a), 0.0, 0);
        let c = s.push(Vec3::new(1.0, 2.0, 0.0), Some(a), 0.0, 0);
        s.push(Vec3::new(1.0, 3.0, 0.0), Some(c), 0.0, 0);
        s.push(Vec3::new(2.0, 3.0, 0.0), Some(c), 0.0, 0);
        s
    }

    #[test]
    fn pipe_model_holds_at_every_fork() {
        let mut s = fork();
        pipe_radii(&mut s, 0.1, 2.3);
        let children = s.children();
        for (i, kids) in children.iter().enumerate() {
            if kids.is_empty() {
                assert_eq!(s.radii[i], 0.1);
            } else {
                let sum: f32 = kids
                    .iter()
                    .map(|c| math::powf(s.radii[*c as usize], 2.3))
                    .sum();
                assert!((math::powf(s.radii[i], 2.3) - sum).abs() < 1e-6, "node {i}");
            }
        }
        assert_eq!(s.radii[0], s.radii[1]);
        // Exponent 2: area is conserved, three tips of 0.1 give sqrt(3) * 0.1 at the root.
        pipe_radii(&mut s, 0.1, 2.0);
        assert!((s.radii[0] - 3f32.sqrt() * 0.1).abs() < 1e-6);
    }

    /// The pipe model as it was first written: two `powf` a node.
    fn pipe_radii_by_node(skeleton: &mut Skeleton, tip_radius: f32, exponent: f32) {
        let n = skeleton.len();
        let mut sums = vec![0.0f64; n];
        let mut has_child = vec![false; n];
        let e = f64::from(exponent);
        for i in (0..n).rev() {
            let r = if has_child[i] {
                math::powf(sums[i], 1.0 / e) as f32
            } else {
                tip_radius
            };
            skeleton.radii[i] = r;
            if let Some(p) = skeleton.parents[i] {
                sums[p as usize] += math::powf(f64::from(r), e);
                has_child[p as usize] = true;
            }
        }
    }

    #[test]
    fn chains_and_tips_skip_powf_to_the_same_bits() {
        // Random trees (long chains, forks of 2 to 4) over tip radii and exponents across
        // their range and beyond it (where chains take the two `powf`).
        let mut rng = rand_mt::Mt64::new(7);
        let tips = [0.01f32, 0.0123, 1e-30, 1e-44, 0.0, 3.0e9, 1.0, 0.37];
        let exponents = [1.0f32, 1.5, 2.0, 2.3, 2.5, 3.7, 4.0, 0.5, 7.0];
        for round in 0..200 {
            let mut s = Skeleton::new();
            s.push(Vec3::ZERO, None, 0.0, 0);
            for i in 1..(50 + rng.next_u64() % 400) as u32 {
                // Mostly the last node (a chain), sometimes an earlier one (a fork).
                let parent = if rng.next_u64().is_multiple_of(4) {
                    (rng.next_u64() % u64::from(i)) as u32
                } else {
                    i - 1
                };
                s.push(Vec3::splat(i as f32), Some(parent), 0.0, 0);
            }
            let tip = tips[round % tips.len()];
            let e = exponents[round % exponents.len()];
            let mut expected = s.clone();
            pipe_radii_by_node(&mut expected, tip, e);
            pipe_radii(&mut s, tip, e);
            let bits = |s: &Skeleton| s.radii.iter().map(|r| r.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&s),
                bits(&expected),
                "round {round}, tip {tip}, exponent {e}"
            );
        }
    }

    /// The main child as it was first written: the whole key of every child.
    fn main_child_by_key(skeleton: &Skeleton, i: usize, kids: &[u32]) -> Option<u32> {
        let pos = &skeleton.positions;
        let incoming = skeleton.parents[i]
            .and_then(|p| (pos[i] - pos[p as usize]).try_normalize())
            .unwrap_or(glam::Vec3::Y);
        let key = |c: u32| {
            let c = c as usize;
            let same_order = skeleton.orders[c] == skeleton.orders[i];
            let turn = (pos[c] - pos[i])
                .try_normalize()
                .map_or(-2.0, |d| d.dot(incoming));
            (same_order, skeleton.radii[c], turn)
        };
        let (&first, rest) = kids.split_first()?;
        let mut best = first;
        for &c in rest {
            if key(c) > key(best) {
                best = c;
            }
        }
        Some(best)
    }

    #[test]
    fn main_children_are_the_ones_the_whole_key_picks() {
        // Forks of up to 5 children with tied radii and orders, NaN radii, -0.0 and 0.0,
        // children on their parent (no turn) and in its direction.
        let mut rng = rand_mt::Mt64::new(11);
        let mut pick = |n: u64| (rng.next_u64() % n) as usize;
        let radii = [0.1f32, 0.1, 0.2, f32::NAN, 0.0, -0.0];
        let spots = [
            Vec3::ZERO,
            Vec3::Y,
            Vec3::X,
            Vec3::new(0.5, 1.0, 0.0),
            Vec3::NEG_Y,
        ];
        for round in 0..2000 {
            let mut s = Skeleton::new();
            let root = s.push(Vec3::ZERO, None, 1.0, 0);
            let parent = if round % 5 == 0 {
                root
            } else {
                s.push(spots[pick(5)] + Vec3::Y, Some(root), 1.0, 0)
            };
            let at = s.positions[parent as usize];
            let kids: Vec<u32> = (0..1 + pick(5))
                .map(|_| {
                    s.push(
                        at + spots[pick(5)],
                        Some(parent),
                        radii[pick(6)],
                        pick(2) as u32,
                    )
                })
                .collect();
            s.orders[parent as usize] = pick(2) as u32;
            let i = parent as usize;
            assert_eq!(
                main_child(&s, i, &kids),
                main_child_by_key(&s, i, &kids),
                "round {round}"
            );
        }
    }

    #[test]
    fn orders_follow_the_thickest_child() {
        let mut s = fork();
        pipe_radii(&mut s, 0.1, 2.3);
        assign_orders(&mut s);
        // Node 3 carries two tips, so it is the main child of node 1 and node 2 is lateral;
        // of node 3's equal tips, node 5 turns least.
        assert_eq!(s.orders, vec![0, 0, 1, 0, 1, 0]);
    }
}
