//! Leaves (seed 000 ch. 4): double-sided quads hung by the middle of one edge near branch
//! tips, a random count per tip, a random orientation, and a colour per leaf drawn between
//! two colours. The quads are textured with an alpha-masked silhouette.

use glam::{Quat, Vec2, Vec3, Vec4};
use pge_engine::geometry::{LeafPoint, Mesh, Skeleton};
use rand_mt::Mt64;

use crate::options::LeafOptions;

/// A uniform draw in `[0, 1)` (53 random bits, rounded to `f32`).
pub(crate) fn uniform(rng: &mut Mt64) -> f32 {
    pge_engine::random::uniform64(rng) as f32
}

/// A uniform integer in `lo..=hi`.
fn int_in(rng: &mut Mt64, lo: u32, hi: u32) -> u32 {
    if hi <= lo {
        lo
    } else {
        lo + (rng.next_u64() % u64::from(hi - lo + 1)) as u32
    }
}

/// Leaf points near the tips: for every tip (in index order) a count drawn in
/// `options.per_tip`; each leaf hangs on one of the tip's last `max_depth + 1` segments (the
/// segment ending at the tip, its parent segment, ...), at a random place along it, pointing
/// away from the branch at 35-75 degrees with a random azimuth and a random roll. A tip that
/// is a root (no segment) bears no leaves.
#[must_use]
pub fn tip_leaves(skeleton: &Skeleton, options: &LeafOptions, rng: &mut Mt64) -> Vec<LeafPoint> {
    let mut out = Vec::new();
    let pos = &skeleton.positions;
    for tip in skeleton.tips() {
        if skeleton.parents[tip as usize].is_none() {
            continue;
        }
        let count = int_in(rng, options.per_tip.0, options.per_tip.1);
        for _ in 0..count {
            // Climb up to `depth` segments, staying on a node that has a parent.
            let depth = int_in(rng, 0, options.max_depth);
            let mut node = tip;
            for _ in 0..depth {
                match skeleton.parents[node as usize] {
                    Some(p) if skeleton.parents[p as usize].is_some() => node = p,
                    _ => break,
                }
            }
            let Some(parent) = skeleton.parents[node as usize] else {
                continue;
            };
            let (a, b) = (pos[parent as usize], pos[node as usize]);
            let along = 0.35 + 0.65 * uniform(rng);
            let position = a.lerp(b, along);
            let branch = (b - a).try_normalize().unwrap_or(Vec3::Y);
            let (e1, e2) = branch.any_orthonormal_pair();
            let azimuth = std::f32::consts::TAU * uniform(rng);
            let out_dir = e1 * azimuth.cos() + e2 * azimuth.sin();
            let tilt = (35.0 + 40.0 * uniform(rng)).to_radians();
            let direction = (branch * tilt.cos() + out_dir * tilt.sin()).normalize();
            let roll = (uniform(rng) - 0.5) * 80f32.to_radians();
            let side0 = direction
                .cross(out_dir.cross(branch))
                .try_normalize()
                .unwrap_or(e1);
            let side = Quat::from_axis_angle(direction, roll) * side0;
            let size = options.size * (0.8 + 0.4 * uniform(rng));
            out.push(LeafPoint {
                node,
                position,
                direction,
                side,
                size,
            });
        }
    }
    out
}

