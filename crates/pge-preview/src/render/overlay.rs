//! Lines drawn over or instead of the meshes: the ground grid and wireframe edges.

use glam::Vec3;
use pge_engine::math;

/// The three edges of every triangle as line pairs (shared edges are drawn twice, which
/// costs less than finding them).
#[must_use]
pub fn triangle_edges(indices: &[u32]) -> Vec<u32> {
    indices
        .chunks_exact(3)
        .flat_map(|t| [t[0], t[1], t[1], t[2], t[2], t[0]])
        .collect()
}

/// A ground grid on y = 0 around the model's footprint: lines as `[x, y, z, r, g, b, a]`,
/// spaced by a power of ten that gives 2 to 20 cells from the centre to the edge, every
/// tenth line brighter;
/// the X axis red and the Z axis blue.
#[must_use]
pub fn grid_lines(bounds: Option<(Vec3, Vec3)>) -> Vec<f32> {
    let (lo, hi) = bounds.unwrap_or((Vec3::splat(-1.0), Vec3::splat(1.0)));
    let half = ((hi - lo).length() * 0.75).max(1.0);
    let spacing = math::powf(10f32, math::log10(half / 2.0).floor());
    let centre = (lo + hi) * 0.5;
    let n = (half / spacing).ceil() as i64;
    let (cx, cz) = (
        (centre.x / spacing).round() as i64,
        (centre.z / spacing).round() as i64,
    );
    let mut out = Vec::new();
    let mut line = |a: [f32; 3], b: [f32; 3], c: [f32; 4]| {
        out.extend_from_slice(&[a[0], a[1], a[2], c[0], c[1], c[2], c[3]]);
        out.extend_from_slice(&[b[0], b[1], b[2], c[0], c[1], c[2], c[3]]);
    };
    let (x0, x1) = ((cx - n) as f32 * spacing, (cx + n) as f32 * spacing);
    let (z0, z1) = ((cz - n) as f32 * spacing, (cz + n) as f32 * spacing);
    for i in -n..=n {
        let (x, z) = ((cx + i) as f32 * spacing, (cz + i) as f32 * spacing);
        let colour = |k: i64, axis: [f32; 4]| {
            if k == 0 {
                axis
            } else if k % 10 == 0 {
                [0.5, 0.5, 0.5, 0.6]
            } else {
                [0.3, 0.3, 0.3, 0.45]
            }
        };
        line(
            [x, 0.0, z0],
            [x, 0.0, z1],
            colour(cx + i, [0.2, 0.3, 0.9, 0.9]),
        );
        line(
            [x0, 0.0, z],
            [x1, 0.0, z],
            colour(cz + i, [0.9, 0.2, 0.2, 0.9]),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edges_of_two_triangles() {
        assert_eq!(
            triangle_edges(&[0, 1, 2, 2, 1, 3]),
            vec![0, 1, 1, 2, 2, 0, 2, 1, 1, 3, 3, 2]
        );
    }

    #[test]
    fn the_grid_scales_with_the_model_and_marks_the_axes() {
        let small = grid_lines(Some((Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 3.0, 1.0))));
        let big = grid_lines(Some((
            Vec3::new(-100.0, 0.0, -100.0),
            Vec3::new(100.0, 30.0, 100.0),
        )));
        let lines = |g: &[f32]| g.len() / 14;
        assert!((10..=110).contains(&lines(&small)), "{}", lines(&small));
        assert!((10..=110).contains(&lines(&big)), "{}", lines(&big));
        assert!(small.chunks(7).all(|v| v[1] == 0.0), "on the ground");
        // The Z axis line (x = 0) is blue.
        let z_axis = small
            .chunks(14)
            .find(|l| l[0] == 0.0 && l[7] == 0.0)
            .expect("axis line");
        assert_eq!(&z_axis[3..7], &[0.2, 0.3, 0.9, 0.9]);
    }
}
