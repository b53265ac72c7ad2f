//! The terrain: a heightfield from fBm noise or a greyscale image, centred on the origin, with
//! height and normal queries and a grid mesh whose vertices tiles share exactly.

use std::path::Path;
use std::sync::Arc;

use glam::{Vec2, Vec3};
use noise::{Fbm, MultiFractal, NoiseFn, Perlin};
use pge_engine::geometry::{Material, Mesh};
use pge_engine::math;

use crate::ForestError;

/// Bytes a terrain mesh holds per vertex (position, normal, texture coordinates, two
/// triangles' indices).
const TERRAIN_VERTEX_BYTES: u64 = 12 + 12 + 8 + 24;

/// A greyscale image read as values in [0, 1], sampled bilinearly (heights, density maps).
#[derive(Clone, Debug, PartialEq)]
pub struct Raster {
    width: usize,
    height: usize,
    values: Vec<f32>,
}

impl Raster {
    /// A raster from row-major values (row 0 is the −z edge of the world).
    pub fn new(width: usize, height: usize, values: Vec<f32>) -> Result<Raster, ForestError> {
        if width == 0 || height == 0 || values.len() != width * height {
            return Err(ForestError::Image {
                path: String::new(),
                message: format!("{width} x {height} image needs {} values", width * height),
            });
        }
        Ok(Raster {
            width,
            height,
            values,
        })
    }

    /// Reads a PNG (or any format the `image` crate was built with) as luminance in [0, 1]
    /// (16-bit images keep their precision).
    pub fn load(path: &Path) -> Result<Raster, ForestError> {
        let shown = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|e| ForestError::Image {
            path: shown.clone(),
            message: e.to_string(),
        })?;
        Raster::decode(&shown, &bytes)
    }

    /// [`Raster::load`] of an image file's bytes (read by the caller; `shown` names the
    /// file in errors), its format found from its contents.
    pub fn decode(shown: &str, bytes: &[u8]) -> Result<Raster, ForestError> {
        let shown = shown.to_string();
        let img = image::load_from_memory(bytes).map_err(|e| ForestError::Image {
            path: shown.clone(),
            message: e.to_string(),
        })?;
        let grey = img.to_luma16();
        let (w, h) = grey.dimensions();
        let values = grey.pixels().map(|p| f32::from(p.0[0]) / 65535.0).collect();
        Raster::new(w as usize, h as usize, values).map_err(|_| ForestError::Image {
            path: shown,
            message: "the image is empty".into(),
        })
    }

    /// The value at `(u, v)` in [0, 1]² (clamped), bilinear between pixel centres.
    #[must_use]
    pub fn sample(&self, u: f64, v: f64) -> f64 {
        let fx = (u.clamp(0.0, 1.0) * (self.width - 1) as f64).max(0.0);
        let fy = (v.clamp(0.0, 1.0) * (self.height - 1) as f64).max(0.0);
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
        let at = |x: usize, y: usize| f64::from(self.values[y * self.width + x]);
        let top = at(x0, y0) * (1.0 - tx) + at(x1, y0) * tx;
        let bottom = at(x0, y1) * (1.0 - tx) + at(x1, y1) * tx;
        top * (1.0 - ty) + bottom * ty
    }
}

/// fBm relief options (`forest:terrain{ height, scale, octaves, ... }`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FbmOptions {
    /// Height amplitude in metres: heights lie roughly in [−height, height].
    pub height: f64,
    /// Horizontal size of the largest hills, metres.
    pub scale: f64,
    /// Octaves of noise (1..=16).
    pub octaves: usize,
    /// Frequency factor between octaves.
    pub lacunarity: f64,
    /// Amplitude factor between octaves.
    pub persistence: f64,
}

impl Default for FbmOptions {
    fn default() -> Self {
        FbmOptions {
            height: 20.0,
            scale: 300.0,
            octaves: 5,
            lacunarity: 2.0,
            persistence: 0.5,
        }
    }
}

#[derive(Clone, Debug)]
enum Relief {
    Flat,
    Fbm {
        noise: Box<Fbm<Perlin>>,
        options: FbmOptions,
    },
    Image {
        raster: Arc<Raster>,
        height: f64,
    },
}

/// A heightfield over `size[0]` x `size[1]` metres centred on the origin (x by z).
#[derive(Clone, Debug)]
pub struct Terrain {
    size: [f64; 2],
    relief: Relief,
    resolution: f64,
}

