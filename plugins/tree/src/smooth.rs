//! Node smoothing (seed 000): each node moved part of the way toward its parent.

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
    let original = skeleton.positions.clone();
    for (i, parent) in skeleton.parents.iter().enumerate() {
        if let Some(p) = parent {
            skeleton.positions[i] = original[i] + amount * (original[*p as usize] - original[i]);
        }
    }
    for leaf in &mut skeleton.leaves {
        let n = leaf.node as usize;
        if n < original.len() {
            leaf.position += skeleton.positions[n] - original[n];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

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
}
