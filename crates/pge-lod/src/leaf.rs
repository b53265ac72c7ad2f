//! A leaf as the simplification sees it (a textured rectangle), and the new leaf that
//! replaces two collapsed ones (seed 003, §2.4.2 "Generación de las hojas nuevas").

use glam::{Vec3, Vec3A, Vec4};

/// One leaf of the collapse forest: an original leaf of the model or one made by a collapse.
///
/// The rectangle is centred on `center`, spans `2 * half_length` along `axis` (the texture's
/// `v`, from the stalk at `v = 0` to the tip) and `2 * half_width` along [`Leaf::side`] (the
/// texture's `u`); `normal` is its front face (`side × axis`, as pge-tree winds its quads).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Leaf {
    /// Centre of the rectangle.
    pub center: Vec3,
    /// Unit normal of the front face.
    pub normal: Vec3,
    /// Unit main axis, in the leaf's plane.
    pub axis: Vec3,
    /// Half the extent along `axis`.
    pub half_length: f32,
    /// Half the extent along [`Leaf::side`].
    pub half_width: f32,
    /// Original leaves represented (1 for an original leaf).
    pub count: u32,
    /// Summed area of the original leaves represented (the foliage the rectangle stands for;
    /// divided by [`Leaf::area`] it is the density that chooses an atlas cell).
    pub leaf_area: f32,
    /// Lower corner of the box around the original leaves represented.
    pub lo: Vec3,
    /// Upper corner of that box.
    pub hi: Vec3,
}

impl Leaf {
    /// The unit secondary axis `axis × normal` (the texture's `u`).
    #[must_use]
    pub fn side(&self) -> Vec3 {
        self.axis.cross(self.normal)
    }

    /// Area of the rectangle.
    #[must_use]
    pub fn area(&self) -> f32 {
        4.0 * self.half_length * self.half_width
    }

    /// Half the rectangle's diagonal: the radius of the sphere around it.
    #[must_use]
    pub fn radius(&self) -> f32 {
        (self.half_length * self.half_length + self.half_width * self.half_width).sqrt()
    }

    /// The four corners in the order of texture coordinates (0,0), (1,0), (1,1), (0,1):
    /// counter-clockwise seen from the front.
    #[must_use]
    pub fn corners(&self) -> [Vec3; 4] {
        let a = self.axis * self.half_length;
        let s = self.side() * self.half_width;
        let c = self.center;
        [c - s - a, c + s - a, c + s + a, c - s + a]
    }

    /// An original leaf from a quad's corners in the order of [`Leaf::corners`] (`p0 p1` the
    /// stalk edge, `p3 p2` the tip edge) and its normal (from the corners when `None`): the
    /// rectangle with the quad's centre and axes that bounds it. `None` for a degenerate or
    /// non-finite quad.
    #[must_use]
    pub fn from_quad(p: [Vec3; 4], normal: Option<Vec3>) -> Option<Leaf> {
        if p.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let center = (p[0] + p[1] + p[2] + p[3]) * 0.25;
        let from_corners = (p[1] - p[0]).cross(p[3] - p[0]).try_normalize();
        let normal = normal.and_then(Vec3::try_normalize).or(from_corners)?;
        let along = (p[2] + p[3]) - (p[0] + p[1]);
        let axis = (along - normal * along.dot(normal)).try_normalize()?;
        let side = axis.cross(normal);
        let half_length = p
            .iter()
            .map(|v| (*v - center).dot(axis).abs())
            .fold(0.0, f32::max);
        let half_width = p
            .iter()
            .map(|v| (*v - center).dot(side).abs())
            .fold(0.0, f32::max);
        let leaf = Leaf {
            center,
            normal,
            axis,
            half_length,
            half_width,
            count: 1,
            leaf_area: 0.0,
            lo: p[0].min(p[1]).min(p[2]).min(p[3]),
            hi: p[0].max(p[1]).max(p[2]).max(p[3]),
        };
        let area = leaf.area();
        (area > 0.0 && area.is_finite()).then_some(Leaf {
            leaf_area: area,
            ..leaf
        })
    }

