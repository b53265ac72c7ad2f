//! Kept trunks of earlier layers in a flat grid, so that later layers keep their distance.

/// Kept trunks of earlier layers, for the distance test of later ones.
#[derive(Default)]
pub(crate) struct Trunks(Vec<(f64, f64)>);

impl Trunks {
    pub(crate) fn extend(&mut self, more: Vec<(f64, f64)>) {
        self.0.extend(more);
    }

    /// A flat grid over the trunks for tests at distance `r`: cells of side `r` at least
    /// (larger when the trunks spread over too many cells of `r`), each cell's trunks
    /// contiguous.
    pub(crate) fn index(&self, r: f64) -> TrunkIndex {
        let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for &(x, z) in &self.0 {
            min = [min[0].min(x), min[1].min(z)];
            max = [max[0].max(x), max[1].max(z)];
        }
        if self.0.is_empty() {
            return TrunkIndex {
                origin: [0.0; 2],
                cell: r,
                dims: [0, 0],
                starts: Vec::new(),
                points: Vec::new(),
            };
        }
        let extent = (max[0] - min[0]).max(max[1] - min[1]);
        // Four cells per trunk at most: sparse trunks get larger cells.
        let budget = (4 * self.0.len()).max(1024) as f64;
        let cell = r.max(extent / budget.sqrt());
        let dims = [
            ((max[0] - min[0]) / cell) as usize + 1,
            ((max[1] - min[1]) / cell) as usize + 1,
        ];
        let cell_of = |x: f64, z: f64| {
            let cx = (((x - min[0]) / cell) as usize).min(dims[0] - 1);
            let cz = (((z - min[1]) / cell) as usize).min(dims[1] - 1);
            cz * dims[0] + cx
        };
        let mut starts = vec![0u32; dims[0] * dims[1] + 1];
        for &(x, z) in &self.0 {
            starts[cell_of(x, z) + 1] += 1;
        }
        for k in 1..starts.len() {
            starts[k] += starts[k - 1];
        }
        let mut fill = starts.clone();
        let mut points = vec![[0.0; 2]; self.0.len()];
        for &(x, z) in &self.0 {
            let k = cell_of(x, z);
            points[fill[k] as usize] = [x, z];
            fill[k] += 1;
        }
        TrunkIndex {
            origin: min,
            cell,
            dims,
            starts,
            points,
        }
    }
}

/// Trunks sorted into a flat grid (compressed rows: `starts[k]..starts[k + 1]` of
/// `points` are cell `k`'s).
pub(crate) struct TrunkIndex {
    origin: [f64; 2],
    cell: f64,
    dims: [usize; 2],
    starts: Vec<u32>,
    points: Vec<[f64; 2]>,
}

impl TrunkIndex {
    /// Whether a trunk stands closer than `d` to `(x, z)`.
    pub(crate) fn any_within(&self, x: f64, z: f64, d: f64) -> bool {
        if self.points.is_empty() {
            return false;
        }
        let range = |v: f64, axis: usize| {
            let a = ((v - d - self.origin[axis]) / self.cell).floor();
            let b = ((v + d - self.origin[axis]) / self.cell).floor();
            let n = self.dims[axis] as f64 - 1.0;
            if b < 0.0 || a > n {
                None
            } else {
                Some((a.max(0.0) as usize, b.min(n) as usize))
            }
        };
        let (Some((x0, x1)), Some((z0, z1))) = (range(x, 0), range(z, 1)) else {
            return false;
        };
        let d2 = d * d;
        for cz in z0..=z1 {
            let row = cz * self.dims[0];
            let (a, b) = (self.starts[row + x0], self.starts[row + x1 + 1]);
            if self.points[a as usize..b as usize].iter().any(|p| {
                let (dx, dz) = (p[0] - x, p[1] - z);
                dx * dx + dz * dz < d2
            }) {
                return true;
            }
        }
        false
    }
}
