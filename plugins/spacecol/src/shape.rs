//! Envelopes: the volumes attraction points are drawn from.
//!
//! Every shape answers "is this point inside?" and gives its bounding box; the analytic ones
//! and meshes also give a signed distance to their surface (negative inside), used by the
//! `surround` mode to keep a shell under the surface.

use std::fmt;
use std::rc::Rc;

use glam::{Vec2, Vec3, Vec3A};

use crate::trimesh::TriMesh;

/// How deeply unions and differences may nest: every query walks the shape recursively.
pub const MAX_NESTING: usize = 64;

/// How many parts a combined shape may hold, counting a shared part once per use: every
/// query may visit them all.
pub const MAX_PARTS: usize = 100_000;

/// A Rust predicate: inside or not, or an error (a Lua predicate that failed).
pub type PredicateFn = dyn Fn(Vec3) -> Result<bool, pge_engine::Error>;

/// A volume. Cheap to clone (meshes and predicates are shared).
#[derive(Clone)]
pub enum Shape {
    /// A ball.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius (> 0).
        radius: f32,
    },
    /// An axis-aligned ellipsoid.
    Ellipsoid {
        /// Centre.
        center: Vec3,
        /// Semi-axes along x, y and z (each > 0).
        radii: Vec3,
    },
    /// An axis-aligned box.
    Box {
        /// Lowest corner.
        min: Vec3,
        /// Highest corner.
        max: Vec3,
    },
    /// All points within `radius` of the segment `a`-`b`.
    Capsule {
        /// One end of the axis.
        a: Vec3,
        /// The other end.
        b: Vec3,
        /// Radius (> 0).
        radius: f32,
    },
    /// A solid cone with a disc of `radius` at `base` and its point at `apex`.
    Cone {
        /// Centre of the base disc.
        base: Vec3,
        /// The tip.
        apex: Vec3,
        /// Radius of the base (> 0).
        radius: f32,
    },
    /// A solid cylinder between the centres of its two discs.
    Cylinder {
        /// Centre of one disc.
        a: Vec3,
        /// Centre of the other.
        b: Vec3,
        /// Radius (> 0).
        radius: f32,
    },
    /// A closed 2D profile of `(r, y)` points (r >= 0) revolved around the vertical axis
    /// through `center` (seed 002's envelope).
    Revolve {
        /// The profile polygon, closed implicitly from the last point to the first.
        profile: Rc<[Vec2]>,
        /// Where the axis stands (the profile's `y = 0` is at `center.y`).
        center: Vec3,
    },
    /// The inside of a closed triangle mesh (ray parity).
    Mesh(Rc<TriMesh>),
    /// Inside any of the shapes.
    Union(Rc<[Shape]>),
    /// Inside `a` and not inside `b`.
    Difference(Rc<Shape>, Rc<Shape>),
    /// Inside where a function says so, within the given bounds.
    Predicate {
        /// The test.
        test: Rc<PredicateFn>,
        /// Bounds sampled for points.
        min: Vec3,
        /// Upper bounds.
        max: Vec3,
    },
}

impl fmt::Debug for Shape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Shape::{}", self.kind())
    }
}

/// Why a combined shape is refused ([`Shape::check_size`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ShapeSizeError {
    /// Unions and differences nest deeper than [`MAX_NESTING`].
    #[error("unions and differences nest deeper than the limit of {MAX_NESTING} levels")]
    TooDeep,
    /// The shape visits more than [`MAX_PARTS`] parts.
    #[error(
        "the shape holds more than the limit of {MAX_PARTS} parts (a shared part counts once per use)"
    )]
    TooManyParts,
}

