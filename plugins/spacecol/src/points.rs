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
///
/// Each cell is split again into `split³` sub-cells (more when the points are dense), and
/// every point carries a *reach*: the squared distance under which a new node changes
/// something for it (for colonization, its distance to its nearest node). Cells and
/// sub-cells remember the largest reach of their points, so [`PointGrid::update_near`]
/// skips those that no point of which can be affected, without reading their points.
#[derive(Clone, Debug)]
pub struct PointGrid {
    origin: Vec3,
    inv_cell: f32,
    cell: f32,
    dims: [usize; 3],
    /// Sub-cells per cell side.
    split: usize,
    /// Where the items of each sub-cell start; a cell's sub-cells are consecutive (x, y, z
    /// order), so cell `c` holds items `starts[c s³] .. starts[(c + 1) s³]`.
    starts: Vec<u32>,
    items: Vec<u32>,
    /// The position of each item, stored in cell order next to it for locality.
    positions: Vec<Vec3>,
    /// Each item's reach (squared).
    reach: Vec<f32>,
    /// The largest reach in each sub-cell (an upper bound).
    sub_bound: Vec<f32>,
    /// The largest reach in each cell (an upper bound).
    cell_bound: Vec<f32>,
    /// How far a point may lie outside its cell's nominal box through rounding: skipping
    /// tests shrink distances by this much, so that they never skip an affected point.
    slack: f32,
    /// Scratch of `update_near`: (item, slot, sub-cell, squared distance).
    pending: Vec<(u32, u32, u32, f32)>,
    /// Scratch of `update_near`: the cells to read.
    visit: Vec<([usize; 3], usize)>,
}

/// Grids larger than this many cells get larger cells.
const MAX_CELLS: usize = 1 << 21;

/// Sub-cells are made only while the grid has at most this many of them.
const MAX_SUB_CELLS: usize = 1 << 22;

/// The number of points a sub-cell should hold on average.
const POINTS_PER_SUB_CELL: f32 = 8.0;

