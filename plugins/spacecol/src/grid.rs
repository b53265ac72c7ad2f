//! The uniform grid over the attraction points: which live points lie within a radius of a
//! node, and which of them a new node changes.

use pge_engine::math;
use std::ops::Range;

use glam::{Vec3, Vec4};

const NONE: u32 = u32::MAX;

/// A uniform grid over the attraction points, for "which points lie within r of this node"
/// queries, from which points are removed as they die.
///
/// Each cell is split again into `split³` sub-cells (more when the points are dense). Each
/// sub-cell keeps its live points in a compact run of slots, four to a group of lanes (the
/// positions and reaches of four points, coordinate by coordinate, so that they are tested
/// together); a run starts on a group and its last group is padded with empty slots, which
/// no query hits. A removed point's slot takes the run's last point (swap-remove), so dead
/// points are never read again.
///
/// Every point carries a *reach*: the squared distance under which a new node changes
/// something for it (for colonization, its distance to its nearest node). Cells and
/// sub-cells remember the largest reach of their points (an upper bound), so
/// [`PointGrid::update_near`] skips those that no point of which can be affected, without
/// reading their points.
#[derive(Clone, Debug)]
pub struct PointGrid {
    origin: Vec3,
    inv_cell: f32,
    cell: f32,
    dims: [usize; 3],
    /// Sub-cells per cell side.
    split: usize,
    /// Where the slots of each sub-cell start (a multiple of four); a cell's sub-cells are
    /// consecutive (x, y, z order), so cell `c` holds slots `starts[c s³] .. starts[(c + 1)
    /// s³]`.
    starts: Vec<u32>,
    /// How many of its slots each sub-cell still fills (its live points).
    lens: Vec<u32>,
    /// The point in each slot ([`NONE`]: an empty slot).
    items: Vec<u32>,
    /// The positions and reaches of the slots, four to a group: slot `k` is lane `k % 4`
    /// of group `k / 4`.
    lanes: Vec<Lanes>,
    /// Each point's slot, [`NONE`] once removed (or never kept).
    slot_of: Vec<u32>,
    /// The largest reach in each sub-cell (an upper bound).
    sub_bound: Vec<f32>,
    /// The largest reach in each cell (an upper bound), and three more of 0 at the end, so
    /// that the cells are read four at a time.
    cell_bound: Vec<f32>,
    /// How far a point may lie outside its cell's nominal box through rounding: skipping
    /// tests shrink distances by this much, so that they never skip an affected point.
    slack: f32,
    /// Scratch of `update_near`: the per-axis gaps of the cells it spans.
    gaps: Vec<f32>,
}

/// Four slots of a [`PointGrid`]: their positions coordinate by coordinate and their reaches
/// (squared), each a SIMD vector on x86-64. An empty slot lies at the origin with reach 0,
/// which no distance is below. A slot's lane is addressed through the vector's array
/// (`as_ref`, `as_mut`): `Vec4`'s indexing is a `match`, a jump on the lane that the
/// processor mispredicts at nearly every call-back.
#[derive(Clone, Copy, Debug, Default)]
struct Lanes {
    x: Vec4,
    y: Vec4,
    z: Vec4,
    reach: Vec4,
}

impl Lanes {
    /// Bit `j` set when lane `j` lies within `r2` of `q` and closer than its reach, and the
    /// lanes' squared distances to `q` (summed as `Vec3::distance_squared` sums them, lane
    /// by lane: the same bits).
    #[inline(always)]
    fn hits(&self, q: Vec3, r2: f32) -> (u64, Vec4) {
        let (dx, dy, dz) = (
            self.x - Vec4::splat(q.x),
            self.y - Vec4::splat(q.y),
            self.z - Vec4::splat(q.z),
        );
        let d2 = dx * dx + dy * dy + dz * dz;
        let hits = d2.cmplt(self.reach.min(Vec4::splat(r2))).bitmask();
        (u64::from(hits), d2)
    }
}

/// Grids larger than this many cells get larger cells.
const MAX_CELLS: usize = 1 << 21;

