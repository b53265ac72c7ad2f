//! [`MarchingCubes`]: extracts the isosurface of a [`Metaballs`] field as a closed mesh.

use std::collections::HashMap;
use std::sync::Arc;

use glam::Vec3;
use pge_engine::geometry::{Material, Mesh};

use crate::field::{Metaballs, Particle};
use crate::table::{EDGES, corner_offset, table};

/// The finest grid allowed along one axis.
pub const MAX_RESOLUTION: u32 = 4096;

/// Cells per block side: the grid is visited in blocks of `BLOCK³` cells, and a block is
/// skipped when the field provably does not cross the iso value inside it.
const BLOCK: usize = 8;

/// Why a surface could not be extracted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MarchError {
    /// The resolution was 0 or above [`MAX_RESOLUTION`].
    #[error("resolution must be between 1 and {MAX_RESOLUTION} cells, got {0}")]
    BadResolution(i64),
    /// The iso value was not a positive finite number.
    #[error("iso must be a positive number (the field is 0 far from every particle), got {0}")]
    BadIso(f32),
    /// The bounds were empty, inverted or not finite.
    #[error("bounds must have min < max on every axis and be finite")]
    BadBounds,
    /// The grid has more cells than allowed.
    #[error(
        "a grid of {nx}x{ny}x{nz} cells is larger than the limit of {max} cells; lower the resolution"
    )]
    GridTooLarge {
        /// Cells along x.
        nx: usize,
        /// Cells along y.
        ny: usize,
        /// Cells along z.
        nz: usize,
        /// The limit.
        max: u64,
    },
    /// The work or the mesh would need more memory than allowed.
    #[error(
        "marching cubes needs more than the memory limit of {limit_mib} MiB ({what}); lower the resolution"
    )]
    MemoryLimit {
        /// What grew too large.
        what: &'static str,
        /// The limit in MiB.
        limit_mib: usize,
    },
    /// The caller asked to stop (time limit or cancellation).
    #[error("interrupted")]
    Interrupted,
}

/// How [`MarchingCubes`] samples the field.
#[derive(Clone, Debug, PartialEq)]
pub struct MarchOptions {
    /// Cells along the longest side of the bounds (default 64); the other sides get cells of
    /// the same size.
    pub resolution: u32,
    /// The field value of the surface (default 0.5). Inside is where the field is above it.
    pub iso: f32,
    /// The box to sample; default: the field's bounds (where any particle reaches). The mesh
    /// is closed at the box's walls where the surface would cross them.
    pub bounds: Option<(Vec3, Vec3)>,
    /// The most cells the grid may have (default 2^31).
    pub max_cells: u64,
    /// The most bytes the work and the mesh may take (default 1 GiB).
    pub max_bytes: usize,
    /// The mesh's material.
    pub material: Arc<Material>,
}

impl Default for MarchOptions {
    fn default() -> Self {
        MarchOptions {
            resolution: 64,
            iso: 0.5,
            bounds: None,
            max_cells: 1 << 31,
            max_bytes: 1 << 30,
            material: Arc::new(Material::default()),
        }
    }
}

/// What one extraction did, for tests and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MarchStats {
    /// Cells of the whole grid.
    pub grid_cells: u64,
    /// Cells whose corners were sampled and classified.
    pub visited_cells: u64,
    /// Blocks of the grid.
    pub blocks: u64,
    /// Blocks visited (the others provably hold no surface).
    pub visited_blocks: u64,
}