impl PointGrid {
    /// A grid of cells about `cell` wide over the points whose `keep` is true; every kept
    /// point's reach is infinite.
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
        let cells = dims[0] * dims[1] * dims[2];
        let kept = keep.iter().filter(|k| **k).count();
        let per_cell = kept as f32 / cells as f32;
        let mut split = ((per_cell / POINTS_PER_SUB_CELL).cbrt().round() as usize).clamp(1, 8);
        while split > 1 && cells * split.pow(3) > MAX_SUB_CELLS {
            split -= 1;
        }
        let top = lo + Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) * cell;
        let slack = 1e-3 * cell + 1e-5 * lo.abs().max(top.abs()).max_element();
        let mut grid = PointGrid {
            origin: lo,
            inv_cell: 1.0 / cell,
            cell,
            dims,
            split,
            starts: Vec::new(),
            items: Vec::new(),
            positions: Vec::new(),
            reach: Vec::new(),
            sub_bound: Vec::new(),
            cell_bound: Vec::new(),
            slack,
            pending: Vec::new(),
            visit: Vec::new(),
        };
        let subs = cells * split.pow(3);
        let mut counts = vec![0u32; subs + 1];
        let sub_of: Vec<usize> = points
            .iter()
            .zip(keep)
            .map(|(p, k)| if *k { grid.sub_index(*p) } else { 0 })
            .collect();
        for (i, c) in sub_of.iter().enumerate() {
            if keep[i] {
                counts[*c + 1] += 1;
            }
        }
        for c in 0..subs {
            counts[c + 1] += counts[c];
        }
        let mut fill = counts.clone();
        let total = counts[subs] as usize;
        grid.items = vec![0; total];
        grid.positions = vec![Vec3::ZERO; total];
        for (i, c) in sub_of.iter().enumerate() {
            if keep[i] {
                grid.items[fill[*c] as usize] = i as u32;
                grid.positions[fill[*c] as usize] = points[i];
                fill[*c] += 1;
            }
        }
        grid.starts = counts;
        grid.reach = vec![f32::INFINITY; total];
        grid.sub_bound = vec![0.0; subs];
        grid.cell_bound = vec![0.0; cells];
        grid.refresh_bounds();
        grid
    }

    /// Sets every point's reach to `reach(index)`.
    pub fn set_reaches(&mut self, reach: impl Fn(u32) -> f32) {
        for (r, i) in self.reach.iter_mut().zip(&self.items) {
            *r = reach(*i);
        }
        self.refresh_bounds();
    }

    fn refresh_bounds(&mut self) {
        let s3 = self.split.pow(3);
        for (s, bound) in self.sub_bound.iter_mut().enumerate() {
            let (a, b) = (self.starts[s] as usize, self.starts[s + 1] as usize);
            *bound = self.reach[a..b].iter().fold(0.0, |m, r| m.max(*r));
        }
        for (c, bound) in self.cell_bound.iter_mut().enumerate() {
            *bound = self.sub_bound[c * s3..(c + 1) * s3]
                .iter()
                .fold(0.0, |m, r| m.max(*r));
        }
    }

    fn coord(&self, v: f32, axis: usize, o: f32) -> usize {
        (((v - o) * self.inv_cell).floor().max(0.0) as usize).min(self.dims[axis] - 1)
    }

    /// The sub-cell of `p` (cell-major), consistent with the cell [`Self::coord`] gives.
    fn sub_index(&self, p: Vec3) -> usize {
        let s = self.split;
        let (o, fine) = (self.origin, self.inv_cell * s as f32);
        let axis = |v: f32, a: usize, o: f32| {
            let k = self.coord(v, a, o);
            let f = ((v - o) * fine).floor().max(0.0) as usize;
            (k, f.clamp(k * s, k * s + s - 1) - k * s)
        };
        let (x, sx) = axis(p.x, 0, o.x);
        let (y, sy) = axis(p.y, 1, o.y);
        let (z, sz) = axis(p.z, 2, o.z);
        let cell = (x * self.dims[1] + y) * self.dims[2] + z;
        cell * s * s * s + (sx * s + sy) * s + sz
    }

    /// The cells whose boxes the ball of radius `r` around `q` touches, as runs of z cells:
    /// `f(self, x, y, z0, z1)` for each (x, y) column, in increasing cell order.
    fn runs(&self, q: Vec3, r: f32, mut f: impl FnMut(&Self, usize, usize, usize, usize)) {
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
                f(self, x, y, z, z_end);
            }
        }
    }

    /// Calls `f(index, position, squared distance)` for every point within `r` of `q`, in
    /// no particular order. Only cells that the ball touches are read.
    pub fn for_each_near(&self, q: Vec3, r: f32, mut f: impl FnMut(u32, Vec3, f32)) {
        let r2 = r * r;
        let s3 = self.split.pow(3);
        self.runs(q, r, |g, x, y, z, z_end| {
            let row = (x * g.dims[1] + y) * g.dims[2];
            let (s, e) = (
                g.starts[(row + z) * s3] as usize,
                g.starts[(row + z_end + 1) * s3] as usize,
            );
            for (i, p) in g.items[s..e].iter().zip(&g.positions[s..e]) {
                let d2 = p.distance_squared(q);
                if d2 < r2 {
                    f(*i, *p, d2);
                }
            }
        });
    }

    /// Squared distance from `q` to the slab `[a, a + w]` along one axis, shrunk by the
    /// rounding slack (a lower bound of any stored point's distance along that axis).
    fn near_gap(&self, a: f32, w: f32, q: f32) -> f32 {
        let d = ((a - q).max(q - (a + w)).max(0.0) - self.slack).max(0.0);
        d * d
    }

    /// Calls `f(index, squared distance)` for every point within `r` of `q` that lies closer
    /// to `q` than its reach; `f` returns the point's new reach. The calls come cell by cell
    /// in increasing cell order and by increasing index within a cell. Cells and sub-cells
    /// whose largest reach is below their distance to `q` are skipped unread.
    pub fn update_near(&mut self, q: Vec3, r: f32, mut f: impl FnMut(u32, f32) -> f32) {
        let r2 = r * r;
        let mut pending = std::mem::take(&mut self.pending);
        let mut cells = std::mem::take(&mut self.visit);
        cells.clear();
        self.runs(q, r, |g, x, y, z, z_end| {
            let cx = g.near_gap(g.origin.x + x as f32 * g.cell, g.cell, q.x);
            let cy = g.near_gap(g.origin.y + y as f32 * g.cell, g.cell, q.y);
            for zz in z..=z_end {
                let c = (x * g.dims[1] + y) * g.dims[2] + zz;
                let cz = g.near_gap(g.origin.z + zz as f32 * g.cell, g.cell, q.z);
                if cx + cy + cz < g.cell_bound[c] {
                    cells.push(([x, y, zz], c));
                }
            }
        });
        for &(at, c) in &cells {
            self.update_cell(q, r2, at, c, &mut pending, &mut f);
        }
        self.pending = pending;
        self.visit = cells;
    }

    /// [`Self::update_near`] within cell `c` at `[x, y, z]`.
    fn update_cell(
        &mut self,
        q: Vec3,
        r2: f32,
        [x, y, z]: [usize; 3],
        c: usize,
        pending: &mut Vec<(u32, u32, u32, f32)>,
        f: &mut impl FnMut(u32, f32) -> f32,
    ) {
        let s = self.split;
        let w = self.cell / s as f32;
        let corner = self.origin + Vec3::new(x as f32, y as f32, z as f32) * self.cell;
        let first = c * s * s * s;
        pending.clear();
        for sx in 0..s {
            let gx = self.near_gap(corner.x + sx as f32 * w, w, q.x);
            for sy in 0..s {
                let gxy = gx + self.near_gap(corner.y + sy as f32 * w, w, q.y);
                for sz in 0..s {
                    let sub = first + (sx * s + sy) * s + sz;
                    let bound = self.sub_bound[sub];
                    if gxy + self.near_gap(corner.z + sz as f32 * w, w, q.z) >= bound {
                        continue;
                    }
                    let (a, b) = (self.starts[sub] as usize, self.starts[sub + 1] as usize);
                    let mut kept = 0.0f32;
                    for slot in a..b {
                        let d2 = self.positions[slot].distance_squared(q);
                        if d2 < r2 && d2 < self.reach[slot] {
                            pending.push((self.items[slot], slot as u32, sub as u32, d2));
                        } else {
                            kept = kept.max(self.reach[slot]);
                        }
                    }
                    self.sub_bound[sub] = kept;
                }
            }
        }
        if pending.is_empty() && s == 1 {
            self.cell_bound[c] = self.sub_bound[first];
            return;
        }
        // Items are unique: the order by index is total.
        pending.sort_unstable_by_key(|e| e.0);
        for &(item, slot, sub, d2) in pending.iter() {
            let reach = f(item, d2);
            self.reach[slot as usize] = reach;
            let bound = &mut self.sub_bound[sub as usize];
            *bound = bound.max(reach);
        }
        self.cell_bound[c] = self.sub_bound[first..first + s * s * s]
            .iter()
            .fold(0.0, |m, r| m.max(*r));
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

    /// `update_near` against brute force on dense points (cells split into sub-cells):
    /// it reports exactly the points within `r` and closer than their reach, cell by cell
    /// in increasing cell order and by index within a cell, and keeps the reaches it is
    /// given for the next queries.
    #[test]
    fn updates_visit_exactly_the_points_within_reach_in_cell_order() {
        let mut rng = Mt64::new(3);
        let pts: Vec<Vec3> = (0..20_000)
            .map(|_| {
                Vec3::new(
                    uniform24(&mut rng),
                    uniform24(&mut rng),
                    uniform24(&mut rng),
                ) * 2.0
            })
            .collect();
        let keep: Vec<bool> = (0..pts.len()).map(|i| i % 7 != 0).collect();
        let mut g = PointGrid::new(&pts, &keep, 0.3);
        assert!(g.split > 1, "dense points split the cells");
        let mut reach: Vec<f32> = (0..pts.len())
            .map(|i| if keep[i] { f32::INFINITY } else { 0.0 })
            .collect();
        let r = 0.5;
        let mut visited_total = 0;
        for round in 0..300 {
            let q = Vec3::new(
                uniform24(&mut rng),
                uniform24(&mut rng),
                uniform24(&mut rng),
            ) * 2.2
                - 0.1;
            let mut want: Vec<(usize, u32)> = (0..pts.len() as u32)
                .filter(|&i| {
                    let d2 = pts[i as usize].distance_squared(q);
                    keep[i as usize] && d2 < r * r && d2 < reach[i as usize]
                })
                .map(|i| (g.sub_index(pts[i as usize]) / g.split.pow(3), i))
                .collect();
            want.sort_unstable();
            let mut got = Vec::new();
            g.update_near(q, r, |i, d2| {
                assert_eq!(d2, pts[i as usize].distance_squared(q));
                got.push(i);
                // Some points leave (reach 0), the others come closer.
                reach[i as usize] = if (i + round) % 5 == 0 { 0.0 } else { d2 };
                reach[i as usize]
            });
            let want: Vec<u32> = want.into_iter().map(|(_, i)| i).collect();
            assert_eq!(got, want, "query {round} at {q}");
            visited_total += got.len();
        }
        assert!(
            visited_total > 1000,
            "the queries changed {visited_total} points"
        );
    }
}
