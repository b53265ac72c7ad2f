//! Attraction points drawn from an envelope, and the uniform grid that finds them again.

use glam::Vec3;
use pge_engine::random::uniform24;
use pge_engine::{Error, Location, RunContext};
use rand_mt::Mt64;

use crate::shape::Shape;

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
    while out.len() < n && attempts < max_attempts {
        attempts += 1;
        if attempts.is_multiple_of(8192) {
            ctx.check_deadline(location)?;
        }
        if out.is_empty() && attempts > EMPTY_AFTER {
            break;
        }
        let p = lo
            + size
                * Vec3::new(
                    uniform24(&mut rng),
                    uniform24(&mut rng),
                    uniform24(&mut rng),
                );
        let keep = match mode {
            Mode::Surround { thickness } => shape
                .signed_distance(p)
                .is_some_and(|d| d <= 0.0 && d >= -thickness),
            _ => shape.contains(p)?,
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

/// A uniform grid over the attraction points (compressed rows: one index list per cell),
/// for "which points lie within r of this node" queries.
#[derive(Clone, Debug)]
pub struct PointGrid {
    origin: Vec3,
    inv_cell: f32,
    cell: f32,
    dims: [usize; 3],
    starts: Vec<u32>,
    items: Vec<u32>,
    /// The position of each item, stored in cell order next to it for locality.
    positions: Vec<Vec3>,
}

/// Grids larger than this many cells get larger cells.
const MAX_CELLS: usize = 1 << 21;

impl PointGrid {
    /// A grid of cells about `cell` wide over the points whose `keep` is true.
    #[must_use]
    pub fn new(points: &[Vec3], keep: &[bool], cell: f32) -> PointGrid {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for (p, k) in points.iter().zip(keep) {
            if *k {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        if !lo.is_finite() {
            lo = Vec3::ZERO;
            hi = Vec3::ZERO;
        }
        let size = (hi - lo).max(Vec3::splat(1e-6));
        let mut cell = cell.max(size.max_element() / 1024.0).max(1e-6);
        let dims = loop {
            let d = (size / cell).ceil().max(Vec3::ONE);
            let dims = [d.x as usize, d.y as usize, d.z as usize];
            if dims[0] * dims[1] * dims[2] <= MAX_CELLS {
                break dims;
            }
            cell *= 1.5;
        };
        let mut grid = PointGrid {
            origin: lo,
            inv_cell: 1.0 / cell,
            cell,
            dims,
            starts: Vec::new(),
            items: Vec::new(),
            positions: Vec::new(),
        };
        let cells = dims[0] * dims[1] * dims[2];
        let mut counts = vec![0u32; cells + 1];
        let cell_of: Vec<usize> = points.iter().map(|p| grid.cell_index(*p)).collect();
        for (i, c) in cell_of.iter().enumerate() {
            if keep[i] {
                counts[*c + 1] += 1;
            }
        }
        for c in 0..cells {
            counts[c + 1] += counts[c];
        }
        let mut fill = counts.clone();
        grid.items = vec![0; counts[cells] as usize];
        grid.positions = vec![Vec3::ZERO; counts[cells] as usize];
        for (i, c) in cell_of.iter().enumerate() {
            if keep[i] {
                grid.items[fill[*c] as usize] = i as u32;
                grid.positions[fill[*c] as usize] = points[i];
                fill[*c] += 1;
            }
        }
        grid.starts = counts;
        grid
    }

    fn coord(&self, v: f32, axis: usize, o: f32) -> usize {
        (((v - o) * self.inv_cell).floor().max(0.0) as usize).min(self.dims[axis] - 1)
    }

    fn cell_index(&self, p: Vec3) -> usize {
        let x = self.coord(p.x, 0, self.origin.x);
        let y = self.coord(p.y, 1, self.origin.y);
        let z = self.coord(p.z, 2, self.origin.z);
        (x * self.dims[1] + y) * self.dims[2] + z
    }

    /// Calls `f(index, position, squared distance)` for every point within `r` of `q`.
    /// Only cells that the ball touches are read.
    pub fn for_each_near(&self, q: Vec3, r: f32, mut f: impl FnMut(u32, Vec3, f32)) {
        let lo = q - r;
        let hi = q + r;
        let top = self.origin
            + Vec3::new(
                self.dims[0] as f32,
                self.dims[1] as f32,
                self.dims[2] as f32,
            ) * self.cell;
        if hi.cmplt(self.origin).any() || lo.cmpgt(top).any() {
            return;
        }
        let r2 = r * r;
        let (x0, x1) = (
            self.coord(lo.x, 0, self.origin.x),
            self.coord(hi.x, 0, self.origin.x),
        );
        let (y0, y1) = (
            self.coord(lo.y, 1, self.origin.y),
            self.coord(hi.y, 1, self.origin.y),
        );
        let (z0, z1) = (
            self.coord(lo.z, 2, self.origin.z),
            self.coord(hi.z, 2, self.origin.z),
        );
        // Squared distance from q to the slab of cell k along one axis.
        let gap = |k: usize, q: f32, o: f32| {
            let a = o + k as f32 * self.cell;
            let d = (a - q).max(q - (a + self.cell)).max(0.0);
            d * d
        };
        for x in x0..=x1 {
            let dx = gap(x, q.x, self.origin.x);
            for y in y0..=y1 {
                let dxy = dx + gap(y, q.y, self.origin.y);
                if dxy > r2 {
                    continue;
                }
                let row = (x * self.dims[1] + y) * self.dims[2];
                // The run of z cells the ball touches in this column.
                let mut z = z0;
                while z <= z1 && dxy + gap(z, q.z, self.origin.z) > r2 {
                    z += 1;
                }
                let mut z_end = z1;
                while z_end > z && dxy + gap(z_end, q.z, self.origin.z) > r2 {
                    z_end -= 1;
                }
                if z > z_end {
                    continue;
                }
                let (s, e) = (
                    self.starts[row + z] as usize,
                    self.starts[row + z_end + 1] as usize,
                );
                for (i, p) in self.items[s..e].iter().zip(&self.positions[s..e]) {
                    let d2 = p.distance_squared(q);
                    if d2 < r2 {
                        f(*i, *p, d2);
                    }
                }
            }
        }
    }
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

    #[test]
    fn grid_queries_cover_the_neighbourhood() {
        let pts: Vec<Vec3> = (0..1000)
            .map(|i| Vec3::new((i % 10) as f32, ((i / 10) % 10) as f32, (i / 100) as f32))
            .collect();
        let keep = vec![true; pts.len()];
        let g = PointGrid::new(&pts, &keep, 1.5);
        let q = Vec3::new(4.2, 5.1, 3.3);
        let mut found = Vec::new();
        g.for_each_near(q, 2.0, |i, p, d2| {
            assert_eq!(p, pts[i as usize]);
            assert_eq!(d2, p.distance_squared(q));
            found.push(i);
        });
        found.sort_unstable();
        let want: Vec<u32> = (0..pts.len() as u32)
            .filter(|i| pts[*i as usize].distance(q) < 2.0)
            .collect();
        assert_eq!(found, want);
        let mut none = 0;
        g.for_each_near(Vec3::splat(100.0), 2.0, |_, _, _| none += 1);
        assert_eq!(none, 0);
    }
}
