//! Merging of straight non-branching chains (seed 002).

use pge_engine::geometry::Skeleton;
use pge_engine::math;

/// Removes nodes with exactly one child where the branch runs straight: a node is dropped
/// when the direction from the last kept node to it and the direction from it to its child
/// differ by less than `max_angle_degrees`. Roots, forks and tips are always kept, so the
/// topology and the tips are unchanged; radii of kept nodes are unchanged. Leaf points on a
/// dropped node move to its nearest kept ancestor (their positions stay).
#[must_use]
pub fn merge_straight(skeleton: &Skeleton, max_angle_degrees: f32) -> Skeleton {
    merge_by(skeleton, |i| skeleton.positions[i], max_angle_degrees)
}

/// [`smooth`](crate::smooth) then [`merge_straight`], without the smoothed copy of the
/// skeleton: only the smoothed positions are made (the same operations, so the same bits as
/// the two in turn), and the merge reads the rest from `skeleton`.
#[must_use]
pub(crate) fn smooth_and_merge(
    skeleton: &Skeleton,
    amount: f32,
    max_angle_degrees: f32,
) -> Skeleton {
    let amount = amount.clamp(0.0, 1.0);
    if amount == 0.0 {
        return merge_straight(skeleton, max_angle_degrees);
    }
    let positions = &skeleton.positions;
    let smoothed: Vec<glam::Vec3> = (0..positions.len())
        .map(|i| crate::smooth::smoothed(positions, &skeleton.parents, i, amount))
        .collect();
    let mut out = merge_by(skeleton, |i| smoothed[i], max_angle_degrees);
    // The leaves move with their nodes, as `smooth` moves them; `merge_by` kept their order
    // and positions.
    for (leaf, original) in out.leaves.iter_mut().zip(&skeleton.leaves) {
        let n = original.node as usize;
        if n < smoothed.len() {
            leaf.position += smoothed[n] - positions[n];
        }
    }
    out
}