/// Marching cubes over a [`Metaballs`] field.
///
/// The grid is split into blocks of 8³ cells; each particle is listed in the blocks its
/// radius reaches. A block without particles, or whose interval bound on the field (from the
/// nearest and farthest distance of each listed particle) stays on one side of `iso`, is
/// skipped, so the work follows the surface rather than the volume. Within a block the
/// corners are sampled from the block's own particle list, in particle order, so the two
/// blocks sharing a corner compute the same bits.
///
/// The mesh is closed: every vertex is welded per grid edge, the case table agrees across
/// shared faces (see [`crate::table`]), and the grid's outer corners count as outside.
/// Normals are the normalised negative field gradient at each vertex.
///
/// ```
/// use pge_metaballs::{Metaballs, MarchingCubes, MarchOptions};
/// use glam::Vec3;
///
/// let mut field = Metaballs::new(1.0);
/// field.add_particle(Vec3::ZERO, 1.0, None).unwrap();
/// let (mesh, stats) = MarchingCubes::new(MarchOptions { resolution: 64, ..Default::default() })
///     .unwrap()
///     .polygonize(&field, &mut || false)
///     .unwrap();
/// assert!(mesh.triangle_count() > 100);
/// assert!(stats.visited_cells < stats.grid_cells);
/// ```
#[derive(Clone, Debug)]
pub struct MarchingCubes {
    options: MarchOptions,
}

impl MarchingCubes {
    /// Checks the options.
    pub fn new(options: MarchOptions) -> Result<MarchingCubes, MarchError> {
        if options.resolution == 0 || options.resolution > MAX_RESOLUTION {
            return Err(MarchError::BadResolution(i64::from(options.resolution)));
        }
        if !options.iso.is_finite() || options.iso <= 0.0 {
            return Err(MarchError::BadIso(options.iso));
        }
        if let Some((lo, hi)) = options.bounds
            && (!lo.is_finite() || !hi.is_finite() || !lo.cmplt(hi).all())
        {
            return Err(MarchError::BadBounds);
        }
        Ok(MarchingCubes { options })
    }

    /// Changes the memory budget (the session's limit, known only when the mesh is made).
    pub fn set_max_bytes(&mut self, bytes: usize) {
        self.options.max_bytes = bytes;
    }

    /// The options.
    #[must_use]
    pub fn options(&self) -> &MarchOptions {
        &self.options
    }

    /// Extracts the surface. `interrupt` is called between blocks; returning `true` stops
    /// with [`MarchError::Interrupted`].
    ///
    /// The stages: lay the grid over the bounds (`Grid::new`), list the particles that
    /// reach each block (`BlockLists::build`), then per block: skip it when the field's
    /// interval bound stays on one side of `iso` (`may_cross`), sample its corners
    /// (`Marcher::sample`) and march its cells (`Marcher::march`); last, patch the normals
    /// the gradient could not give (`fix_degenerate_normals`).
    pub fn polygonize(
        &self,
        field: &Metaballs,
        interrupt: &mut dyn FnMut() -> bool,
    ) -> Result<(Mesh, MarchStats), MarchError> {
        let o = &self.options;
        let mesh = Mesh {
            name: "metaballs".into(),
            material: o.material.clone(),
            ..Mesh::default()
        };
        let Some((lo, hi)) = o.bounds.or_else(|| field.bounds()) else {
            return Ok((mesh, MarchStats::default()));
        };
        let grid = Grid::new(lo, hi, o)?;
        let limit_mib = o.max_bytes >> 20;
        let blocks = BlockLists::build(field.particles(), &grid, o.max_bytes)?;
        let mut marcher = Marcher {
            grid: &grid,
            iso: o.iso,
            tables: table(),
            welded: HashMap::new(),
            local: Vec::new(),
            values: vec![0.0f32; (BLOCK + 1).pow(3)],
            mesh,
            stats: MarchStats {
                grid_cells: grid.cells(),
                blocks: grid.block_count() as u64,
                ..MarchStats::default()
            },
        };
        let nb = grid.blocks;
        for bz in 0..nb[2] {
            for by in 0..nb[1] {
                for bx in 0..nb[0] {
                    if interrupt() {
                        return Err(MarchError::Interrupted);
                    }
                    let list = blocks.list(grid.block_index(bx, by, bz));
                    if list.is_empty() {
                        continue;
                    }
                    let (i0, i1) = grid.block_cells(bx, by, bz);
                    marcher.local.clear();
                    marcher
                        .local
                        .extend(list.iter().map(|&i| field.particles()[i as usize]));
                    if !may_cross(&grid, &marcher.local, i0, i1, o.iso) {
                        continue;
                    }
                    marcher.stats.visited_blocks += 1;
                    marcher.sample(i0, i1);
                    marcher.march(i0, i1);
                    let mesh = &marcher.mesh;
                    let bytes = mesh.positions.len() * 48 + mesh.indices.len() * 4;
                    if bytes > o.max_bytes {
                        return Err(MarchError::MemoryLimit {
                            what: "the mesh",
                            limit_mib,
                        });
                    }
                }
            }
        }
        let Marcher {
            mut mesh, stats, ..
        } = marcher;
        fix_degenerate_normals(&mut mesh);
        Ok((mesh, stats))
    }
}

