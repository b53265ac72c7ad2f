//! Merging of straight non-branching chains (seed 002).

use pge_engine::geometry::Skeleton;

/// Removes nodes with exactly one child where the branch runs straight: a node is dropped
/// when the direction from the last kept node to it and the direction from it to its child
/// differ by less than `max_angle_degrees`. Roots, forks and tips are always kept, so the
/// topology and the tips are unchanged; radii of kept nodes are unchanged. Leaf points on a
/// dropped node move to its nearest kept ancestor (their positions stay).
#[must_use]
pub fn merge_straight(skeleton: &Skeleton, max_angle_degrees: f32) -> Skeleton {
    let n = skeleton.len();
    let cos_max = max_angle_degrees.clamp(0.0, 180.0).to_radians().cos();
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
                    let here = skeleton.positions[i];
                    let next = skeleton.positions[only_child[i] as usize];
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
            new_index[i] = out.push(
                skeleton.positions[i],
                parent,
                skeleton.radii[i],
                skeleton.orders[i],
            );
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
}