/// Appends one quad per leaf point to `mesh` (positions, normals, uvs, colors, indices):
/// the middle of the quad's stalk edge at the point, the quad extending `size` along its
/// direction and `size * options.width` wide along its side; `v` runs from 0 at the stalk to 1 at the tip.
/// Each leaf's colour is drawn between `options.colors`. A leaf of size 0 or less takes
/// `options.size`.
pub fn append_leaf_quads(
    leaves: &[LeafPoint],
    options: &LeafOptions,
    rng: &mut Mt64,
    mesh: &mut Mesh,
) {
    let [c0, c1] = options.colors.map(Vec4::from_array);
    mesh.positions.reserve(leaves.len() * 4);
    mesh.normals.reserve(leaves.len() * 4);
    mesh.uvs.reserve(leaves.len() * 4);
    mesh.colors.reserve(leaves.len() * 4);
    mesh.indices.reserve(leaves.len() * 6);
    for leaf in leaves {
        let size = if leaf.size > 0.0 && leaf.size.is_finite() {
            leaf.size
        } else {
            options.size
        };
        let axis = leaf.direction.try_normalize().unwrap_or(Vec3::Y);
        let side = (leaf.side - axis * leaf.side.dot(axis))
            .try_normalize()
            .unwrap_or_else(|| axis.any_orthonormal_vector());
        let l = axis * size;
        let s = side * (0.5 * size * options.width);
        let normal = side.cross(axis);
        let color = c0.lerp(c1, uniform(rng));
        let base = mesh.positions.len() as u32;
        let p = leaf.position;
        mesh.positions
            .extend_from_slice(&[p - s, p + s, p + s + l, p - s + l]);
        mesh.normals.extend_from_slice(&[normal; 4]);
        mesh.uvs.extend_from_slice(&[
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ]);
        mesh.colors.extend_from_slice(&[color; 4]);
        mesh.indices
            .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree() -> Skeleton {
        let mut s = Skeleton::new();
        let mut prev = s.push(Vec3::ZERO, None, 0.1, 0);
        for y in 1..=6 {
            prev = s.push(Vec3::new(0.0, y as f32, 0.0), Some(prev), 0.1, 0);
        }
        let fork = 3;
        let mut side = fork;
        for x in 1..=4 {
            side = s.push(
                Vec3::new(x as f32, 3.0 + x as f32, 0.0),
                Some(side),
                0.05,
                1,
            );
        }
        s
    }

    /// Parent steps from `node` down to a tip below it, if the node lies within `max` of one.
    fn depth_to_tip(s: &Skeleton, node: u32, max: u32) -> Option<u32> {
        s.tips().into_iter().find_map(|t| {
            let mut n = t;
            for d in 0..=max {
                if n == node {
                    return Some(d);
                }
                n = s.parents[n as usize]?;
            }
            None
        })
    }

    #[test]
    fn leaves_hang_near_tips_within_max_depth() {
        let s = tree();
        let opts = LeafOptions {
            per_tip: (5, 9),
            max_depth: 2,
            ..LeafOptions::default()
        };
        let mut rng = Mt64::new(3);
        let leaves = tip_leaves(&s, &opts, &mut rng);
        assert!(leaves.len() >= 10 && leaves.len() <= 18, "{}", leaves.len());
        for l in &leaves {
            assert!(
                depth_to_tip(&s, l.node, 2).is_some(),
                "leaf on node {}",
                l.node
            );
            let parent = s.parents[l.node as usize].expect("not a root");
            // The stalk point lies on the segment parent -> node.
            let (a, b) = (s.positions[parent as usize], s.positions[l.node as usize]);
            let t = (l.position - a).dot(b - a) / (b - a).length_squared();
            assert!((0.0..=1.0).contains(&t));
            assert!(((a + (b - a) * t) - l.position).length() < 1e-5);
            assert!((l.direction.length() - 1.0).abs() < 1e-5);
            assert!(l.direction.dot(l.side).abs() < 1e-5);
        }
        let zero = LeafOptions {
            max_depth: 0,
            ..opts
        };
        for l in tip_leaves(&s, &zero, &mut rng) {
            assert!(s.tips().contains(&l.node));
        }
    }

    #[test]
    fn quads_are_hung_by_the_middle_of_an_edge() {
        let leaf = LeafPoint {
            node: 0,
            position: Vec3::new(1.0, 2.0, 3.0),
            direction: Vec3::Y,
            side: Vec3::X,
            size: 2.0,
        };
        let opts = LeafOptions {
            colors: [[1.0, 0.0, 0.0, 1.0]; 2],
            ..LeafOptions::default()
        };
        let mut mesh = Mesh::default();
        append_leaf_quads(&[leaf], &opts, &mut Mt64::new(1), &mut mesh);
        mesh.validate().expect("valid");
        assert_eq!(
            mesh.positions,
            vec![
                Vec3::new(0.0, 2.0, 3.0),
                Vec3::new(2.0, 2.0, 3.0),
                Vec3::new(2.0, 4.0, 3.0),
                Vec3::new(0.0, 4.0, 3.0)
            ]
        );
        assert_eq!((mesh.positions[0] + mesh.positions[1]) * 0.5, leaf.position);
        assert_eq!(mesh.normals[0], Vec3::Z);
        assert_eq!(mesh.colors[0], Vec4::new(1.0, 0.0, 0.0, 1.0));
        let [a, b, c] = [0, 1, 2].map(|i| mesh.positions[mesh.indices[i] as usize]);
        assert!(
            (b - a).cross(c - a).normalize().dot(Vec3::Z) > 0.99,
            "front face along the normal"
        );
    }

    #[test]
    fn colours_lie_between_the_two() {
        let opts = LeafOptions {
            colors: [[0.0, 0.2, 0.0, 1.0], [0.5, 0.6, 0.1, 1.0]],
            ..LeafOptions::default()
        };
        let s = tree();
        let mut rng = Mt64::new(9);
        let leaves = tip_leaves(&s, &opts, &mut rng);
        let mut mesh = Mesh::default();
        append_leaf_quads(&leaves, &opts, &mut rng, &mut mesh);
        for c in &mesh.colors {
            assert!(c.x >= 0.0 && c.x <= 0.5 && c.y >= 0.2 && c.y <= 0.6, "{c}");
            assert!(
                ((c.x / 0.5) - (c.y - 0.2) / 0.4).abs() < 1e-4,
                "on the segment between"
            );
        }
    }
}