impl Shape {
    /// The shape's kind as the Lua constructor names it (`sphere`, `mesh`, ...).
    #[must_use]
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Sphere { .. } => "sphere",
            Shape::Ellipsoid { .. } => "ellipsoid",
            Shape::Box { .. } => "box",
            Shape::Capsule { .. } => "capsule",
            Shape::Cone { .. } => "cone",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Revolve { .. } => "revolve",
            Shape::Mesh(_) => "mesh",
            Shape::Union(_) => "union",
            Shape::Difference(..) => "difference",
            Shape::Predicate { .. } => "predicate",
        }
    }

    /// Checks a combined shape against `MAX_NESTING` and `MAX_PARTS`, visiting at most
    /// that many parts; the error names the limit. The Lua constructors check every union
    /// and difference they build, so the queries' recursion stays bounded.
    pub fn check_size(&self) -> Result<(), ShapeSizeError> {
        let mut budget = MAX_PARTS;
        self.visit_parts(0, &mut budget)
    }

    fn visit_parts(&self, depth: usize, budget: &mut usize) -> Result<(), ShapeSizeError> {
        if depth > MAX_NESTING {
            return Err(ShapeSizeError::TooDeep);
        }
        if *budget == 0 {
            return Err(ShapeSizeError::TooManyParts);
        }
        *budget -= 1;
        match self {
            Shape::Union(parts) => {
                for part in parts.iter() {
                    part.visit_parts(depth + 1, budget)?;
                }
            }
            Shape::Difference(a, b) => {
                a.visit_parts(depth + 1, budget)?;
                b.visit_parts(depth + 1, budget)?;
            }
            _ => {}
        }
        Ok(())
    }

    /// Whether `p` is inside.
    pub fn contains(&self, p: Vec3) -> Result<bool, pge_engine::Error> {
        Ok(match self {
            Shape::Union(parts) => {
                for s in parts.iter() {
                    if s.contains(p)? {
                        return Ok(true);
                    }
                }
                false
            }
            Shape::Difference(a, b) => a.contains(p)? && !b.contains(p)?,
            Shape::Predicate { test, min, max } => {
                p.cmpge(*min).all() && p.cmple(*max).all() && test(p)?
            }
            Shape::Mesh(m) => m.contains(p),
            Shape::Ellipsoid { center, radii } => ellipsoid_contains(p - *center, *radii),
            _ => self.signed_distance(p).is_some_and(|d| d <= 0.0),
        })
    }

    /// Signed distance to the surface, negative inside; `None` for shapes without one (a
    /// predicate, or a combination holding one). Exact for spheres, boxes, capsules,
    /// cylinders, cones, revolved profiles and meshes; a close bound for ellipsoids; unions
    /// and differences combine by min/max (exact outside, a bound inside).
    #[must_use]
    pub fn signed_distance(&self, p: Vec3) -> Option<f32> {
        Some(match self {
            Shape::Sphere { center, radius } => p.distance(*center) - radius,
            Shape::Ellipsoid { center, radii } => {
                let q = p - *center;
                ellipsoid_distance(q, ellipsoid_k0(q, *radii), *radii)
            }
            Shape::Box { min, max } => {
                let c = (*min + *max) * 0.5;
                let h = (*max - *min) * 0.5;
                let q = (p - c).abs() - h;
                q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
            }
            Shape::Capsule { a, b, radius } => segment_distance(p, *a, *b) - radius,
            Shape::Cylinder { a, b, radius } => {
                let (q, y, h) = axial(p, *a, *b);
                polygon_distance(
                    Vec2::new(q, y),
                    &[
                        Vec2::new(0.0, 0.0),
                        Vec2::new(*radius, 0.0),
                        Vec2::new(*radius, h),
                        Vec2::new(0.0, h),
                    ],
                )
            }
            Shape::Cone { base, apex, radius } => {
                let (q, y, h) = axial(p, *base, *apex);
                polygon_distance(
                    Vec2::new(q, y),
                    &[Vec2::ZERO, Vec2::new(*radius, 0.0), Vec2::new(0.0, h)],
                )
            }
            Shape::Revolve { profile, center } => {
                let d = p - *center;
                polygon_distance(Vec2::new(Vec2::new(d.x, d.z).length(), d.y), profile)
            }
            Shape::Mesh(m) => m.signed_distance(p),
            Shape::Union(parts) => {
                let mut best = f32::INFINITY;
                for s in parts.iter() {
                    best = best.min(s.signed_distance(p)?);
                }
                best
            }
            Shape::Difference(a, b) => a.signed_distance(p)?.max(-b.signed_distance(p)?),
            Shape::Predicate { .. } => return None,
        })
    }

    /// Whether [`signed_distance`](Shape::signed_distance) is available.
    #[must_use]
    pub fn has_distance(&self) -> bool {
        match self {
            Shape::Predicate { .. } => false,
            Shape::Union(parts) => parts.iter().all(Shape::has_distance),
            Shape::Difference(a, b) => a.has_distance() && b.has_distance(),
            _ => true,
        }
    }

    /// The axis-aligned bounds `(min, max)` of the inside.
    #[must_use]
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            Shape::Sphere { center, radius } => (*center - *radius, *center + *radius),
            Shape::Ellipsoid { center, radii } => (*center - *radii, *center + *radii),
            Shape::Box { min, max } => (*min, *max),
            Shape::Capsule { a, b, radius } | Shape::Cylinder { a, b, radius } => {
                (a.min(*b) - *radius, a.max(*b) + *radius)
            }
            Shape::Cone { base, apex, radius } => {
                (base.min(*apex) - *radius, base.max(*apex) + *radius)
            }
            Shape::Revolve { profile, center } => {
                let r = profile.iter().map(|p| p.x.abs()).fold(0.0, f32::max);
                let lo = profile.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
                let hi = profile
                    .iter()
                    .map(|p| p.y)
                    .fold(f32::NEG_INFINITY, f32::max);
                (
                    *center + Vec3::new(-r, lo, -r),
                    *center + Vec3::new(r, hi, r),
                )
            }
            Shape::Mesh(m) => m.bounds(),
            Shape::Union(parts) => {
                let mut it = parts.iter().map(Shape::bounds);
                let first = it.next().unwrap_or((Vec3::ZERO, Vec3::ZERO));
                it.fold(first, |(lo, hi), (a, b)| (lo.min(a), hi.max(b)))
            }
            Shape::Difference(a, _) => a.bounds(),
            Shape::Predicate { min, max, .. } => (*min, *max),
        }
    }

    /// The first mesh in the shape that is not closed, with why (the inside test of the
    /// `fill` and `surround` modes needs closed meshes).
    #[must_use]
    pub fn open_mesh(&self) -> Option<String> {
        match self {
            Shape::Mesh(m) => m.closed().err().map(|e| format!("mesh '{}' {e}", m.name)),
            Shape::Union(parts) => parts.iter().find_map(Shape::open_mesh),
            Shape::Difference(a, b) => a.open_mesh().or_else(|| b.open_mesh()),
            _ => None,
        }
    }

    /// The vertices of every mesh in the shape (for the `vertices` mode), in order.
    #[must_use]
    pub fn mesh_vertices(&self) -> Vec<Vec3> {
        match self {
            Shape::Mesh(m) => m.vertices().to_vec(),
            Shape::Union(parts) => parts.iter().flat_map(Shape::mesh_vertices).collect(),
            Shape::Difference(a, _) => a.mesh_vertices(),
            _ => Vec::new(),
        }
    }
}

