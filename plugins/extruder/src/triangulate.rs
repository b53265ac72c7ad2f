//! Ear clipping of a simple polygon, for the extruder's caps.

use glam::Vec2;

fn cross(o: Vec2, a: Vec2, b: Vec2) -> f32 {
    (a - o).perp_dot(b - o)
}

/// Whether `p` lies inside or on the counter-clockwise triangle `(a, b, c)`.
fn in_triangle(p: Vec2, a: Vec2, b: Vec2, c: Vec2) -> bool {
    cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0
}

/// The most points an outline may have to be triangulated by ear clipping.
pub const EAR_CLIPPING_MAX: usize = 256;

/// Triangulates the polygon `points` (closed, any orientation) into `n - 2` triangles of
/// indices into `points`, counter-clockwise in the plane of `points`.
///
/// A simple polygon (convex or not) of up to [`EAR_CLIPPING_MAX`] points is triangulated by
/// ear clipping. When no ear can be found (a self-intersecting or degenerate outline), or
/// the outline has more points (ear clipping is quadratic or worse), the rest is closed by a
/// fan, which is right for convex outlines such as fine circles. The count is always `n - 2`.
#[must_use]
pub fn triangulate(points: &[Vec2]) -> Vec<[usize; 3]> {
    let n = points.len();
    if n < 3 {
        return Vec::new();
    }
    if n > EAR_CLIPPING_MAX {
        return (1..n - 1).map(|k| [0, k, k + 1]).collect();
    }
    let area: f32 = (0..n)
        .map(|i| points[i].perp_dot(points[(i + 1) % n]))
        .sum();
    let mut ring: Vec<usize> = (0..n).collect();
    let ccw = area >= 0.0;
    if !ccw {
        ring.reverse();
    }
    let mut out = Vec::with_capacity(n - 2);
    let mut guard = 0usize;
    let mut i = 0usize;
    while ring.len() > 3 && guard < ring.len() {
        let m = ring.len();
        let (ia, ib, ic) = (ring[(i + m - 1) % m], ring[i % m], ring[(i + 1) % m]);
        let (a, b, c) = (points[ia], points[ib], points[ic]);
        let convex = cross(a, b, c) > 0.0;
        let is_ear = convex
            && ring
                .iter()
                .all(|&k| k == ia || k == ib || k == ic || !in_triangle(points[k], a, b, c));
        if is_ear {
            out.push([ia, ib, ic]);
            ring.remove(i % m);
            guard = 0;
            i %= ring.len();
        } else {
            i = (i + 1) % m;
            guard += 1;
        }
    }
    // Three left, or no ear found: close with a fan.
    for k in 1..ring.len() - 1 {
        out.push([ring[0], ring[k], ring[k + 1]]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::math;

    fn area(points: &[Vec2], tris: &[[usize; 3]]) -> f32 {
        tris.iter()
            .map(|t| cross(points[t[0]], points[t[1]], points[t[2]]) * 0.5)
            .sum()
    }

    #[test]
    fn convex_and_concave_polygons() {
        let square = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ];
        let t = triangulate(&square);
        assert_eq!(t.len(), 2);
        assert!((area(&square, &t) - 1.0).abs() < 1e-6);
        // A star: concave, 10 points.
        let star: Vec<Vec2> = (0..10)
            .map(|i| {
                let a = std::f32::consts::TAU * i as f32 / 10.0;
                let r = if i % 2 == 0 { 1.0 } else { 0.4 };
                Vec2::new(r * math::cos(a), r * math::sin(a))
            })
            .collect();
        let t = triangulate(&star);
        assert_eq!(t.len(), 8);
        assert!(
            t.iter()
                .all(|t| cross(star[t[0]], star[t[1]], star[t[2]]) > 0.0),
            "no flipped ear"
        );
        let expected: f32 = (0..10)
            .map(|i| star[i].perp_dot(star[(i + 1) % 10]) * 0.5)
            .sum();
        assert!((area(&star, &t) - expected).abs() < 1e-5);
    }

    #[test]
    fn clockwise_outlines_give_counter_clockwise_triangles() {
        let cw = [
            Vec2::new(0.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
        ];
        let t = triangulate(&cw);
        assert_eq!(t.len(), 2);
        assert!(t.iter().all(|t| cross(cw[t[0]], cw[t[1]], cw[t[2]]) > 0.0));
    }

    #[test]
    fn large_outlines_are_fanned() {
        let circle: Vec<Vec2> = (0..1000)
            .map(|i| {
                let a = std::f32::consts::TAU * i as f32 / 1000.0;
                Vec2::new(math::cos(a), math::sin(a))
            })
            .collect();
        let t = triangulate(&circle);
        assert_eq!(t.len(), 998);
        assert!((area(&circle, &t) - std::f32::consts::PI).abs() < 1e-3);
    }

    #[test]
    fn degenerate_outlines_still_give_n_minus_2() {
        let line = [
            Vec2::ZERO,
            Vec2::X,
            Vec2::new(2.0, 0.0),
            Vec2::new(3.0, 0.0),
        ];
        assert_eq!(triangulate(&line).len(), 2);
        assert!(triangulate(&line[..2]).is_empty());
    }
}
