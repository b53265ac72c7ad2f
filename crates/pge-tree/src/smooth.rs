//! Node smoothing (seed 000): each node moved part of the way toward its parent.

use glam::Vec3;
use pge_engine::geometry::Skeleton;

/// Moves every non-root node `amount` of the way toward its parent's original position:
/// `v' = v + amount * (v_parent - v)`. Seed 000 uses 0.5, which lowers branching angles and
/// shortens the zig-zag of space colonization. `amount` outside `[0, 1]` is clamped; 0 does
/// nothing. Leaf points move with their nodes.
pub fn smooth(skeleton: &mut Skeleton, amount: f32) {
    let amount = amount.clamp(0.0, 1.0);
    if amount == 0.0 {
        return;
    }
    let positions = &mut skeleton.positions;
    // The leaves first, while every position is the original.
    for leaf in &mut skeleton.leaves {
        let n = leaf.node as usize;
        if n < positions.len() {
            leaf.position += smoothed(positions, &skeleton.parents, n, amount) - positions[n];
        }
    }
    // Backwards: a parent precedes its children, so it is still where it was when they move
    // (no copy of the positions).
    for i in (0..positions.len()).rev() {
        positions[i] = smoothed(positions, &skeleton.parents, i, amount);
    }
}

/// Where smoothing by `amount` (already clamped) puts node `i`, from the original
/// `positions`.
pub(crate) fn smoothed(positions: &[Vec3], parents: &[Option<u32>], i: usize, amount: f32) -> Vec3 {
    match parents[i] {
        Some(p) => positions[i] + amount * (positions[p as usize] - positions[i]),
        None => positions[i],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::geometry::LeafPoint;

    #[test]
    fn halfway_to_the_original_parent() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 1.0, 0);
        let a = s.push(Vec3::new(0.0, 2.0, 0.0), Some(r), 1.0, 0);
        s.push(Vec3::new(2.0, 2.0, 0.0), Some(a), 1.0, 0);
        smooth(&mut s, 0.5);
        assert_eq!(
            s.positions,
            vec![Vec3::ZERO, Vec3::Y, Vec3::new(1.0, 2.0, 0.0)]
        );
        let before = s.clone();
        smooth(&mut s, 0.0);
        assert_eq!(s, before);
    }

    #[test]
    fn leaves_move_with_their_nodes() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 1.0, 0);
        let a = s.push(Vec3::new(0.0, 2.0, 0.0), Some(r), 1.0, 0);
        let b = s.push(Vec3::new(2.0, 2.0, 0.0), Some(a), 1.0, 0);
        let leaf = |node: u32, position: Vec3| LeafPoint {
            node,
            position,
            direction: Vec3::X,
            side: Vec3::Z,
            size: 1.0,
        };
        s.leaves = vec![leaf(b, Vec3::new(2.5, 2.0, 0.0)), leaf(r, Vec3::Y)];
        smooth(&mut s, 0.25);
        // Node b moves a quarter of the way to a's original place, (0, 2, 0), not to a's
        // new one; the root's leaf stays.
        assert_eq!(s.positions[b as usize], Vec3::new(1.5, 2.0, 0.0));
        assert_eq!(s.positions[a as usize], Vec3::new(0.0, 1.5, 0.0));
        assert_eq!(s.leaves[0].position, Vec3::new(2.0, 2.0, 0.0));
        assert_eq!(s.leaves[1].position, Vec3::Y);
    }
}