/// `k0 = |q / radii|` of an ellipsoid of semi-axes `radii` at `q` from its centre: the
/// three quotients in one SIMD division (`Vec3A`), each rounded as alone, and the length
/// summed as `Vec3::length` sums it (x, y, then z): the same bits.
#[inline]
fn ellipsoid_k0(q: Vec3, radii: Vec3) -> f32 {
    (Vec3A::from(q) / Vec3A::from(radii)).length()
}

/// The signed distance bound `k0 (k0 - 1) / k1` of an ellipsoid of semi-axes `radii` at
/// `q` from its centre, where `k0 = |q / radii|` and `k1 = |q / radii²|` (as `k0`, in one
/// division).
fn ellipsoid_distance(q: Vec3, k0: f32, radii: Vec3) -> f32 {
    let k1 = ellipsoid_k0(q, radii * radii);
    if k1 == 0.0 {
        -radii.min_element()
    } else {
        k0 * (k0 - 1.0) / k1
    }
}

/// Whether `q` (from the centre) is inside an ellipsoid of semi-axes `radii`, as
/// [`Shape::contains`] decides it: its signed distance is at most 0, which it is whenever
/// `k0 <= 1` (`k1 > 0`, or the centre), so most points decide without `k1` and the division.
#[inline]
pub(crate) fn ellipsoid_contains(q: Vec3, radii: Vec3) -> bool {
    let k0 = ellipsoid_k0(q, radii);
    k0 <= 1.0 || ellipsoid_distance(q, k0, radii) <= 0.0
}