/// The vertex grid of a terrain: vertex `k` along x is at `x0 + k * step`, the last one on
/// the world's edge. Tiles use the same global indices, so they share border vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// Metres between vertices.
    pub step: f64,
    /// Vertex index of the last vertex along x and along z.
    pub last: [usize; 2],
    /// Vertices per tile edge (when tiled).
    pub per_tile: Option<usize>,
}

impl Terrain {
    /// A flat terrain of `size` metres.
    #[must_use]
    pub fn flat(size: [f64; 2]) -> Terrain {
        Terrain {
            size,
            relief: Relief::Flat,
            resolution: 4.0,
        }
    }

    /// fBm noise seeded by `seed`.
    #[must_use]
    pub fn fbm(size: [f64; 2], options: FbmOptions, seed: u64) -> Terrain {
        let noise = Fbm::<Perlin>::new(seed as u32)
            .set_octaves(options.octaves.clamp(1, 16))
            .set_frequency(1.0)
            .set_lacunarity(options.lacunarity)
            .set_persistence(options.persistence);
        Terrain {
            size,
            relief: Relief::Fbm {
                noise: Box::new(noise),
                options,
            },
            resolution: 4.0,
        }
    }

    /// A greyscale image stretched over the world: black is 0 m, white is `height` metres;
    /// the image's top row is the −z edge.
    #[must_use]
    pub fn image(size: [f64; 2], raster: Arc<Raster>, height: f64) -> Terrain {
        Terrain {
            size,
            relief: Relief::Image { raster, height },
            resolution: 4.0,
        }
    }

    /// Sets the wanted distance between mesh vertices (metres, default 4).
    #[must_use]
    pub fn with_resolution(mut self, metres: f64) -> Terrain {
        self.resolution = metres;
        self
    }

    /// The world's size in metres, x by z.
    #[must_use]
    pub fn size(&self) -> [f64; 2] {
        self.size
    }

    /// The height at `(x, z)`.
    #[must_use]
    pub fn height(&self, x: f64, z: f64) -> f64 {
        match &self.relief {
            Relief::Flat => 0.0,
            Relief::Fbm { noise, options } => {
                options.height * noise.get([x / options.scale, z / options.scale])
            }
            Relief::Image { raster, height } => {
                let u = (x + 0.5 * self.size[0]) / self.size[0];
                let v = (z + 0.5 * self.size[1]) / self.size[1];
                height * raster.sample(u, v)
            }
        }
    }

    /// The unit normal at `(x, z)` (central differences half a grid step apart, never
    /// farther than the world is wide).
    #[must_use]
    pub fn normal(&self, x: f64, z: f64) -> Vec3 {
        // A `resolution` past the world's size makes one cell; half of it would sample far
        // outside the world, where the noise's lattice index no longer fits an integer.
        let widest = self.size[0].abs().max(self.size[1].abs());
        let e = 0.5 * self.resolution.min(widest).max(0.01);
        let dx = (self.height(x + e, z) - self.height(x - e, z)) / (2.0 * e);
        let dz = (self.height(x, z + e) - self.height(x, z - e)) / (2.0 * e);
        Vec3::new(-dx as f32, 1.0, -dz as f32).normalize()
    }

    /// The slope at `(x, z)` in degrees (0 = flat).
    #[must_use]
    pub fn slope_degrees(&self, x: f64, z: f64) -> f64 {
        math::acos(f64::from(self.normal(x, z).y.clamp(-1.0, 1.0))).to_degrees()
    }

    /// The vertex grid; with `tile`, the step divides the tile exactly.
    #[must_use]
    pub fn grid(&self, tile: Option<f64>) -> Grid {
        let res = self.resolution.max(0.01);
        let (step, per_tile) = match tile {
            Some(t) => {
                let n = (t / res).ceil().max(1.0) as usize;
                (t / n as f64, Some(n))
            }
            None => (res, None),
        };
        let last = |s: f64| ((s / step) - 1e-9).ceil().max(1.0) as usize;
        Grid {
            step,
            last: [last(self.size[0]), last(self.size[1])],
            per_tile,
        }
    }

    fn vertex_x(&self, grid: &Grid, k: usize, axis: usize) -> f64 {
        let x0 = -0.5 * self.size[axis];
        if k >= grid.last[axis] {
            x0 + self.size[axis]
        } else {
            x0 + k as f64 * grid.step
        }
    }