/// The sampling grid over the bounds: cubic cells of side `h` from `lo`, visited in blocks
/// of `BLOCK³` cells.
struct Grid {
    lo: Vec3,
    h: f32,
    /// Cells along each axis.
    n: [usize; 3],
    /// Blocks along each axis.
    blocks: [usize; 3],
}

impl Grid {
    /// Cells of `1 / resolution` of the longest side over `lo..hi`; an error when the grid
    /// is not finite or has more than `max_cells` cells.
    fn new(lo: Vec3, hi: Vec3, o: &MarchOptions) -> Result<Grid, MarchError> {
        let extent = hi - lo;
        if !extent.is_finite() {
            return Err(MarchError::BadBounds);
        }
        let h = extent.max_element() / o.resolution as f32;
        let dims = (extent / h).ceil().max(Vec3::ONE);
        let (nx, ny, nz) = (dims.x as usize, dims.y as usize, dims.z as usize);
        let cells = nx as u64 * ny as u64 * nz as u64;
        if cells > o.max_cells {
            return Err(MarchError::GridTooLarge {
                nx,
                ny,
                nz,
                max: o.max_cells,
            });
        }
        Ok(Grid {
            lo,
            h,
            n: [nx, ny, nz],
            blocks: [nx.div_ceil(BLOCK), ny.div_ceil(BLOCK), nz.div_ceil(BLOCK)],
        })
    }

    fn cells(&self) -> u64 {
        self.n[0] as u64 * self.n[1] as u64 * self.n[2] as u64
    }

    fn block_count(&self) -> usize {
        self.blocks[0] * self.blocks[1] * self.blocks[2]
    }

    fn block_index(&self, bx: usize, by: usize, bz: usize) -> usize {
        (bz * self.blocks[1] + by) * self.blocks[0] + bx
    }

    /// The first and one-past-last grid points of a block's cells.
    fn block_cells(&self, bx: usize, by: usize, bz: usize) -> ([usize; 3], [usize; 3]) {
        let i0 = [bx * BLOCK, by * BLOCK, bz * BLOCK];
        let i1 = [
            (i0[0] + BLOCK).min(self.n[0]),
            (i0[1] + BLOCK).min(self.n[1]),
            (i0[2] + BLOCK).min(self.n[2]),
        ];
        (i0, i1)
    }

    /// The position of grid point `(i, j, k)`.
    fn point(&self, i: usize, j: usize, k: usize) -> Vec3 {
        self.lo + Vec3::new(i as f32, j as f32, k as f32) * self.h
    }

    /// Whether grid point `q` lies on a wall of the bounds (where the field counts as 0).
    fn on_wall(&self, q: [usize; 3]) -> bool {
        q.contains(&0) || q[0] == self.n[0] || q[1] == self.n[1] || q[2] == self.n[2]
    }
}

/// The particles each block lists (compressed rows, each in particle order): those whose
/// radius may reach a grid point of the block.
struct BlockLists {
    start: Vec<u32>,
    lists: Vec<u32>,
}