/// Distance from `p` to the segment `a`-`b`.
fn segment_distance(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

/// `p` in the frame of the axis `a` -> `b`: (distance from the axis, height along it from
/// `a`, axis length).
fn axial(p: Vec3, a: Vec3, b: Vec3) -> (f32, f32, f32) {
    let axis = b - a;
    let h = axis.length();
    let dir = if h > 0.0 { axis / h } else { Vec3::Y };
    let d = p - a;
    let y = d.dot(dir);
    ((d - dir * y).length(), y, h)
}

/// Signed distance from `p` to a closed polygon (negative inside, by crossing parity).
pub(crate) fn polygon_distance(p: Vec2, poly: &[Vec2]) -> f32 {
    let n = poly.len();
    if n < 3 {
        return f32::INFINITY;
    }
    let mut d2 = f32::INFINITY;
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let e = b - a;
        let w = p - a;
        let len2 = e.length_squared();
        let t = if len2 > 0.0 {
            (w.dot(e) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        d2 = d2.min((w - e * t).length_squared());
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * e.x / e.y {
            inside = !inside;
        }
    }
    if inside { -d2.sqrt() } else { d2.sqrt() }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The SIMD `k0` is `(q / radii).length()` to the bit, for points inside and outside,
    /// below zero, and radii from tiny to huge.
    #[test]
    fn ellipsoid_k0_is_the_scalar_quotients_length() {
        let mut rng = rand_mt::Mt64::new(17);
        let mut draw = |scale: f32| {
            (Vec3::new(
                pge_engine::random::uniform24(&mut rng),
                pge_engine::random::uniform24(&mut rng),
                pge_engine::random::uniform24(&mut rng),
            ) - 0.5)
                * scale
        };
        for k in 0..20_000 {
            let scale = [1e-3, 0.7, 5.0, 3e4][k % 4];
            let radii = draw(scale).abs() + scale * 1e-3;
            let q = draw(scale * 3.0);
            for r in [radii, radii * radii] {
                assert_eq!(
                    ellipsoid_k0(q, r).to_bits(),
                    (q / r).length().to_bits(),
                    "q {q}, radii {r}"
                );
            }
        }
    }

    /// An ellipsoid's inside test (which decides most points without the full distance)
    /// agrees with the sign of its signed distance, on points near its surface too.
    #[test]
    fn ellipsoid_inside_is_the_sign_of_its_distance() {
        let ell = Shape::Ellipsoid {
            center: Vec3::new(0.5, 6.4, -1.0),
            radii: Vec3::new(5.5, 3.2, 4.95),
        };
        let mut rng = rand_mt::Mt64::new(7);
        let mut both = [0; 2];
        for _ in 0..20_000 {
            let u = Vec3::new(
                pge_engine::random::uniform24(&mut rng),
                pge_engine::random::uniform24(&mut rng),
                pge_engine::random::uniform24(&mut rng),
            ) * 2.0
                - 1.0;
            // Directions scaled to lie around the surface, within a few per cent of it.
            let scale = 0.97 + 0.06 * pge_engine::random::uniform24(&mut rng);
            let p = Vec3::new(0.5, 6.4, -1.0)
                + u.normalize_or_zero() * scale * Vec3::new(5.5, 3.2, 4.95);
            let inside = ell.contains(p).expect("no predicate");
            let d = ell.signed_distance(p).expect("a distance");
            assert_eq!(inside, d <= 0.0, "{p}: distance {d}");
            both[usize::from(inside)] += 1;
        }
        assert!(both[0] > 1000 && both[1] > 1000, "{both:?}");
    }

    fn inside(s: &Shape, p: Vec3) -> bool {
        s.contains(p).expect("no predicate error")
    }

    #[test]
    fn combinations_past_the_limits_are_refused() {
        let sphere = Shape::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let mut nested = sphere.clone();
        for _ in 0..MAX_NESTING {
            nested = Shape::Union(vec![nested].into());
        }
        assert_eq!(nested.check_size(), Ok(()));
        let deeper = Shape::Union(vec![nested].into());
        let e = deeper.check_size().expect_err("too deep").to_string();
        assert!(e.contains("the limit of 64 levels"), "{e}");
        // A shared part counts once per use: 2^20 visits.
        let mut shared = sphere;
        for _ in 0..20 {
            shared = Shape::Union(vec![shared.clone(), shared].into());
        }
        let e = shared.check_size().expect_err("too many parts").to_string();
        assert!(e.contains("the limit of 100000 parts"), "{e}");
    }

    #[test]
    fn analytic_shapes_contain_what_they_should() {
        let sphere = Shape::Sphere {
            center: Vec3::Y,
            radius: 1.0,
        };
        assert!(inside(&sphere, Vec3::new(0.0, 1.9, 0.0)));
        assert!(!inside(&sphere, Vec3::new(0.0, 2.1, 0.0)));
        assert!(
            (sphere
                .signed_distance(Vec3::new(3.0, 1.0, 0.0))
                .expect("sdf")
                - 2.0)
                .abs()
                < 1e-6
        );
        let ell = Shape::Ellipsoid {
            center: Vec3::ZERO,
            radii: Vec3::new(2.0, 1.0, 1.0),
        };
        assert!(inside(&ell, Vec3::new(1.9, 0.0, 0.0)));
        assert!(!inside(&ell, Vec3::new(0.0, 1.1, 0.0)));
        let bx = Shape::Box {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        assert!(inside(&bx, Vec3::splat(0.5)));
        assert!(!inside(&bx, Vec3::new(0.5, 1.5, 0.5)));
        assert_eq!(bx.signed_distance(Vec3::splat(0.5)), Some(-0.5));
        let cap = Shape::Capsule {
            a: Vec3::ZERO,
            b: Vec3::Y * 2.0,
            radius: 0.5,
        };
        assert!(inside(&cap, Vec3::new(0.0, 2.4, 0.0)));
        assert!(!inside(&cap, Vec3::new(0.6, 1.0, 0.0)));
        let cyl = Shape::Cylinder {
            a: Vec3::ZERO,
            b: Vec3::Y * 2.0,
            radius: 0.5,
        };
        assert!(inside(&cyl, Vec3::new(0.45, 1.9, 0.0)));
        assert!(!inside(&cyl, Vec3::new(0.0, 2.1, 0.0)));
        assert!((cyl.signed_distance(Vec3::new(0.0, 1.0, 2.0)).expect("sdf") - 1.5).abs() < 1e-6);
        let cone = Shape::Cone {
            base: Vec3::ZERO,
            apex: Vec3::Y * 2.0,
            radius: 1.0,
        };
        assert!(inside(&cone, Vec3::new(0.9, 0.1, 0.0)));
        assert!(inside(&cone, Vec3::new(0.0, 1.9, 0.0)));
        assert!(!inside(&cone, Vec3::new(0.6, 1.0, 0.0)));
        assert!(!inside(&cone, Vec3::new(0.0, -0.1, 0.0)));
    }

    #[test]
    fn revolved_profiles_and_combinations() {
        // A vase: wide at y = 1, narrow at the bottom and the top.
        let profile: Rc<[Vec2]> = vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(0.5, 0.0),
            Vec2::new(1.5, 1.0),
            Vec2::new(0.2, 2.0),
            Vec2::new(0.0, 2.0),
        ]
        .into();
        let vase = Shape::Revolve {
            profile,
            center: Vec3::new(10.0, 0.0, 0.0),
        };
        assert!(inside(&vase, Vec3::new(11.3, 1.0, 0.0)));
        assert!(inside(&vase, Vec3::new(10.0, 1.0, 1.3)));
        assert!(!inside(&vase, Vec3::new(11.3, 0.2, 0.0)));
        let (lo, hi) = vase.bounds();
        assert_eq!(
            (lo, hi),
            (Vec3::new(8.5, 0.0, -1.5), Vec3::new(11.5, 2.0, 1.5))
        );

        let a = Shape::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let b = Shape::Sphere {
            center: Vec3::X,
            radius: 1.0,
        };
        let u = Shape::Union(vec![a.clone(), b.clone()].into());
        assert!(inside(&u, Vec3::new(1.8, 0.0, 0.0)));
        assert_eq!(
            u.bounds(),
            (Vec3::new(-1.0, -1.0, -1.0), Vec3::new(2.0, 1.0, 1.0))
        );
        let d = Shape::Difference(Rc::new(a), Rc::new(b));
        assert!(inside(&d, Vec3::new(-0.5, 0.0, 0.0)));
        assert!(!inside(&d, Vec3::new(0.5, 0.0, 0.0)));
        assert!(d.signed_distance(Vec3::new(0.5, 0.0, 0.0)).expect("sdf") > 0.0);
    }

    #[test]
    fn predicates_are_bounded_and_have_no_distance() {
        let p = Shape::Predicate {
            test: Rc::new(|p: Vec3| Ok(p.x > 0.0)),
            min: Vec3::splat(-1.0),
            max: Vec3::ONE,
        };
        assert!(inside(&p, Vec3::new(0.5, 0.0, 0.0)));
        assert!(!inside(&p, Vec3::new(1.5, 0.0, 0.0)), "outside the bounds");
        assert!(!p.has_distance());
        assert_eq!(p.signed_distance(Vec3::ZERO), None);
    }

    #[test]
    fn polygon_distance_sign_and_size() {
        let square = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        assert!((polygon_distance(Vec2::splat(0.5), &square) + 0.5).abs() < 1e-6);
        assert!((polygon_distance(Vec2::new(2.0, 0.5), &square) - 1.0).abs() < 1e-6);
    }
}