    /// Checks that the mesh of the vertices `kx.0..=kx.1` by `kz.0..=kz.1` (of a [`Grid`]) can be
    /// made, before it is: its vertices numbered by 32-bit indices (else an error naming
    /// `resolution`) and its buffers within `budget` (else an
    /// [`pge_engine::Error::MemoryLimit`] at `at` naming `resolution`, in
    /// [`ForestError::Script`]).
    pub fn check_mesh(
        &self,
        kx: (usize, usize),
        kz: (usize, usize),
        budget: &pge_engine::Budget,
        at: &pge_engine::Location,
    ) -> Result<(), ForestError> {
        let side = |k: (usize, usize)| (k.1.saturating_sub(k.0) as u64).saturating_add(1);
        let (nx, nz) = (side(kx), side(kz));
        let vertices = nx.saturating_mul(nz);
        if vertices > u64::from(u32::MAX) {
            return Err(ForestError::Option {
                option: "resolution",
                message: format!(
                    "{} m makes a terrain mesh of {nx} x {nz} vertices, more than a mesh holds (4294967295): raise resolution or use tiles",
                    self.resolution
                ),
            });
        }
        let bytes = vertices.saturating_mul(TERRAIN_VERTEX_BYTES);
        budget
            .check(bytes, at, || {
                format!(
                    "the terrain mesh ({nx} x {nz} vertices at resolution = {} m) needs {} MiB",
                    self.resolution,
                    bytes.div_ceil(1 << 20)
                )
            })
            .map_err(ForestError::Script)
    }

    /// The mesh of the vertices `kx.0..=kx.1` by `kz.0..=kz.1` of `grid` (named `terrain`).
    #[must_use]
    pub fn mesh(&self, grid: &Grid, kx: (usize, usize), kz: (usize, usize)) -> Mesh {
        match self.mesh_checked(grid, kx, kz, &mut || Ok::<(), std::convert::Infallible>(())) {
            Ok(mesh) => mesh,
            Err(never) => match never {},
        }
    }

    /// [`Terrain::mesh`], calling `check` before each row of vertices and of triangles (a
    /// fine terrain's rows are the long part of a forest's assembly): its error stops the
    /// mesh.
    pub fn mesh_checked<E>(
        &self,
        grid: &Grid,
        kx: (usize, usize),
        kz: (usize, usize),
        check: &mut dyn FnMut() -> Result<(), E>,
    ) -> Result<Mesh, E> {
        let (nx, nz) = (kx.1 - kx.0 + 1, kz.1 - kz.0 + 1);
        let mut positions = Vec::with_capacity(nx * nz);
        let mut normals = Vec::with_capacity(nx * nz);
        let mut uvs = Vec::with_capacity(nx * nz);
        for l in kz.0..=kz.1 {
            check()?;
            let z = self.vertex_x(grid, l, 1);
            for k in kx.0..=kx.1 {
                let x = self.vertex_x(grid, k, 0);
                positions.push(Vec3::new(x as f32, self.height(x, z) as f32, z as f32));
                normals.push(self.normal(x, z));
                uvs.push(Vec2::new((x / 8.0) as f32, (z / 8.0) as f32));
            }
        }
        let mut indices = Vec::with_capacity((nx - 1) * (nz - 1) * 6);
        for l in 0..nz - 1 {
            check()?;
            for k in 0..nx - 1 {
                let a = (l * nx + k) as u32;
                let (b, c, d) = (a + 1, a + nx as u32, a + nx as u32 + 1);
                indices.extend_from_slice(&[a, c, b, b, c, d]);
            }
        }
        Ok(Mesh {
            name: "terrain".into(),
            positions,
            normals,
            uvs,
            indices,
            material: Arc::new(Material {
                name: "terrain".into(),
                base_color: [0.16, 0.21, 0.08, 1.0],
                roughness: 1.0,
                ..Material::default()
            }),
            ..Mesh::default()
        })
    }