impl BlockLists {
    /// Lists `particles` per block of `grid`; an error when the lists would take more than
    /// `max_bytes`.
    fn build(
        particles: &[Particle],
        grid: &Grid,
        max_bytes: usize,
    ) -> Result<BlockLists, MarchError> {
        let (lo, h, nb) = (grid.lo, grid.h, grid.blocks);
        let block_count = grid.block_count();
        // Which blocks each particle reaches (points it may affect, conservatively).
        let ranges: Vec<[(usize, usize); 3]> = particles
            .iter()
            .map(|p| {
                let r = Vec3::splat(p.radius);
                let a = ((p.position - r - lo) / h).floor();
                let b = ((p.position + r - lo) / h).ceil();
                let range = |a: f32, b: f32, n: usize| {
                    let last = n as i64 - 1;
                    let first = ((a as i64).saturating_sub(1).div_euclid(BLOCK as i64))
                        .clamp(0, last.max(0));
                    let end = ((b as i64).div_euclid(BLOCK as i64)).clamp(-1, last);
                    (first as usize, (end + 1).max(first) as usize)
                };
                [
                    range(a.x, b.x, nb[0]),
                    range(a.y, b.y, nb[1]),
                    range(a.z, b.z, nb[2]),
                ]
            })
            .collect();
        let pairs: u64 = ranges
            .iter()
            .map(|r| r.iter().map(|(a, b)| (b - a) as u64).product::<u64>())
            .sum();
        if pairs.saturating_mul(4) + block_count as u64 * 8 > max_bytes as u64
            || pairs > u64::from(u32::MAX)
        {
            return Err(MarchError::MemoryLimit {
                what: "particle lists per block",
                limit_mib: max_bytes >> 20,
            });
        }
        let mut start = vec![0u32; block_count + 1];
        for r in &ranges {
            for bz in r[2].0..r[2].1 {
                for by in r[1].0..r[1].1 {
                    for bx in r[0].0..r[0].1 {
                        start[grid.block_index(bx, by, bz) + 1] += 1;
                    }
                }
            }
        }
        for i in 0..block_count {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut lists = vec![0u32; pairs as usize];
        for (pi, r) in ranges.iter().enumerate() {
            for bz in r[2].0..r[2].1 {
                for by in r[1].0..r[1].1 {
                    for bx in r[0].0..r[0].1 {
                        let b = grid.block_index(bx, by, bz);
                        lists[fill[b] as usize] = pi as u32;
                        fill[b] += 1;
                    }
                }
            }
        }
        Ok(BlockLists { start, lists })
    }

    /// The particles of block `b`.
    fn list(&self, b: usize) -> &[u32] {
        &self.lists[self.start[b] as usize..self.start[b + 1] as usize]
    }
}

/// Whether the surface may cross the block `i0..i1` whose particles are `local`: false when
/// the interval bound of the field over the block (from each particle's nearest and farthest
/// distance) stays on one side of `iso`. A block on the bounds' walls, where the field
/// counts as 0, is kept whenever some of it is inside.
fn may_cross(grid: &Grid, local: &[Particle], i0: [usize; 3], i1: [usize; 3], iso: f32) -> bool {
    let (blo, bhi) = (
        grid.point(i0[0], i0[1], i0[2]),
        grid.point(i1[0], i1[1], i1[2]),
    );
    let (mut fmin, mut fmax) = (0.0f32, 0.0f32);
    for p in local {
        let near = p.position.clamp(blo, bhi).distance_squared(p.position);
        let far_corner = Vec3::select(p.position.cmplt((blo + bhi) * 0.5), bhi, blo);
        let far = far_corner.distance_squared(p.position);
        let (a, b) = (p.falloff(far), p.falloff(near));
        fmin += a.min(b);
        fmax += a.max(b);
    }
    let n = grid.n;
    let touches_wall = i0.contains(&0) || i1[0] == n[0] || i1[1] == n[1] || i1[2] == n[2];
    !(fmax <= iso || (fmin > iso && !touches_wall))
}

/// The state of one extraction: the mesh so far, its vertices welded per grid edge, and the
/// current block's particles and corner values.
struct Marcher<'a> {
    grid: &'a Grid,
    iso: f32,
    tables: &'static [Vec<[u8; 3]>; 256],
    /// The vertex of each grid edge already cut (key: grid point and axis).
    welded: HashMap<u64, u32>,
    /// The current block's particles, in particle order.
    local: Vec<Particle>,
    /// The current block's corner values.
    values: Vec<f32>,
    mesh: Mesh,
    stats: MarchStats,
}

