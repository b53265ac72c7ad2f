//! Attraction points drawn from an envelope.

use glam::Vec3;
use pge_engine::random::uniform24;
use pge_engine::{Error, Location, RunContext};
use rand_mt::Mt64;

use crate::shape::{Shape, ellipsoid_contains};

/// How points are taken from the envelope.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    /// Uniformly inside the volume.
    Fill,
    /// Uniformly in the shell of this thickness just under the surface (a crown whose
    /// inside stays bare).
    Surround {
        /// Shell thickness (> 0).
        thickness: f32,
    },
    /// The vertices of the envelope's mesh(es).
    Vertices,
}

/// Points drawn when the script does not say how many.
pub const DEFAULT_POINTS: u32 = 2000;

/// Candidates tried without finding one inside before the envelope is declared empty.
const EMPTY_AFTER: u64 = 100_000;

/// Draws the attraction points: `count` of them (default [`DEFAULT_POINTS`]; in the
/// `vertices` mode every vertex unless `count` asks for fewer) by rejection sampling in the
/// envelope's bounds with an MT19937-64 seeded with `seed`. Errors, located at `location`:
/// an envelope with zero volume or in which no candidate falls, a `surround` on a shape
/// without a surface, a `vertices` mode without a mesh, a failing predicate.
pub fn generate(
    shape: &Shape,
    mode: Mode,
    count: Option<u32>,
    seed: u64,
    ctx: &RunContext,
    location: &Location,
) -> Result<Vec<Vec3>, Error> {
    let err = |m: String| Error::script(location.clone(), m);
    let mut rng = Mt64::new(seed);
    if mode == Mode::Vertices {
        let mut verts = shape.mesh_vertices();
        if verts.is_empty() {
            return Err(err(format!(
                "mode \"vertices\" needs a mesh envelope (pge.shape.mesh), got a {}",
                shape.kind()
            )));
        }
        if let Some(n) = count.map(|n| n as usize).filter(|n| *n < verts.len()) {
            // A partial Fisher-Yates shuffle picks n distinct vertices.
            for i in 0..n {
                let j = i + (rng.next_u64() % (verts.len() - i) as u64) as usize;
                verts.swap(i, j);
            }
            verts.truncate(n);
        }
        return Ok(verts);
    }
    if let Mode::Surround { .. } = mode
        && !shape.has_distance()
    {
        return Err(err(format!(
            "mode \"surround\" needs an envelope with a surface; a {} has none (use \"fill\")",
            shape.kind()
        )));
    }
    let (lo, hi) = shape.bounds();
    let size = hi - lo;
    if !(lo.is_finite() && hi.is_finite()) || size.min_element() <= 0.0 {
        return Err(err(format!(
            "the envelope ({}) has zero volume: its bounds run from ({}, {}, {}) to ({}, {}, {})",
            shape.kind(),
            lo.x,
            lo.y,
            lo.z,
            hi.x,
            hi.y,
            hi.z
        )));
    }
    let n = count.unwrap_or(DEFAULT_POINTS) as usize;
    let mut out = Vec::with_capacity(n);
    let max_attempts = 400 * n as u64 + EMPTY_AFTER;
    let mut attempts = 0u64;
    let mut draw = || {
        lo + size
            * Vec3::new(
                uniform24(&mut rng),
                uniform24(&mut rng),
                uniform24(&mut rng),
            )
    };
    // The usual crown (a filled ellipsoid): candidates drawn and tested a batch at a time,
    // so that their divisions and square roots overlap instead of waiting on each other,
    // then taken in order as one at a time takes them. The generator is this function's
    // own, so the draws after the last point taken change nothing.
    let ellipsoid = match (mode, shape) {
        (Mode::Fill, Shape::Ellipsoid { center, radii }) => Some((*center, *radii)),
        _ => None,
    };
    let mut batch = [(Vec3::ZERO, false); 8];
    let mut next = batch.len();
    while out.len() < n && attempts < max_attempts {
        attempts += 1;
        if attempts.is_multiple_of(8192) {
            ctx.check_deadline(location)?;
        }
        if out.is_empty() && attempts > EMPTY_AFTER {
            break;
        }
        let (p, keep) = if let Some((center, radii)) = ellipsoid {
            if next == batch.len() {
                for candidate in &mut batch {
                    candidate.0 = draw();
                }
                for (p, keep) in &mut batch {
                    // As `contains` tests it.
                    *keep = ellipsoid_contains(*p - center, radii);
                }
                next = 0;
            }
            next += 1;
            batch[next - 1]
        } else {
            let p = draw();
            let keep = match mode {
                Mode::Surround { thickness } => shape
                    .signed_distance(p)
                    .is_some_and(|d| d <= 0.0 && d >= -thickness),
                _ => shape.contains(p)?,
            };
            (p, keep)
        };
        if keep {
            out.push(p);
        }
    }
    if out.is_empty() {
        let what = match mode {
            Mode::Surround { thickness } => format!("in its shell of thickness {thickness}"),
            _ => "inside it".to_string(),
        };
        return Err(err(format!(
            "the envelope ({}) yields no attraction points: none of {attempts} random points in its bounds fell {what}",
            shape.kind()
        )));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::rc::Rc;

    fn loc() -> Location {
        Location::new("t.lua", 1)
    }

    #[test]
    fn fill_points_are_inside_and_repeat_per_seed() {
        let s = Shape::Sphere {
            center: Vec3::Y * 5.0,
            radius: 2.0,
        };
        let ctx = RunContext::default();
        let a = generate(&s, Mode::Fill, Some(500), 1, &ctx, &loc()).expect("points");
        assert_eq!(a.len(), 500);
        assert!(a.iter().all(|p| p.distance(Vec3::Y * 5.0) <= 2.0));
        assert_eq!(
            a,
            generate(&s, Mode::Fill, Some(500), 1, &ctx, &loc()).expect("points")
        );
        assert_ne!(
            a,
            generate(&s, Mode::Fill, Some(500), 2, &ctx, &loc()).expect("points")
        );
        let shell = generate(
            &s,
            Mode::Surround { thickness: 0.3 },
            Some(300),
            1,
            &ctx,
            &loc(),
        )
        .expect("points");
        assert!(
            shell
                .iter()
                .all(|p| (1.7..=2.0).contains(&p.distance(Vec3::Y * 5.0)))
        );
    }

    /// A filled ellipsoid, drawn a batch at a time, keeps the points a loop of one draw
    /// and one `contains` at a time keeps, in the same order, whatever the count.
    #[test]
    fn ellipsoid_fill_keeps_the_points_of_one_draw_at_a_time() {
        let shape = Shape::Ellipsoid {
            center: Vec3::new(0.5, 6.4, -1.0),
            radii: Vec3::new(5.5, 3.2, 4.95),
        };
        let ctx = RunContext::default();
        let (lo, hi) = shape.bounds();
        for (seed, n) in [(1, 1), (2, 7), (3, 8), (4, 9), (5, 500), (6, 3001)] {
            let mut rng = Mt64::new(seed);
            let mut want = Vec::new();
            while want.len() < n {
                let p = lo
                    + (hi - lo)
                        * Vec3::new(
                            uniform24(&mut rng),
                            uniform24(&mut rng),
                            uniform24(&mut rng),
                        );
                if shape.contains(p).expect("analytic") {
                    want.push(p);
                }
            }
            let got = generate(&shape, Mode::Fill, Some(n as u32), seed, &ctx, &loc());
            assert_eq!(got.expect("points"), want, "seed {seed}, {n} points");
        }
    }

    #[test]
    fn empty_envelopes_are_errors() {
        let ctx = RunContext::default();
        let flat = Shape::Box {
            min: Vec3::ZERO,
            max: Vec3::new(1.0, 0.0, 1.0),
        };
        let e = generate(&flat, Mode::Fill, None, 1, &ctx, &loc()).expect_err("flat");
        assert!(
            e.to_string()
                .starts_with("t.lua:1: the envelope (box) has zero volume"),
            "{e}"
        );
        let never = Shape::Predicate {
            test: Rc::new(|_| Ok(false)),
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        let e = generate(&never, Mode::Fill, None, 1, &ctx, &loc()).expect_err("never");
        assert!(e.to_string().contains("yields no attraction points"), "{e}");
        let e = generate(
            &never,
            Mode::Surround { thickness: 0.1 },
            None,
            1,
            &ctx,
            &loc(),
        )
        .expect_err("no sdf");
        assert!(
            e.to_string().contains("needs an envelope with a surface"),
            "{e}"
        );
        let e = generate(&flat, Mode::Vertices, None, 1, &ctx, &loc()).expect_err("no mesh");
        assert!(e.to_string().contains("needs a mesh envelope"), "{e}");
    }
}