    /// The vertex ranges of the whole world, or of tile `(i, j)` when the grid is tiled.
    #[must_use]
    pub fn patch(
        &self,
        grid: &Grid,
        tile: Option<(usize, usize)>,
    ) -> ((usize, usize), (usize, usize)) {
        match (tile, grid.per_tile) {
            (Some((i, j)), Some(n)) => (
                ((i * n).min(grid.last[0]), ((i + 1) * n).min(grid.last[0])),
                ((j * n).min(grid.last[1]), ((j + 1) * n).min(grid.last[1])),
            ),
            _ => ((0, grid.last[0]), (0, grid.last[1])),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fbm_heights_stay_near_the_amplitude_and_normals_point_up() {
        let t = Terrain::fbm([200.0, 200.0], FbmOptions::default(), 3);
        let mut max: f64 = 0.0;
        for i in 0..50 {
            let (x, z) = (i as f64 * 3.7 - 90.0, i as f64 * -2.9 + 70.0);
            max = max.max(t.height(x, z).abs());
            let n = t.normal(x, z);
            assert!((n.length() - 1.0).abs() < 1e-5 && n.y > 0.0);
        }
        assert!(
            max > 0.5 && max < 2.0 * FbmOptions::default().height,
            "{max}"
        );
    }

    #[test]
    fn a_resolution_far_wider_than_the_world_gives_one_cell_of_finite_normals() {
        // Found by the forest_options fuzz target: the normal sampled the noise half a
        // resolution (6e131 m) away, past the range of its lattice index (a panic).
        for resolution in [1.2e132, 9.3e242, 1e6] {
            let t =
                Terrain::fbm([30.0, 30.0], FbmOptions::default(), 1).with_resolution(resolution);
            let grid = t.grid(None);
            assert_eq!(grid.last, [1, 1]);
            let mesh = t.mesh(&grid, (0, 1), (0, 1));
            assert_eq!(mesh.positions.len(), 4);
            assert!(mesh.normals.iter().all(|n| n.is_finite() && n.y > 0.0));
        }
    }

    #[test]
    fn a_checked_mesh_checks_every_row_and_stops_at_an_error() {
        // A fine terrain's mesh is the long part of a forest's assembly: the run's deadline
        // is checked before each row of vertices and of triangles.
        let t = Terrain::fbm([100.0, 60.0], FbmOptions::default(), 2).with_resolution(2.0);
        let grid = t.grid(None);
        let (kx, kz) = t.patch(&grid, None);
        let rows = kz.1 - kz.0 + 1;
        let mut calls = 0;
        let mesh = t
            .mesh_checked(&grid, kx, kz, &mut || {
                calls += 1;
                Ok::<(), &str>(())
            })
            .expect("mesh");
        assert_eq!(calls, rows + rows - 1);
        assert_eq!(mesh, t.mesh(&grid, kx, kz));
        let mut calls = 0;
        let stopped = t.mesh_checked(&grid, kx, kz, &mut || {
            calls += 1;
            if calls == rows / 2 {
                Err("time limit")
            } else {
                Ok(())
            }
        });
        assert_eq!(stopped.err(), Some("time limit"));
        assert_eq!(calls, rows / 2, "no row after the error");
    }

    #[test]
    fn a_ramp_image_gives_its_slope() {
        // 100 m wide, rising 100 m from x = -50 to x = 50: 45 degrees.
        let raster = Raster::new(2, 2, vec![0.0, 1.0, 0.0, 1.0]).expect("raster");
        let t = Terrain::image([100.0, 100.0], Arc::new(raster), 100.0);
        assert!((t.height(-50.0, 0.0)).abs() < 1e-9);
        assert!((t.height(0.0, 10.0) - 50.0).abs() < 1e-9);
        assert!((t.slope_degrees(0.0, 0.0) - 45.0).abs() < 1e-3);
    }

    #[test]
    fn tile_patches_share_their_border_vertices() {
        let t = Terrain::fbm([100.0, 70.0], FbmOptions::default(), 9).with_resolution(3.0);
        let grid = t.grid(Some(40.0));
        assert_eq!(grid.per_tile, Some(14));
        let (ax, az) = t.patch(&grid, Some((0, 0)));
        let (bx, bz) = t.patch(&grid, Some((1, 0)));
        let a = t.mesh(&grid, ax, az);
        let b = t.mesh(&grid, bx, bz);
        let (anx, bnx) = (ax.1 - ax.0 + 1, bx.1 - bx.0 + 1);
        for row in 0..=(az.1 - az.0) {
            assert_eq!(a.positions[row * anx + anx - 1], b.positions[row * bnx]);
        }
        // The last tile stops at the world's edge.
        let (cx, _) = t.patch(&grid, Some((2, 1)));
        let c = t.mesh(&grid, cx, t.patch(&grid, Some((2, 1))).1);
        let max_x = c.positions.iter().map(|p| p.x).fold(f32::MIN, f32::max);
        assert_eq!(max_x, 50.0);
        assert!(a.normals.iter().all(|n| n.y > 0.0));
        a.validate().expect("valid mesh");
    }
}