/// Sub-cells are made only while the grid has at most this many of them.
const MAX_SUB_CELLS: usize = 1 << 22;

/// The number of points a sub-cell should hold on average.
const POINTS_PER_SUB_CELL: f32 = 8.0;

impl PointGrid {
    /// A grid of cells about `cell` wide over the points whose `keep` is true; every kept
    /// point's reach is infinite. Within a sub-cell, points are in increasing index order.
    #[must_use]
    pub fn new(points: &[Vec3], keep: &[bool], cell: f32) -> PointGrid {
        let mut grid = PointGrid::layout(points, keep, cell);
        grid.slot_of = vec![NONE; points.len()];
        let (cells, split) = (grid.cells(), grid.split);
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
        grid.lens = counts[1..].to_vec();
        // Each run starts on a group of four slots.
        for c in 0..subs {
            counts[c + 1] = counts[c] + counts[c + 1].next_multiple_of(4);
        }
        let mut fill = counts.clone();
        let total = counts[subs] as usize;
        grid.items = vec![NONE; total];
        grid.lanes = vec![Lanes::default(); total / 4];
        for (i, c) in sub_of.iter().enumerate() {
            if keep[i] {
                let slot = fill[*c];
                grid.items[slot as usize] = i as u32;
                grid.set(slot as usize, points[i], f32::INFINITY);
                grid.slot_of[i] = slot;
                fill[*c] += 1;
            }
        }
        grid.starts = counts;
        grid.sub_bound = (0..subs)
            .map(|s| if grid.lens[s] > 0 { f32::INFINITY } else { 0.0 })
            .collect();
        let s3 = split.pow(3);
        grid.cell_bound = (0..cells)
            .map(|c| {
                grid.sub_bound[c * s3..(c + 1) * s3]
                    .iter()
                    .fold(0.0f32, |m, r| m.max(*r))
            })
            .chain([0.0; 3])
            .collect();
        grid
    }