impl Marcher<'_> {
    /// The index of grid point `(i, j, k)` in `values` for the block starting at `i0`
    /// with `i1` as its far corner.
    fn at(i0: [usize; 3], i1: [usize; 3], i: usize, j: usize, k: usize) -> usize {
        let (sx, sy) = (i1[0] - i0[0] + 1, i1[1] - i0[1] + 1);
        ((k - i0[2]) * sy + (j - i0[1])) * sx + (i - i0[0])
    }

    /// Samples the field at the block's grid points (0 on the walls), summing the block's
    /// particles in particle order.
    fn sample(&mut self, i0: [usize; 3], i1: [usize; 3]) {
        let grid = self.grid;
        for k in i0[2]..=i1[2] {
            for j in i0[1]..=i1[1] {
                for i in i0[0]..=i1[0] {
                    self.values[Self::at(i0, i1, i, j, k)] = if grid.on_wall([i, j, k]) {
                        0.0
                    } else {
                        let p = grid.point(i, j, k);
                        self.local.iter().map(|q| q.value(p)).sum()
                    };
                }
            }
        }
    }

    /// Marches the block's cells: classifies each cell's corners and adds the triangles of
    /// its case, reusing the vertex of every grid edge already cut.
    fn march(&mut self, i0: [usize; 3], i1: [usize; 3]) {
        for k in i0[2]..i1[2] {
            for j in i0[1]..i1[1] {
                for i in i0[0]..i1[0] {
                    self.stats.visited_cells += 1;
                    let mut case = 0usize;
                    let mut v = [0.0f32; 8];
                    for (c, vc) in v.iter_mut().enumerate() {
                        let [dx, dy, dz] = corner_offset(c);
                        *vc = self.values[Self::at(i0, i1, i + dx, j + dy, k + dz)];
                        if *vc > self.iso {
                            case |= 1 << c;
                        }
                    }
                    for tri in &self.tables[case] {
                        let mut ids = [0u32; 3];
                        for (slot, &e) in ids.iter_mut().zip(tri) {
                            let (ca, cb, axis) = EDGES[e as usize];
                            let [dx, dy, dz] = corner_offset(ca);
                            *slot = self.edge_vertex([i + dx, j + dy, k + dz], axis, v[ca], v[cb]);
                        }
                        self.mesh.indices.extend(ids);
                    }
                }
            }
        }
    }

    /// The vertex where the surface cuts the grid edge from point `g` along `axis`, whose
    /// end values are `va` and `vb`: made on first use, then reused.
    fn edge_vertex(&mut self, g: [usize; 3], axis: usize, va: f32, vb: f32) -> u32 {
        let grid = self.grid;
        let [gi, gj, gk] = g;
        let [nx, ny, _] = grid.n;
        let key = (((gk * (ny + 1) + gj) * (nx + 1) + gi) * 3 + axis) as u64;
        let (iso, local, mesh) = (self.iso, &self.local, &mut self.mesh);
        *self.welded.entry(key).or_insert_with(|| {
            let t = ((iso - va) / (vb - va)).clamp(0.0, 1.0);
            let pa = grid.point(gi, gj, gk);
            let mut step = Vec3::ZERO;
            step[axis] = grid.h;
            let p = pa + step * t;
            // Where the bounds cut the surface the cap's normal is not the field's: take
            // the triangles' (see fix_degenerate_normals).
            let mut end = g;
            end[axis] += 1;
            let normal = if grid.on_wall(g) || grid.on_wall(end) {
                Vec3::ZERO
            } else {
                let g: Vec3 = local.iter().map(|q| q.gradient(p)).sum();
                (-g).try_normalize().unwrap_or(Vec3::ZERO)
            };
            mesh.positions.push(p);
            mesh.normals.push(normal);
            (mesh.positions.len() - 1) as u32
        })
    }
}

