//! The trunk flare: extra rings over a root tube's first metres, widened into buttresses.

use pge_engine::math;
use std::f32::consts::TAU;

use glam::Vec3;

use crate::options::Flare;

/// Where a flared trunk gets rings of its own: fractions of the flare's height.
const FLARE_RINGS: [f32; 9] = [0.0, 0.03, 0.08, 0.15, 0.25, 0.38, 0.55, 0.75, 1.0];

/// Appends the points of a tube (position, radius, node) with extra points in its first
/// `height` metres (at [`FLARE_RINGS`]), each with its distance from the start along the
/// tube, and to `nodes` each point's node (`None` for the extra ones).
pub(super) fn with_flare_rings(
    points: &[(Vec3, f32, Option<u32>)],
    height: f32,
    out: &mut Vec<(Vec3, f32, f32)>,
    nodes: &mut Vec<Option<u32>>,
) {
    let mut travelled = 0.0;
    out.push((points[0].0, points[0].1, 0.0));
    nodes.push(points[0].2);
    for w in points.windows(2) {
        let ((a, ra, _), (b, rb, node)) = (w[0], w[1]);
        let len = a.distance(b);
        for f in FLARE_RINGS {
            let s = f * height;
            if s > travelled + 1e-3 && s < travelled + len - 1e-3 {
                let t = (s - travelled) / len;
                out.push((a.lerp(b, t), ra + (rb - ra) * t, s));
                nodes.push(None);
            }
        }
        travelled += len;
        out.push((b, rb, travelled));
        nodes.push(node);
    }
}
/// A flared ring vertex at `travelled` metres up the trunk and `turn` turns around it: the
/// factor its offset from the axis is widened by, and its normal. The flare fades from
/// `1 + spread` on a buttress at the ground to nothing at `height`; buttresses are
/// `roots` lobes around the ring. `radial` and `tangent` are the vertex's unit directions
/// out of and around the ring, `dir` the trunk's.
pub(super) fn flared(
    f: Flare,
    travelled: f32,
    turn: f32,
    radius: f32,
    radial: Vec3,
    tangent: Vec3,
    dir: Vec3,
) -> (f32, Vec3) {
    let h = (1.0 - travelled / f.height).clamp(0.0, 1.0);
    let fade = f.spread * math::powf(h, 2.5);
    let dfade = -2.5 * f.spread / f.height * math::powf(h, 1.5);
    let n = f.roots as f32;
    let wave = 0.5 + 0.5 * math::cos(TAU * n * turn);
    let lobe = 0.2 + 0.8 * wave * wave;
    let dlobe = 0.8 * 2.0 * wave * (-0.5 * n * math::sin(TAU * n * turn));
    let widen = 1.0 + fade * lobe;
    // The surface r(theta, s) = radius * widen: its normal leans back against the growth of
    // r around the ring and up the trunk.
    let normal = radial - tangent * (fade * dlobe / widen) - dir * (radius * dfade * lobe);
    (widen, normal.try_normalize().unwrap_or(radial))
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use pge_engine::geometry::Skeleton;

    use super::{FLARE_RINGS, Flare};
    use crate::cylinders::bark_mesh;
    use crate::options::MeshOptions;

    #[test]
    fn a_flared_trunk_spreads_into_buttresses_over_its_first_metre() {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.3, 0);
        s.push(Vec3::new(0.0, 4.0, 0.0), Some(r), 0.2, 0);
        let flare = Flare {
            roots: 5,
            spread: 1.0,
            height: 1.0,
        };
        let options = MeshOptions {
            sides: 40,
            flare: Some(flare),
            ..MeshOptions::default()
        };
        let m = bark_mesh(&s, &options);
        m.validate().expect("valid");
        assert!(m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-4));
        // Rings at the flare's heights, then the top.
        let rings = m.positions.len() / 41 - 1; // and the tip cap
        assert_eq!(rings, FLARE_RINGS.len() + 1);
        let reach = |y: f32| {
            m.positions
                .iter()
                .filter(|p| (p.y - y).abs() < 1e-4)
                .map(|p| Vec3::new(p.x, 0.0, p.z).length())
                .fold((f32::MAX, 0f32), |(lo, hi), r| (lo.min(r), hi.max(r)))
        };
        let (lo, hi) = reach(0.0);
        assert!(
            hi > 0.55 && lo < 0.4,
            "at the ground the buttresses reach {lo}..{hi}"
        );
        let (lo, hi) = reach(1.0);
        assert!(hi - lo < 1e-3, "round again at 1 m: {lo}..{hi}");
        // Five buttresses: the ground ring's radius has five maxima around.
        let ground: Vec<f32> = (0..40)
            .map(|k| Vec3::new(m.positions[k].x, 0.0, m.positions[k].z).length())
            .collect();
        let peaks = (0..40)
            .filter(|&k| ground[k] > ground[(k + 39) % 40] && ground[k] >= ground[(k + 1) % 40])
            .count();
        assert_eq!(peaks, 5);
        // Every face still points outward.
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
            let face = (m.positions[b] - m.positions[a]).cross(m.positions[c] - m.positions[a]);
            let avg = m.normals[a] + m.normals[b] + m.normals[c];
            assert!(face.dot(avg) > 0.0, "inward triangle {t:?}");
        }
    }
}