    /// A grid without points: its cells and sub-cells for the kept points.
    fn layout(points: &[Vec3], keep: &[bool], cell: f32) -> PointGrid {
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
        let mut split = (math::cbrt(per_cell / POINTS_PER_SUB_CELL).round() as usize).clamp(1, 8);
        while split > 1 && cells * split.pow(3) > MAX_SUB_CELLS {
            split -= 1;
        }
        let top = lo + Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) * cell;
        let slack = 1e-3 * cell + 1e-5 * lo.abs().max(top.abs()).max_element();
        PointGrid {
            origin: lo,
            inv_cell: 1.0 / cell,
            cell,
            dims,
            split,
            starts: Vec::new(),
            lens: Vec::new(),
            items: Vec::new(),
            lanes: Vec::new(),
            slot_of: Vec::new(),
            sub_bound: Vec::new(),
            cell_bound: Vec::new(),
            slack,
            gaps: Vec::new(),
        }
    }

    /// The order in which [`Self::new`] would keep the points, as [`Self::renumber`] then
    /// gives it (cell by cell, in increasing index within a cell), when its cells are not
    /// split (`None` when they are), without building the grid: a stable counting sort of
    /// the kept points by cell.
    #[must_use]
    pub fn unsplit_order(points: &[Vec3], keep: &[bool], cell: f32) -> Option<Vec<u32>> {
        let grid = PointGrid::layout(points, keep, cell);
        if grid.split > 1 {
            return None;
        }
        let cells = grid.cells();
        let mut starts = vec![0u32; cells + 1];
        let cell_of: Vec<u32> = points
            .iter()
            .zip(keep)
            .map(|(p, k)| {
                let c = grid.sub_index(*p);
                if *k {
                    starts[c + 1] += 1;
                }
                c as u32
            })
            .collect();
        for c in 0..cells {
            starts[c + 1] += starts[c];
        }
        let mut order = vec![0u32; starts[cells] as usize];
        for (i, c) in cell_of.iter().enumerate() {
            if keep[i] {
                let slot = &mut starts[*c as usize];
                order[*slot as usize] = i as u32;
                *slot += 1;
            }
        }
        Some(order)
    }

    /// Renumbers the points in the grid's order (cell by cell, sub-cell by sub-cell: the
    /// points a query reads together get consecutive numbers) and returns the old number
    /// of each new one; points not in the grid get no new number. Only before any point
    /// was removed (the slots are then in the grid's order).
    pub fn renumber(&mut self) -> Vec<u32> {
        let mut old = Vec::with_capacity(self.slot_of.len());
        self.slot_of.clear();
        for (slot, item) in self.items.iter_mut().enumerate() {
            if *item != NONE {
                old.push(*item);
                *item = self.slot_of.len() as u32;
                self.slot_of.push(slot as u32);
            }
        }
        old
    }

    /// The number of cells.
    fn cells(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// Sub-cells per cell side (1: the cells are not split).
    #[must_use]
    pub fn sub_cells(&self) -> usize {
        self.split
    }

    /// Whether point `i` is still in the grid.
    #[must_use]
    pub fn contains(&self, i: u32) -> bool {
        self.slot_of.get(i as usize).is_some_and(|s| *s != NONE)
    }

    /// The cell of coordinate `v` along `axis` (origin `o` there), clamped to the grid.
    fn coord(&self, v: f32, axis: usize, o: f32) -> usize {
        floor_index((v - o) * self.inv_cell).min(self.dims[axis] - 1)
    }

    /// The position of the point in `slot`.
    fn position(&self, slot: usize) -> Vec3 {
        let (l, j) = (&self.lanes[slot / 4], slot % 4);
        Vec3::new(l.x.as_ref()[j], l.y.as_ref()[j], l.z.as_ref()[j])
    }

    /// Puts a point at `p` with reach `reach` in `slot`.
    fn set(&mut self, slot: usize, p: Vec3, reach: f32) {
        let (l, j) = (&mut self.lanes[slot / 4], slot % 4);
        l.x.as_mut()[j] = p.x;
        l.y.as_mut()[j] = p.y;
        l.z.as_mut()[j] = p.z;
        l.reach.as_mut()[j] = reach;
    }

    /// The sub-cell of `p` (cell-major), consistent with the cell [`Self::coord`] gives.
    #[inline]
    fn sub_index(&self, p: Vec3) -> usize {
        let s = self.split;
        if s == 1 {
            // The cell alone, its three coordinates at once (as `coord` computes each).
            let c = (p - self.origin) * self.inv_cell;
            let [x, y, z] = [c.x, c.y, c.z].map(floor_index);
            let [nx, ny, nz] = self.dims;
            return (x.min(nx - 1) * ny + y.min(ny - 1)) * nz + z.min(nz - 1);
        }
        let (o, fine) = (self.origin, self.inv_cell * s as f32);
        let axis = |v: f32, a: usize, o: f32| {
            let k = self.coord(v, a, o);
            if s == 1 {
                return (k, 0);
            }
            let f = floor_index((v - o) * fine);
            (k, f.clamp(k * s, k * s + s - 1) - k * s)
        };
        let (x, sx) = axis(p.x, 0, o.x);
        let (y, sy) = axis(p.y, 1, o.y);
        let (z, sz) = axis(p.z, 2, o.z);
        let cell = (x * self.dims[1] + y) * self.dims[2] + z;
        cell * s * s * s + (sx * s + sy) * s + sz
    }

    /// Removes point `i` (nothing if it is not in the grid): the last point of its
    /// sub-cell takes its slot.
    pub fn remove(&mut self, i: u32) {
        let Some(&slot) = self.slot_of.get(i as usize) else {
            return;
        };
        if slot == NONE {
            return;
        }
        let sub = self.sub_index(self.position(slot as usize));
        self.remove_slot(sub, slot as usize);
    }

    /// Removes the point in `slot` of sub-cell `sub`, moving the sub-cell's last point in;
    /// the last slot is left empty.
    fn remove_slot(&mut self, sub: usize, slot: usize) {
        self.lens[sub] -= 1;
        let last = (self.starts[sub] + self.lens[sub]) as usize;
        self.slot_of[self.items[slot] as usize] = NONE;
        if last != slot {
            self.items[slot] = self.items[last];
            let reach = self.lanes[last / 4].reach.as_ref()[last % 4];
            self.set(slot, self.position(last), reach);
            self.slot_of[self.items[slot] as usize] = slot as u32;
        }
        self.items[last] = NONE;
        self.set(last, Vec3::ZERO, 0.0);
    }

    /// The cells whose boxes the ball of radius `r` around `q` touches, as runs of z cells:
    /// `f(self, x, y, z0, z1)` for each (x, y) column, in increasing cell order.
    fn runs(&self, q: Vec3, r: f32, mut f: impl FnMut(&Self, usize, usize, usize, usize)) {
        let Some([(x0, x1), (y0, y1), (z0, z1)]) = self.span(q, r) else {
            return;
        };
        let r2 = r * r;
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

    /// Calls `f(index, position, squared distance)` for every live point within `r` of
    /// `q`, in no particular order. Only cells that the ball touches are read.
    pub fn for_each_near(&self, q: Vec3, r: f32, mut f: impl FnMut(u32, Vec3, f32)) {
        let r2 = r * r;
        let s3 = self.split.pow(3);
        self.runs(q, r, |g, x, y, z, z_end| {
            let row = (x * g.dims[1] + y) * g.dims[2];
            for sub in (row + z) * s3..(row + z_end + 1) * s3 {
                let a = g.starts[sub] as usize;
                let b = a + g.lens[sub] as usize;
                for slot in a..b {
                    let p = g.position(slot);
                    let d2 = p.distance_squared(q);
                    if d2 < r2 {
                        f(g.items[slot], p, d2);
                    }
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

    /// Calls `f(index, squared distance)` for every live point within `r` of `q` that lies
    /// closer to `q` than its reach; `f` returns the point's new reach, or `None` to remove
    /// the point. Each point is called for once at most, in no particular order. Cells and
    /// sub-cells whose largest reach is below their distance to `q` are skipped unread.
    ///
    /// A cell's distance to `q` is the sum of its three per-axis gaps, computed once per
    /// query for the rows, columns and layers the ball spans; a column's cells are tested
    /// four at a time (most cells are skipped once the points near them have a node close
    /// by), and unsplit cells to read that follow one another are read as one run of slots.
    pub fn update_near(&mut self, q: Vec3, r: f32, mut f: impl FnMut(u32, f32) -> Option<f32>) {
        let Some([(x0, x1), (y0, y1), (z0, z1)]) = self.span(q, r) else {
            return;
        };
        let r2 = r * r;
        let mut gaps = std::mem::take(&mut self.gaps);
        gaps.clear();
        let (o, w) = (self.origin, self.cell);
        gaps.extend((x0..=x1).map(|x| self.near_gap(o.x + x as f32 * w, w, q.x)));
        gaps.extend((y0..=y1).map(|y| self.near_gap(o.y + y as f32 * w, w, q.y)));
        gaps.extend((z0..=z1).map(|z| self.near_gap(o.z + z as f32 * w, w, q.z)));
        // The layers padded to groups of four with an infinite gap, whose cells (the next
        // column's, or the bounds' padding) are never read.
        let layers = z1 - z0 + 1;
        gaps.resize(
            gaps.len() + layers.next_multiple_of(4) - layers,
            f32::INFINITY,
        );
        let (gx, rest) = gaps.split_at(x1 - x0 + 1);
        let (gy, gz) = rest.split_at(y1 - y0 + 1);
        let r2s = Vec4::splat(r2);
        for (x, &dx) in (x0..).zip(gx) {
            for (y, &dy) in (y0..).zip(gy) {
                let dxy = dx + dy;
                // A lower bound of the distance of any point in these cells: a cell is
                // read only when it is below both the radius and the cell's largest reach.
                if dxy >= r2 {
                    continue;
                }
                let column = (x * self.dims[1] + y) * self.dims[2] + z0;
                for (first, dz) in (column..).step_by(4).zip(gz.chunks_exact(4)) {
                    let d = Vec4::splat(dxy) + Vec4::from_slice(dz);
                    let bound = Vec4::from_slice(&self.cell_bound[first..first + 4]);
                    let mut read = (d.cmplt(r2s) & d.cmplt(bound)).bitmask();
                    if self.split == 1 {
                        // Each cell is its one sub-cell, whose distance was just tested, and
                        // the column's cells lie one after the other in the slots: a run of
                        // cells to read is read as one run of slots.
                        while read != 0 {
                            let k = read.trailing_zeros();
                            let cells = (!(read >> k)).trailing_zeros();
                            read &= !(((1 << cells) - 1) << k);
                            let c = first + k as usize;
                            self.update_run(q, r2, c..c + cells as usize, &mut f);
                        }
                        continue;
                    }
                    while read != 0 {
                        let k = read.trailing_zeros() as usize;
                        read &= read - 1;
                        self.update_cell(q, r2, first + k, &mut f);
                    }
                }
            }
        }
        self.gaps = gaps;
    }

    /// The ranges of cells along x, y and z that the box of half-side `r` around `q`
    /// overlaps, or `None` when it misses the grid.
    fn span(&self, q: Vec3, r: f32) -> Option<[(usize, usize); 3]> {
        let lo = q - r;
        let hi = q + r;
        let top = self.origin
            + Vec3::new(
                self.dims[0] as f32,
                self.dims[1] as f32,
                self.dims[2] as f32,
            ) * self.cell;
        if hi.cmplt(self.origin).any() || lo.cmpgt(top).any() {
            return None;
        }
        let o = self.origin;
        Some([
            (self.coord(lo.x, 0, o.x), self.coord(hi.x, 0, o.x)),
            (self.coord(lo.y, 1, o.y), self.coord(hi.y, 1, o.y)),
            (self.coord(lo.z, 2, o.z), self.coord(hi.z, 2, o.z)),
        ])
    }

    /// [`Self::update_near`] within cell `c` of a split grid.
    fn update_cell(
        &mut self,
        q: Vec3,
        r2: f32,
        c: usize,
        f: &mut impl FnMut(u32, f32) -> Option<f32>,
    ) {
        let s = self.split;
        let (x, y, z) = (
            c / (self.dims[1] * self.dims[2]),
            c / self.dims[2] % self.dims[1],
            c % self.dims[2],
        );
        let w = self.cell / s as f32;
        let corner = self.origin + Vec3::new(x as f32, y as f32, z as f32) * self.cell;
        let first = c * s * s * s;
        let mut cell_bound = 0.0f32;
        for sx in 0..s {
            let gx = self.near_gap(corner.x + sx as f32 * w, w, q.x);
            for sy in 0..s {
                let gxy = gx + self.near_gap(corner.y + sy as f32 * w, w, q.y);
                for sz in 0..s {
                    let sub = first + (sx * s + sy) * s + sz;
                    let bound = self.sub_bound[sub];
                    if gxy + self.near_gap(corner.z + sz as f32 * w, w, q.z) >= bound {
                        cell_bound = cell_bound.max(bound);
                        continue;
                    }
                    self.update_run(q, r2, sub..sub + 1, f);
                    cell_bound = cell_bound.max(self.sub_bound[sub]);
                }
            }
        }
        self.cell_bound[c] = cell_bound;
    }

    /// [`Self::update_near`] within the consecutive sub-cells `subs`, whose slots follow one
    /// another (one sub-cell, or a run of a column's unsplit cells, read as one run of
    /// slots: one loop where each cell had its own); the largest reach of each sub-cell that
    /// changed is folded again (an unsplit cell's bound too). Inlined into the cells' loop
    /// (some 20,000 cells read an oak), which keeps the query's values in registers.
    #[inline(always)]
    fn update_run(
        &mut self,
        q: Vec3,
        r2: f32,
        subs: Range<usize>,
        f: &mut impl FnMut(u32, f32) -> Option<f32>,
    ) {
        let start = self.starts[subs.start] as usize;
        let last = subs.end - 1;
        let end = (self.starts[last] + self.lens[last]) as usize;
        // Up to 16 groups (64 slots) at a time from the last: the points to call back for
        // are found four at a time without branching (empty slots between the sub-cells,
        // of reach 0, never hit), then called back for from the highest slot down, so that
        // a removal's swap (within a sub-cell) moves in only a point already seen.
        let first = start / 4;
        let mut chunk_end = end.div_ceil(4);
        // The sub-cell of the slots being called back for (they come in decreasing order),
        // and the sub-cells that changed, a bit each from `subs.start` (a run is one
        // sub-cell, or at most the four cells of a column chunk).
        debug_assert!(subs.len() <= 4, "a run of {} sub-cells", subs.len());
        let (mut sub, mut changed) = (last, 0u64);
        // The squared distances of the chunk's slots, kept for the call-backs.
        let mut d2s = [Vec4::ZERO; 16];
        while chunk_end > first {
            let chunk_start = chunk_end.saturating_sub(16).max(first);
            let mut hits = 0u64;
            for (k, (lanes, d2)) in self.lanes[chunk_start..chunk_end]
                .iter()
                .zip(&mut d2s)
                .enumerate()
            {
                let (bits, group) = lanes.hits(q, r2);
                hits |= bits << (4 * k);
                *d2 = group;
            }
            while hits != 0 {
                let k = 63 - hits.leading_zeros() as usize;
                hits &= !(1u64 << k);
                let slot = chunk_start * 4 + k;
                while self.starts[sub] as usize > slot {
                    sub -= 1;
                }
                changed |= 1 << (sub - subs.start);
                let d2 = d2s[k / 4].as_ref()[k % 4];
                match f(self.items[slot], d2) {
                    Some(reach) => self.lanes[slot / 4].reach.as_mut()[slot % 4] = reach,
                    None => self.remove_slot(sub, slot),
                }
            }
            chunk_end = chunk_start;
        }
        // The sub-cells where no point changed (most of those read) keep their bounds
        // unread.
        while changed != 0 {
            let sub = subs.start + changed.trailing_zeros() as usize;
            changed &= changed - 1;
            // Empty slots have reach 0, which leaves the largest reach as it is.
            let start = self.starts[sub] as usize;
            let groups = start / 4..(start + self.lens[sub] as usize).div_ceil(4);
            let kept = self.lanes[groups]
                .iter()
                .fold(Vec4::ZERO, |m, l| m.max(l.reach))
                .max_element();
            self.sub_bound[sub] = kept;
            if self.split == 1 {
                self.cell_bound[sub] = kept;
            }
        }
    }
}

/// `x` rounded down and clamped at 0 (NaN gives 0), as an index.
///
/// The cast rounds toward zero and takes negatives and NaN to 0, so it is `floor` clamped at
/// 0 without the call to `floor` (a libm call on the baseline x86-64 target). It goes through
/// `i32`, whose saturating cast is a few instructions where `usize`'s is a dozen; an index
/// beyond `i32::MAX` saturates there, above any grid's largest index, so callers' clamps
/// give the same cell.
fn floor_index(x: f32) -> usize {
    (x as i32).max(0) as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::random::uniform24;
    use rand_mt::Mt64;

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

    /// `unsplit_order` gives the order `new` keeps unsplit cells in, and nothing for split
    /// ones.
    #[test]
    fn unsplit_order_is_the_grids_order() {
        let mut rng = Mt64::new(5);
        let pts: Vec<Vec3> = (0..3000)
            .map(|_| {
                Vec3::new(
                    uniform24(&mut rng),
                    uniform24(&mut rng),
                    uniform24(&mut rng),
                ) * 4.0
            })
            .collect();
        let keep: Vec<bool> = (0..pts.len()).map(|i| i % 5 != 0).collect();
        let mut grid = PointGrid::new(&pts, &keep, 0.5);
        assert_eq!(grid.sub_cells(), 1);
        assert_eq!(
            PointGrid::unsplit_order(&pts, &keep, 0.5),
            Some(grid.renumber())
        );
        assert!(PointGrid::new(&pts, &keep, 2.0).sub_cells() > 1);
        assert_eq!(PointGrid::unsplit_order(&pts, &keep, 2.0), None);
    }

    /// `update_near` against brute force on dense points (cells split into sub-cells): it
    /// reports exactly the live points within `r` and closer than their reach, keeps the
    /// reaches it is given for the next queries and forgets the points it removes (as
    /// `remove` does).
    #[test]
    fn updates_visit_exactly_the_live_points_within_reach() {
        let g = check_updates(20_000, 0.3);
        assert!(g.split > 1, "dense points split the cells");
    }

    /// The same on sparse points (a few per cell, no sub-cells, as in a small tree's
    /// crown), and on points so crowded that sub-cells hold more than the 64 points
    /// `update_sub` tests at once.
    #[test]
    fn updates_visit_exactly_the_live_points_within_reach_sparse_and_crowded() {
        let g = check_updates(1_500, 0.2);
        assert_eq!(g.split, 1, "sparse points leave the cells whole");
        let g = check_updates(60_000, 2.0);
        assert!(
            g.lens.iter().any(|n| *n > 64),
            "a sub-cell holds more than 64 points"
        );
    }

    /// Runs 300 `update_near` queries of radius 0.5 on `n` random points in a 2 m cube
    /// (one in seven left out) in a grid of cells `cell` wide, each checked against brute
    /// force; returns the grid.
    fn check_updates(n: usize, cell: f32) -> PointGrid {
        let mut rng = Mt64::new(3);
        let pts: Vec<Vec3> = (0..n)
            .map(|_| {
                Vec3::new(
                    uniform24(&mut rng),
                    uniform24(&mut rng),
                    uniform24(&mut rng),
                ) * 2.0
            })
            .collect();
        let keep: Vec<bool> = (0..pts.len()).map(|i| i % 7 != 0).collect();
        let mut g = PointGrid::new(&pts, &keep, cell);
        let mut live = keep.clone();
        let mut reach = vec![f32::INFINITY; pts.len()];
        let r = 0.5;
        let (mut visited, mut removed) = (0, 0);
        for round in 0..300u32 {
            let q = Vec3::new(
                uniform24(&mut rng),
                uniform24(&mut rng),
                uniform24(&mut rng),
            ) * 2.2
                - 0.1;
            let mut want: Vec<u32> = (0..pts.len() as u32)
                .filter(|&i| {
                    let d2 = pts[i as usize].distance_squared(q);
                    live[i as usize] && d2 < r * r && d2 < reach[i as usize]
                })
                .collect();
            let mut got = Vec::new();
            g.update_near(q, r, |i, d2| {
                assert_eq!(d2, pts[i as usize].distance_squared(q));
                got.push(i);
                // Some points leave, the others come closer.
                if (i + round) % 5 == 0 {
                    live[i as usize] = false;
                    removed += 1;
                    None
                } else {
                    reach[i as usize] = d2;
                    Some(d2)
                }
            });
            got.sort_unstable();
            want.sort_unstable();
            assert_eq!(got, want, "query {round} at {q}");
            visited += got.len();
            // Every 10th round, a point dies outside the queries.
            if round % 10 == 0 {
                let i = (round * 61) % pts.len() as u32;
                g.remove(i);
                live[i as usize] = false;
            }
            for i in (round * 13..round * 13 + 13).map(|i| i % pts.len() as u32) {
                assert_eq!(g.contains(i), live[i as usize], "point {i}");
            }
        }
        assert!(
            visited > 1000 && removed > 100,
            "the queries changed {visited} points and removed {removed}"
        );
        let mut left = 0;
        g.for_each_near(Vec3::ONE, 10.0, |i, _, _| {
            assert!(live[i as usize]);
            left += 1;
        });
        assert_eq!(left, live.iter().filter(|l| **l).count());
        g
    }
}