    /// The leaf that replaces `a` and `b` (seed 003 §2.4.2, steps 1-4):
    /// 1. its centre is the mean of both centres weighted by the leaves each represents;
    /// 2. its normal the weighted mean of both normals (leaves are double-sided, so `b`'s
    ///    normal is flipped first when it faces away from `a`'s);
    /// 3. both leaves' corners are projected orthographically on the plane through that
    ///    centre; the line through the projected centres is the main axis, the secondary
    ///    axis is perpendicular to it, and the rectangle on these axes that contains both
    ///    projections is the bounding quad. The new leaf is centred on that rectangle (the
    ///    weighted centre lies on its main axis): a rectangle symmetric about the weighted
    ///    centre would reach past the leaves on the lighter side, and over many levels the
    ///    coarse leaves would outgrow the crown;
    /// 4. its area lies between the summed areas and the bounding area: the mean of the two
    ///    (the thesis' rule) when the bounding quad is the larger, so sparse pairs shrink;
    ///    the bounding area when the leaves overlap so much that their summed area is the
    ///    larger, so the quad never reaches past the leaves it replaces. The bounding quad is
    ///    scaled about its centre to that area.
    #[must_use]
    pub fn collapse(a: &Leaf, b: &Leaf) -> Leaf {
        let (wa, wb) = (a.count as f32, b.count as f32);
        let center = (a.center * wa + b.center * wb) / (wa + wb);
        let nb = if a.normal.dot(b.normal) < 0.0 {
            -b.normal
        } else {
            b.normal
        };
        let normal = (a.normal * wa + nb * wb)
            .try_normalize()
            .unwrap_or(a.normal);
        let in_plane = |v: Vec3| (v - normal * v.dot(normal)).try_normalize();
        let bigger = if b.area() > a.area() { b } else { a };
        let axis = in_plane(b.center - a.center)
            .or_else(|| in_plane(bigger.axis))
            .or_else(|| in_plane(bigger.side()))
            .unwrap_or_else(|| normal.any_orthonormal_vector());
        let side = axis.cross(normal);
        // Each leaf's corners, projected on the plane, span its centre's coordinates plus or
        // minus the projections of its half axes (projecting drops only the normal's part,
        // which `axis` and `side` do not see): no corner is built.
        let span = |l: &Leaf| {
            let (along, across) = (l.axis * l.half_length, l.side() * l.half_width);
            let d = l.center - center;
            let mid = glam::Vec2::new(d.dot(axis), d.dot(side));
            let half = glam::Vec2::new(
                along.dot(axis).abs() + across.dot(axis).abs(),
                along.dot(side).abs() + across.dot(side).abs(),
            );
            (mid - half, mid + half)
        };
        let ((lo_a, hi_a), (lo_b, hi_b)) = (span(a), span(b));
        let (lo, hi) = (lo_a.min(lo_b), hi_a.max(hi_b));
        let mid = (lo + hi) * 0.5;
        let center = center + axis * mid.x + side * mid.y;
        let (mut half_length, mut half_width) = (0.5 * (hi.x - lo.x), 0.5 * (hi.y - lo.y));
        let bounding = 4.0 * half_length * half_width;
        let summed = a.area() + b.area();
        let target = (0.5 * (summed + bounding)).min(bounding);
        if bounding > 0.0 {
            let s = (target / bounding).sqrt();
            half_length *= s;
            half_width *= s;
        } else {
            // Both leaves project onto a segment or a point: a square of the summed area.
            half_length = 0.5 * summed.sqrt();
            half_width = half_length;
        }
        Leaf {
            center,
            normal,
            axis,
            half_length,
            half_width,
            count: a.count + b.count,
            leaf_area: a.leaf_area + b.leaf_area,
            lo: a.lo.min(b.lo),
            hi: a.hi.max(b.hi),
        }
    }