/// Vertices where the gradient vanished (a saddle exactly on the surface) or whose edge
/// touches a wall of the bounds (where the mesh is closed by a cut) take the average normal
/// of their triangles.
fn fix_degenerate_normals(mesh: &mut Mesh) {
    if mesh.normals.iter().all(|n| *n != Vec3::ZERO) {
        return;
    }
    let mut acc = vec![Vec3::ZERO; mesh.positions.len()];
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            acc[i as usize] += n;
        }
    }
    for (n, a) in mesh.normals.iter_mut().zip(acc) {
        if *n == Vec3::ZERO {
            *n = a.try_normalize().unwrap_or(Vec3::Y);
        }
    }
}

#[cfg(test)]
mod tests {
    use pge_engine::math;
    use std::collections::HashMap;

    use super::*;

    fn extract(field: &Metaballs, resolution: u32) -> (Mesh, MarchStats) {
        MarchingCubes::new(MarchOptions {
            resolution,
            ..MarchOptions::default()
        })
        .expect("valid options")
        .polygonize(field, &mut || false)
        .expect("extracts")
    }

    /// Asserts every undirected edge (by vertex index) is used by exactly two triangles, once
    /// in each direction (closed and consistently oriented).
    fn assert_closed(mesh: &Mesh) {
        let mut uses: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
        for t in mesh.indices.chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let e = uses.entry((a.min(b), a.max(b))).or_insert((0, 0));
                if a < b { e.0 += 1 } else { e.1 += 1 }
            }
        }
        assert!(!uses.is_empty());
        for (edge, (fwd, back)) in uses {
            assert_eq!(
                (fwd, back),
                (1, 1),
                "edge {edge:?} is not shared by exactly two triangles"
            );
        }
    }

    fn volume(mesh: &Mesh) -> f64 {
        mesh.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize].as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn one_ball_is_closed_with_the_sphere_volume() {
        let mut field = Metaballs::new(1.0);
        field
            .add_particle(Vec3::new(0.3, -0.2, 0.1), 1.0, None)
            .expect("ok");
        let (mesh, stats) = extract(&field, 96);
        mesh.validate().expect("valid");
        assert_closed(&mesh);
        let s = (1.0f64 - math::cbrt(0.5f64)).sqrt();
        let analytic = 4.0 / 3.0 * std::f64::consts::PI * s * s * s;
        let v = volume(&mesh);
        assert!(
            (v - analytic).abs() / analytic < 0.02,
            "volume {v} vs {analytic}"
        );
        // Normals come from the gradient: on a sphere, radial.
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            let radial = (*p - Vec3::new(0.3, -0.2, 0.1)).normalize();
            assert!(n.dot(radial) > 0.999, "normal {n} at {p}");
        }
        // The surface takes a thin shell of the grid.
        assert!(stats.visited_cells * 2 < stats.grid_cells, "{stats:?}");
    }

    #[test]
    fn many_balls_with_negative_charges_stay_closed() {
        // A deterministic pseudo-random cloud, dense enough for ambiguous faces.
        let mut field = Metaballs::new(0.6);
        let mut s = 12345u32;
        let mut next = || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1u32 << 24) as f32
        };
        for i in 0..60 {
            let p = Vec3::new(next(), next(), next()) * 3.0;
            let charge = if i % 5 == 0 { -0.8 } else { 1.0 };
            field
                .add_particle(p, charge, Some(0.4 + next() * 0.5))
                .expect("ok");
        }
        for res in [17, 40, 63] {
            let (mesh, _) = extract(&field, res);
            assert!(mesh.triangle_count() > 0);
            mesh.validate().expect("valid");
            assert_closed(&mesh);
            assert!(volume(&mesh) > 0.0, "outward orientation");
        }
    }

    #[test]
    fn bounds_cut_the_surface_and_close_it() {
        let mut field = Metaballs::new(1.0);
        field.add_particle(Vec3::ZERO, 1.0, None).expect("ok");
        let (mesh, _) = MarchingCubes::new(MarchOptions {
            resolution: 20,
            bounds: Some((Vec3::new(-1.0, 0.0, -1.0), Vec3::ONE)),
            ..MarchOptions::default()
        })
        .expect("ok")
        .polygonize(&field, &mut || false)
        .expect("ok");
        assert_closed(&mesh);
        assert!(mesh.positions.iter().all(|p| p.y >= -1e-6));
        // The cut: vertices in the first layer of cells get their triangles' normals, which
        // lean downwards; the rest keep the field's (radial).
        let h = 2.0 / 20.0;
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            if p.y < h * 0.999 {
                assert!(n.y < 0.0, "cap normal {n} at {p}");
            } else {
                assert!(n.dot(p.normalize()) > 0.99, "normal {n} at {p}");
            }
        }
    }

    #[test]
    fn bad_options_and_limits() {
        let opts = |f: fn(&mut MarchOptions)| {
            let mut o = MarchOptions::default();
            f(&mut o);
            MarchingCubes::new(o).err()
        };
        assert_eq!(
            opts(|o| o.resolution = 0),
            Some(MarchError::BadResolution(0))
        );
        assert_eq!(opts(|o| o.iso = 0.0), Some(MarchError::BadIso(0.0)));
        assert_eq!(
            opts(|o| o.iso = f32::NAN).map(|e| e.to_string().contains("iso")),
            Some(true)
        );
        assert_eq!(
            opts(|o| o.bounds = Some((Vec3::ONE, Vec3::ZERO))),
            Some(MarchError::BadBounds)
        );
        let mut field = Metaballs::new(1.0);
        field.add_particle(Vec3::ZERO, 1.0, None).expect("ok");
        let mc = MarchingCubes::new(MarchOptions {
            resolution: 1000,
            max_cells: 1 << 20,
            ..MarchOptions::default()
        })
        .expect("ok");
        assert!(matches!(
            mc.polygonize(&field, &mut || false),
            Err(MarchError::GridTooLarge { .. })
        ));
        let mc = MarchingCubes::new(MarchOptions {
            resolution: 200,
            max_bytes: 1 << 16,
            ..MarchOptions::default()
        })
        .expect("ok");
        assert!(matches!(
            mc.polygonize(&field, &mut || false),
            Err(MarchError::MemoryLimit { .. })
        ));
        let mc = MarchingCubes::new(MarchOptions::default()).expect("ok");
        assert_eq!(
            mc.polygonize(&field, &mut || true).err(),
            Some(MarchError::Interrupted)
        );
        // No particles: an empty mesh, not an error.
        let (mesh, _) = mc
            .polygonize(&Metaballs::new(1.0), &mut || false)
            .expect("ok");
        assert_eq!(mesh.vertex_count(), 0);
    }

    #[test]
    fn far_away_particles_do_not_overflow() {
        let mut field = Metaballs::new(1.0);
        field.add_particle(Vec3::ZERO, 1.0, None).expect("ok");
        field
            .add_particle(Vec3::new(-3.0e38, 0.0, 0.0), 1.0, None)
            .expect("ok");
        let (mesh, _) = MarchingCubes::new(MarchOptions {
            resolution: 16,
            bounds: Some((Vec3::splat(-1.0), Vec3::ONE)),
            ..MarchOptions::default()
        })
        .expect("ok")
        .polygonize(&field, &mut || false)
        .expect("the far particle is simply outside the grid");
        assert!(mesh.triangle_count() > 0);
    }

    #[test]
    fn output_is_deterministic() {
        let mut field = Metaballs::new(1.0);
        field.add_particle(Vec3::ZERO, 1.0, None).expect("ok");
        field
            .add_particle(Vec3::new(0.7, 0.1, 0.0), 0.8, None)
            .expect("ok");
        let (a, _) = extract(&field, 40);
        let (b, _) = extract(&field, 40);
        assert_eq!(a, b);
    }
}