/// [`merge_straight`] over the positions `position` gives for each node.
fn merge_by(
    skeleton: &Skeleton,
    position: impl Fn(usize) -> glam::Vec3,
    max_angle_degrees: f32,
) -> Skeleton {
    let n = skeleton.len();
    let cos_max = math::cos(max_angle_degrees.clamp(0.0, 180.0).to_radians());
    let mut child_count = vec![0u32; n];
    let mut only_child = vec![u32::MAX; n];
    for (i, p) in skeleton.parents.iter().enumerate() {
        if let Some(p) = p {
            child_count[*p as usize] += 1;
            only_child[*p as usize] = i as u32;
        }
    }
    // For each node: its index in the output if kept, else the output index of the kept
    // ancestor that stands in for it.
    let mut new_index = vec![0u32; n];
    // Made for every node, so that no push reallocates.
    let mut out = Skeleton {
        positions: Vec::with_capacity(n),
        parents: Vec::with_capacity(n),
        radii: Vec::with_capacity(n),
        orders: Vec::with_capacity(n),
        leaves: Vec::new(),
    };
    for i in 0..n {
        let keep = match skeleton.parents[i] {
            None => true,
            Some(p) => {
                if child_count[i] != 1 {
                    true
                } else {
                    let anchor = out.positions[new_index[p as usize] as usize];
                    let here = position(i);
                    let next = position(only_child[i] as usize);
                    match (
                        (here - anchor).try_normalize(),
                        (next - here).try_normalize(),
                    ) {
                        (Some(a), Some(b)) => a.dot(b) < cos_max,
                        // A zero-length segment adds nothing: drop it.
                        _ => false,
                    }
                }
            }
        };
        if keep {
            let parent = skeleton.parents[i].map(|p| new_index[p as usize]);
            new_index[i] = out.push(position(i), parent, skeleton.radii[i], skeleton.orders[i]);
        } else {
            // Not a root (roots are kept), so the parent exists and precedes i.
            new_index[i] = skeleton.parents[i].map_or(0, |p| new_index[p as usize]);
        }
    }
    out.leaves = skeleton
        .leaves
        .iter()
        .map(|l| {
            let mut l = *l;
            l.node = new_index.get(l.node as usize).copied().unwrap_or(0);
            l
        })
        .collect();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn straight_runs_collapse_and_bends_stay() {
        let mut s = Skeleton::new();
        let mut prev = s.push(Vec3::ZERO, None, 1.0, 0);
        for y in 1..=4 {
            prev = s.push(Vec3::new(0.0, y as f32, 0.0), Some(prev), 1.0, 0);
        }
        // A right-angle bend at (0, 4, 0), then two more straight nodes.
        let bend = prev;
        let a = s.push(Vec3::new(1.0, 4.0, 0.0), Some(bend), 1.0, 0);
        let b = s.push(Vec3::new(2.0, 4.0, 0.0), Some(a), 1.0, 0);
        // And a fork at b.
        s.push(Vec3::new(3.0, 4.0, 0.0), Some(b), 1.0, 0);
        s.push(Vec3::new(2.0, 5.0, 0.0), Some(b), 1.0, 0);
        let m = merge_straight(&s, 5.0);
        assert_eq!(
            m.positions,
            vec![
                Vec3::ZERO,
                Vec3::new(0.0, 4.0, 0.0),
                Vec3::new(2.0, 4.0, 0.0),
                Vec3::new(3.0, 4.0, 0.0),
                Vec3::new(2.0, 5.0, 0.0)
            ]
        );
        assert_eq!(m.parents, vec![None, Some(0), Some(1), Some(2), Some(2)]);
        assert_eq!(m.tips().len(), s.tips().len());
        // Angle 0 keeps nodes that bend at all, which a straight line does not.
        assert_eq!(merge_straight(&s, 0.0).len(), 5);
    }

    /// Every float of a skeleton as bits, so that -0.0 and 0.0 differ.
    fn bits(s: &Skeleton) -> (Vec<u32>, Vec<Option<u32>>, Vec<u32>, Vec<u32>) {
        let positions = s
            .positions
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits));
        let leaves = s.leaves.iter().flat_map(|l| {
            [l.position.to_array(), l.direction.to_array()]
                .into_iter()
                .flatten()
                .map(f32::to_bits)
                .chain([l.node, l.size.to_bits()])
        });
        let radii = s.radii.iter().map(|r| r.to_bits());
        (
            positions.collect(),
            s.parents.clone(),
            radii.chain(s.orders.iter().copied()).collect(),
            leaves.collect(),
        )
    }

    #[test]
    fn smoothing_while_merging_gives_the_same_bits_as_in_turn() {
        let mut rng = rand_mt::Mt64::new(3);
        let mut unit = || (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        for round in 0..100 {
            let mut s = Skeleton::new();
            s.push(Vec3::new(-0.0, 0.0, -0.0), None, 0.5, 0);
            for i in 1..(20 + round * 7) as u32 {
                let forks = unit() < 0.2;
                let parent = if forks {
                    (unit() * i as f32) as u32 % i
                } else {
                    i - 1
                };
                let p = s.positions[parent as usize];
                // Nearly straight steps (some merged), some zero-length ones, some bends.
                let step = Vec3::new(unit() * 0.1, 1.0, unit() * 0.1) * (unit() * 2.0).floor();
                s.push(p + step, Some(parent), unit(), i % 3);
            }
            for k in 0..s.len() as u32 / 3 {
                s.leaves.push(pge_engine::geometry::LeafPoint {
                    node: k * 3,
                    position: Vec3::new(unit(), -0.0, unit()),
                    direction: Vec3::Y,
                    side: Vec3::X,
                    size: 0.3,
                });
            }
            for (amount, angle) in [
                (0.5, 6.0),
                (0.0, 6.0),
                (0.25, 0.0),
                (1.5, 30.0),
                (-1.0, 6.0),
            ] {
                let mut expected = s.clone();
                crate::smooth(&mut expected, amount);
                let expected = merge_straight(&expected, angle);
                let fused = smooth_and_merge(&s, amount, angle);
                assert_eq!(
                    bits(&fused),
                    bits(&expected),
                    "round {round}, {amount}, {angle}"
                );
            }
        }
    }
}