    /// Whether the leaf [`Leaf::collapse`] makes of `a` and `b` surely reaches farther from
    /// its centre than `allowed[k]` along some world axis `k` (its reach: `|axis[k]| *
    /// half_length + |side[k]| * half_width`): a cheap refusal for the overhang bound, without
    /// the collapse's chain of three square roots and four divisions.
    ///
    /// It evaluates the construction's exact formulas on unnormalised vectors: with the
    /// weights `fa, fb` (summing to 1), `m = fa na + fb nb` (the normal times `|m|`), `v` from
    /// `a`'s centre to `b`'s, `u = |m|² v - (v·m) m` (the main axis times `α = |u|`) and
    /// `e = u × m` (the secondary axis times `α |m|`), the centres lie on the main axis at
    /// `-fb α / |m|²` and `fa α / |m|²` from the weighted centre, so the bounding quad's half
    /// sides are `H / (α |m|²)` and `W / (α |m|)`, with `H` the half span of both leaves along
    /// `u` (scaled by `|m|²`) and `W` along `e`. Its reach along `k` is then
    /// `s (|u[k]| H + |e[k]| W) / (α² |m|²)`, where `s² = min((1 + summed / bounding) / 2, 1)`
    /// is the squared scale to the new area; the test compares squares (in `f64`, so that
    /// they neither overflow nor underflow). `false` when unsure: a main axis within 6° of the
    /// normal, centres closer than a thousandth of the pair's size, a half side under a
    /// thousandth of it, or a pair smaller than 1e-4 or larger than 1e4. The margin asked,
    /// 1e-4 of `allowed` and of the pair's size, is far beyond the rounding of `collapse` and
    /// of this test under these conditions (about 1e-6 of them), so it never refuses a leaf
    /// whose reach is within `allowed`.
    #[must_use]
    pub(crate) fn surely_reaches(a: &Leaf, b: &Leaf, allowed: Vec3) -> bool {
        let (wa, wb) = (a.count as f32, b.count as f32);
        let inv = 1.0 / (wa + wb);
        let (fa, fb) = (wa * inv, wb * inv);
        // The same flip as `collapse`, decided on the same product.
        let nb = if a.normal.dot(b.normal) < 0.0 {
            -b.normal
        } else {
            b.normal
        };
        let m = Vec3A::from(a.normal) * fa + Vec3A::from(nb) * fb;
        let m2 = m.length_squared();
        let v = Vec3A::from(b.center) - Vec3A::from(a.center);
        let u = v * m2 - m * v.dot(m);
        let alpha2 = u.length_squared();
        let apart = v.abs().element_sum();
        let size = apart + (a.half_length + a.half_width) + (b.half_length + b.half_width);
        let well_posed = m2 >= 0.25
            && (1e-4..=1e4).contains(&size)
            && apart >= 1e-3 * size
            && alpha2 >= 0.01 * m2 * m2 * v.length_squared();
        if !well_posed {
            return false;
        }
        let e = u.cross(m);
        // The four half axes of both leaves, one world axis per row, so that their four
        // projections on a direction are one product.
        let half_axes = |l: &Leaf| {
            (
                Vec3A::from(l.axis) * l.half_length,
                Vec3A::from(l.side()) * l.half_width,
            )
        };
        let ((along_a, across_a), (along_b, across_b)) = (half_axes(a), half_axes(b));
        let row = |k: usize| Vec4::new(along_a[k], across_a[k], along_b[k], across_b[k]);
        let (xs, ys, zs) = (row(0), row(1), row(2));
        let on = |d: Vec3A| (xs * d.x + ys * d.y + zs * d.z).abs();
        let (du, de) = (on(u), on(e));
        let (au, bu) = ((du.x + du.y) * m2, (du.z + du.w) * m2);
        let (ae, be) = (de.x + de.y, de.z + de.w);
        let (pa, pb) = (-fb * alpha2, fa * alpha2);
        let h = 0.5 * ((pb + bu).max(pa + au) - (pb - bu).min(pa - au));
        let w = ae.max(be);
        let least = 1e-6 * size * size * alpha2 * m2;
        if !(h * h >= least * m2 && w * w >= least) {
            return false;
        }
        let reach = u.abs() * h + e.abs() * w;
        let margin = Vec3A::splat(1e-4 * size);
        let bound = (Vec3A::from(allowed).max(Vec3A::ZERO) * (1.0 + 1e-4) + margin) * (alpha2 * m2);
        // s² = s2 / bounding, the summed area over the bounding one being
        // `summed α² |m|³ / (4 H W)`.
        let summed = f64::from((a.area() + b.area()) * alpha2 * m2 * m2.sqrt());
        let bounding = 4.0 * f64::from(h) * f64::from(w);
        let s2 = (0.5 * (summed + bounding)).min(bounding);
        let (reach, bound) = (reach.as_dvec3(), bound.as_dvec3());
        (reach * reach * s2).cmpgt(bound * bound * bounding).any()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::assert_approx_eq;
    use pge_engine::math;

    fn square(center: Vec3, normal: Vec3, axis: Vec3, half: f32) -> Leaf {
        Leaf {
            center,
            normal,
            axis,
            half_length: half,
            half_width: half,
            count: 1,
            leaf_area: 4.0 * half * half,
            lo: center - Vec3::splat(half),
            hi: center + Vec3::splat(half),
        }
    }

    #[test]
    fn a_quad_round_trips_through_its_corners() {
        let leaf = square(Vec3::new(1.0, 2.0, 3.0), Vec3::Z, Vec3::Y, 0.5);
        let back = Leaf::from_quad(leaf.corners(), Some(Vec3::Z)).expect("quad");
        assert!(back.center.abs_diff_eq(leaf.center, 1e-6));
        assert!(back.axis.abs_diff_eq(Vec3::Y, 1e-6));
        assert_approx_eq!(back.area(), 1.0, rel 1e-5);
        // Winding: counter-clockwise around the normal, and the normal found from corners.
        let guessed = Leaf::from_quad(leaf.corners(), None).expect("quad");
        assert!(guessed.normal.abs_diff_eq(Vec3::Z, 1e-6));
        assert!(Leaf::from_quad([Vec3::ZERO; 4], None).is_none());
        let mut bad = leaf.corners();
        bad[2].x = f32::NAN;
        assert!(Leaf::from_quad(bad, None).is_none());
    }

    #[test]
    fn two_side_by_side_leaves_become_one_containing_both() {
        let a = square(Vec3::ZERO, Vec3::Z, Vec3::Y, 0.5);
        let b = square(Vec3::new(1.0, 0.0, 0.0), Vec3::Z, Vec3::Y, 0.5);
        let c = Leaf::collapse(&a, &b);
        assert!(c.center.abs_diff_eq(Vec3::new(0.5, 0.0, 0.0), 1e-6));
        assert!(c.normal.abs_diff_eq(Vec3::Z, 1e-6));
        // Main axis through the two centres.
        assert!(c.axis.abs_diff_eq(Vec3::X, 1e-6) || c.axis.abs_diff_eq(-Vec3::X, 1e-6));
        // They tile a 2 x 1 rectangle exactly: summed area = bounding area = 2.
        assert_approx_eq!(c.area(), 2.0, rel 1e-5);
        assert_eq!(c.count, 2);
        assert_approx_eq!(c.leaf_area, 2.0, rel 1e-5);
    }

    #[test]
    fn the_new_area_is_the_mean_of_summed_and_bounding_areas() {
        // Far apart: the bounding quad (3 x 1) is larger than the sum (2).
        let a = square(Vec3::ZERO, Vec3::Z, Vec3::Y, 0.5);
        let b = square(Vec3::new(2.0, 0.0, 0.0), Vec3::Z, Vec3::Y, 0.5);
        assert_approx_eq!(Leaf::collapse(&a, &b).area(), 0.5 * (2.0 + 3.0), rel 1e-5);
        // Overlapping exactly: bounding area 1, summed 2: the bounding area.
        let c = Leaf::collapse(&a, &a);
        assert_approx_eq!(c.area(), 1.0, rel 1e-5);
    }

    #[test]
    fn centre_and_normal_are_weighted_by_represented_leaves() {
        let mut a = square(Vec3::ZERO, Vec3::Z, Vec3::Y, 0.5);
        a.count = 3;
        let b = square(Vec3::new(4.0, 0.0, 0.0), Vec3::X, Vec3::Y, 0.5);
        let c = Leaf::collapse(&a, &b);
        // The weighted centre (1, 0, 0) lies on the new leaf's main axis.
        let off = c.center - Vec3::new(1.0, 0.0, 0.0);
        assert!((off - c.axis * off.dot(c.axis)).length() < 1e-5);
        let expected = (Vec3::Z * 3.0 + Vec3::X).normalize();
        assert!(c.normal.abs_diff_eq(expected, 1e-6));
        // A leaf facing the other way is the same double-sided leaf.
        let flipped = square(Vec3::new(0.1, 0.0, 0.0), -Vec3::Z, Vec3::Y, 0.5);
        let d = Leaf::collapse(&a, &flipped);
        assert!(d.normal.abs_diff_eq(Vec3::Z, 1e-6));
    }

    /// The construction as seed 003 §2.4.2 states it: all eight corners projected on the new
    /// plane, the bounding rectangle on the main axis found from them.
    fn collapse_by_corners(a: &Leaf, b: &Leaf) -> (Vec3, Vec3, f32, f32) {
        let c = Leaf::collapse(a, b);
        let (wa, wb) = (a.count as f32, b.count as f32);
        let weighted = (a.center * wa + b.center * wb) / (wa + wb);
        let side = c.side();
        let project = |p: Vec3| p - c.normal * (p - weighted).dot(c.normal);
        let (mut lo, mut hi) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
        for p in a.corners().into_iter().chain(b.corners()) {
            let d = project(p) - weighted;
            let q = glam::Vec2::new(d.dot(c.axis), d.dot(side));
            lo = lo.min(q);
            hi = hi.max(q);
        }
        let mid = (lo + hi) * 0.5;
        let bounding = (hi.x - lo.x) * (hi.y - lo.y);
        let target = (0.5 * (a.area() + b.area() + bounding)).min(bounding);
        let s = (target / bounding).sqrt();
        let center = weighted + c.axis * mid.x + side * mid.y;
        (
            center,
            c.axis,
            0.5 * (hi.x - lo.x) * s,
            0.5 * (hi.y - lo.y) * s,
        )
    }

    #[test]
    fn spanning_the_half_axes_is_projecting_the_corners() {
        let mut rng = rand_mt::Mt64::new(12);
        let mut u = move || (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32 - 0.5;
        let leaf = |u: &mut dyn FnMut() -> f32| {
            let normal = Vec3::new(u(), u(), u()).normalize_or(Vec3::Z);
            let axis = normal
                .cross(Vec3::new(u(), u(), u()))
                .normalize_or(normal.any_orthonormal_vector());
            let half_length = 0.1 + u().abs();
            let half_width = 0.1 + u().abs();
            let center = Vec3::new(u(), u(), u());
            Leaf {
                center,
                normal,
                axis,
                half_length,
                half_width,
                count: 1 + (u().abs() * 8.0) as u32,
                leaf_area: 4.0 * half_length * half_width,
                lo: center - Vec3::ONE,
                hi: center + Vec3::ONE,
            }
        };
        for _ in 0..2000 {
            let (a, b) = (leaf(&mut u), leaf(&mut u));
            let c = Leaf::collapse(&a, &b);
            let (center, axis, half_length, half_width) = collapse_by_corners(&a, &b);
            let scale = 1.0 + a.radius() + b.radius();
            assert!(
                c.center.abs_diff_eq(center, 1e-5 * scale),
                "{} {center}",
                c.center
            );
            assert!(c.axis.abs_diff_eq(axis, 1e-6));
            assert_approx_eq!(c.half_length, half_length, rel 1e-5);
            assert_approx_eq!(c.half_width, half_width, rel 1e-5);
        }
    }

    /// The new leaf's reach along each world axis, as the overhang bound measures it.
    fn reach(l: &Leaf) -> Vec3 {
        (l.axis * l.half_length).abs() + (l.side() * l.half_width).abs()
    }

    #[test]
    fn the_reach_test_never_refuses_a_leaf_within_its_bound() {
        let mut rng = rand_mt::Mt64::new(31);
        let mut u = move || (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32 - 0.5;
        let unit = |u: &mut dyn FnMut() -> f32| Vec3::new(u(), u(), u()).normalize_or(Vec3::Z);
        let (mut tested, mut refused) = (0, 0);
        for i in 0..20_000 {
            // Sizes from a millimetre to ten metres, far from the origin or near it.
            let scale = math::powf(10f32, 4.0 * (u() + 0.5) - 3.0);
            let offset = Vec3::new(u(), u(), u()) * if i % 2 == 0 { 2000.0 } else { 2.0 };
            let leaf = |u: &mut dyn FnMut() -> f32, normal: Vec3, center: Vec3| {
                let axis = normal
                    .cross(unit(u))
                    .normalize_or(normal.any_orthonormal_vector());
                let (half_length, half_width) =
                    (scale * (0.05 + u().abs()), scale * (0.05 + u().abs()));
                Leaf {
                    center,
                    normal,
                    axis,
                    half_length,
                    half_width,
                    count: 1 + (u().abs() * if i % 3 == 0 { 2000.0 } else { 6.0 }) as u32,
                    leaf_area: 4.0 * half_length * half_width,
                    lo: center - Vec3::splat(scale),
                    hi: center + Vec3::splat(scale),
                }
            };
            let na = unit(&mut u);
            // Nearly parallel normals, or any; centres apart in any direction, along the
            // normal (stacked leaves) or nearly together.
            let nb = match i % 4 {
                0 => (na + unit(&mut u) * 0.05).normalize(),
                1 => -(na + unit(&mut u) * 0.3).normalize(),
                _ => unit(&mut u),
            };
            let apart = match i % 5 {
                0 => na * u() * 2.0 + unit(&mut u) * 0.02 * u(),
                1 => unit(&mut u) * 1e-3 * u(),
                _ => unit(&mut u) * 2.0 * u(),
            };
            let a = leaf(&mut u, na, offset);
            let b = leaf(&mut u, nb, offset + apart * scale);
            let reach = reach(&Leaf::collapse(&a, &b));
            // Exactly the new leaf's reach is within the bound: never refused.
            assert!(!Leaf::surely_reaches(&a, &b, reach), "{a:?} {b:?}");
            assert!(
                !Leaf::surely_reaches(&b, &a, reach_of(&b, &a)),
                "{b:?} {a:?}"
            );
            // A little less along one axis: refused when the test is sure of it.
            let k = i % 3;
            let mut less = reach;
            less[k] *= 0.99;
            tested += 1;
            refused += usize::from(Leaf::surely_reaches(&a, &b, less));
        }
        // Sure for most pairs (the rest are ill-posed: stacked or coinciding centres).
        assert!(refused * 10 >= tested * 6, "{refused} of {tested}");
    }

    fn reach_of(a: &Leaf, b: &Leaf) -> Vec3 {
        reach(&Leaf::collapse(a, b))
    }
}
