//! The texture atlas of leaf clusters (seed 003 §2.4.3 "Generación del atlas de textura"):
//! one cell with the single leaf, larger than the others because the finest levels are seen
//! from closest, and cells showing clusters of leaves with different counts and densities
//! (the leaves' area over the cell's), rendered procedurally from the leaf texture with
//! random placements. A collapsed leaf takes the cell that best matches how many leaves it
//! stands for and how densely they cover it, so coarse levels show clusters, not giant
//! leaves.

use std::sync::Arc;

use glam::Vec2;
use pge_engine::geometry::{GeometryError, Texture};
use rand_mt::Mt64;

/// Side of the atlas in pixels.
pub const ATLAS_SIZE: u32 = 512;
/// Leaf counts the cluster cells show.
pub const CLUSTER_COUNTS: [u32; 4] = [2, 4, 8, 16];
/// Densities the cluster cells show.
pub const CLUSTER_DENSITIES: [f32; 3] = [0.3, 0.55, 0.8];

/// One cell of the atlas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    /// Texture coordinates of the cell's corner at `(u, v) = (0, 0)`.
    pub min: Vec2,
    /// Texture coordinates of the opposite corner.
    pub max: Vec2,
    /// Leaves shown (1 for the single leaf).
    pub count: u32,
    /// Leaf area over cell area the cell was drawn with (the single leaf: 1).
    pub density: f32,
}

impl Cell {
    /// Maps texture coordinates of the whole leaf texture into this cell.
    #[must_use]
    pub fn map(&self, uv: Vec2) -> Vec2 {
        self.min + (self.max - self.min) * uv
    }
}

/// The atlas texture and its cells; cell 0 is the single leaf.
#[derive(Clone, Debug, PartialEq)]
pub struct Atlas {
    /// The RGBA texture (PNG) to put in the leaf material.
    pub texture: Arc<Texture>,
    /// The cells: the single leaf, then one per count of [`CLUSTER_COUNTS`] and density
    /// of [`CLUSTER_DENSITIES`], counts outermost.
    pub cells: Vec<Cell>,
}

impl Atlas {
    /// Builds the atlas from the leaf texture (any size; alpha is the silhouette). The
    /// same texture gives the same atlas, bytes included.
    pub fn new(leaf: &Texture) -> Result<Atlas, GeometryError> {
        let img = image::load_from_memory_with_format(&leaf.png, image::ImageFormat::Png)
            .map_err(|e| GeometryError::Texture(e.to_string()))?
            .to_rgba8();
        let sprite = Sprite {
            width: img.width(),
            height: img.height(),
            rgba: img.into_raw(),
        };
        let n = ATLAS_SIZE as usize;
        let mut rgba = vec![0u8; n * n * 4];
        let half = ATLAS_SIZE / 2;
        let quarter = ATLAS_SIZE / 4;
        let mut rects = vec![(0, 0, half)];
        for (qx, qy) in [(half, 0), (0, half), (half, half)] {
            for k in 0..4 {
                rects.push((qx + (k % 2) * quarter, qy + (k / 2) * quarter, quarter));
            }
        }
        let mut cells = Vec::with_capacity(rects.len());
        for (i, &(x0, y0, size)) in rects.iter().enumerate() {
            let (count, density) = if i == 0 {
                (1, 1.0)
            } else {
                let k = i - 1;
                (
                    CLUSTER_COUNTS[k / CLUSTER_DENSITIES.len()],
                    CLUSTER_DENSITIES[k % CLUSTER_DENSITIES.len()],
                )
            };
            let placements = if i == 0 {
                vec![Placement {
                    center: Vec2::splat(0.5),
                    size: 1.0,
                    angle: 0.0,
                    shade: 1.0,
                }]
            } else {
                cluster(count, density, sprite.coverage(), i as u64)
            };
            draw(&mut rgba, n, (x0, y0, size), &sprite, &placements);
            // Half a texel inside, so that filtering never reads the neighbouring cell.
            let inset = 0.5 / ATLAS_SIZE as f32;
            let s = ATLAS_SIZE as f32;
            cells.push(Cell {
                min: Vec2::new(x0 as f32 / s + inset, y0 as f32 / s + inset),
                max: Vec2::new(
                    (x0 + size) as f32 / s - inset,
                    (y0 + size) as f32 / s - inset,
                ),
                count,
                density,
            });
        }
        let texture = Texture::from_rgba("leaf atlas", ATLAS_SIZE, ATLAS_SIZE, &rgba)?;
        Ok(Atlas {
            texture: Arc::new(texture),
            cells,
        })
    }

    /// The cell for a leaf standing for `count` original leaves that cover `density` of its
    /// area: the single leaf for one, otherwise the cluster whose count is nearest on a log
    /// scale, then whose density is nearest.
    #[must_use]
    pub fn cell_for(&self, count: u32, density: f32) -> &Cell {
        if count <= 1 || self.cells.len() < 2 {
            return &self.cells[0];
        }
        let log = (count as f32).log2();
        let nearest_count = (0..CLUSTER_COUNTS.len())
            .min_by(|&a, &b| {
                let da = ((CLUSTER_COUNTS[a] as f32).log2() - log).abs();
                let db = ((CLUSTER_COUNTS[b] as f32).log2() - log).abs();
                da.total_cmp(&db)
            })
            .unwrap_or(0);
        let density = if density.is_finite() { density } else { 1.0 };
        let nearest_density = (0..CLUSTER_DENSITIES.len())
            .min_by(|&a, &b| {
                (CLUSTER_DENSITIES[a] - density)
                    .abs()
                    .total_cmp(&(CLUSTER_DENSITIES[b] - density).abs())
            })
            .unwrap_or(0);
        let index = 1 + nearest_count * CLUSTER_DENSITIES.len() + nearest_density;
        self.cells.get(index).unwrap_or(&self.cells[0])
    }
}

struct Sprite {
    width: u32,
    height: u32,
    rgba: Vec<u8>,
}

impl Sprite {
    /// The pixel at texture coordinates `uv` in `[0, 1)²` (nearest).
    fn at(&self, uv: Vec2) -> [u8; 4] {
        let x = ((uv.x * self.width as f32) as u32).min(self.width.saturating_sub(1));
        let y = ((uv.y * self.height as f32) as u32).min(self.height.saturating_sub(1));
        let i = (y as usize * self.width as usize + x as usize) * 4;
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }

    /// The fraction of the texture inside the silhouette (alpha at least half).
    fn coverage(&self) -> f32 {
        let pixels = (self.width as usize * self.height as usize).max(1);
        let inside = self.rgba.chunks_exact(4).filter(|p| p[3] >= 128).count();
        (inside as f32 / pixels as f32).max(0.05)
    }
}

/// One leaf drawn in a cell: its centre and size in cell units, its rotation and a shade.
struct Placement {
    center: Vec2,
    size: f32,
    angle: f32,
    shade: f32,
}

/// `count` leaves whose silhouettes add up to about `density` of the cell: each of side
/// `sqrt(density / (count * coverage))`, at random places inside the cell, pointing up within
/// ±50 degrees, each a little darker or lighter. Seeded by the cell, so the atlas never
/// changes.
fn cluster(count: u32, density: f32, coverage: f32, seed: u64) -> Vec<Placement> {
    let mut rng = Mt64::new(0x5eed_a71a5 ^ seed);
    let mut uniform = move || ((rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64) as f32;
    let size = (density / (count as f32 * coverage))
        .sqrt()
        .clamp(0.15, 1.0);
    (0..count)
        .map(|_| {
            let lo = 0.5 * size * 0.8;
            let hi = (1.0 - lo).max(lo);
            Placement {
                center: Vec2::new(lo + (hi - lo) * uniform(), lo + (hi - lo) * uniform()),
                size,
                angle: (uniform() - 0.5) * 100f32.to_radians(),
                shade: 0.82 + 0.18 * uniform(),
            }
        })
        .collect()
}

/// Draws the placements into the cell `(x0, y0, size)` of an `n`-pixel-wide RGBA image,
/// later ones over earlier ones where their silhouette is opaque.
fn draw(
    rgba: &mut [u8],
    n: usize,
    (x0, y0, size): (u32, u32, u32),
    sprite: &Sprite,
    placements: &[Placement],
) {
    for py in 0..size {
        for px in 0..size {
            let p = Vec2::new(
                (px as f32 + 0.5) / size as f32,
                (py as f32 + 0.5) / size as f32,
            );
            let i = ((y0 + py) as usize * n + (x0 + px) as usize) * 4;
            for leaf in placements {
                let (sin, cos) = leaf.angle.sin_cos();
                let d = p - leaf.center;
                let local = Vec2::new(cos * d.x + sin * d.y, -sin * d.x + cos * d.y) / leaf.size
                    + Vec2::splat(0.5);
                if !(0.0..1.0).contains(&local.x) || !(0.0..1.0).contains(&local.y) {
                    continue;
                }
                let texel = sprite.at(local);
                if texel[3] >= 128 {
                    for c in 0..3 {
                        rgba[i + c] = (f32::from(texel[c]) * leaf.shade) as u8;
                    }
                    rgba[i + 3] = 255;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A leaf texture: an opaque disc on transparency.
    fn disc() -> Texture {
        let n = 32u32;
        let mut rgba = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let d = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) / n as f32 - Vec2::splat(0.5);
                let a = if d.length() < 0.4 { 255 } else { 0 };
                rgba.extend_from_slice(&[200, 220, 200, a]);
            }
        }
        Texture::from_rgba("leaf", n, n, &rgba).expect("png")
    }

    fn opaque_fraction(atlas: &Atlas, cell: &Cell) -> f32 {
        let img = image::load_from_memory(&atlas.texture.png)
            .expect("decode")
            .to_rgba8();
        let s = ATLAS_SIZE as f32;
        let (x0, y0) = ((cell.min.x * s) as u32, (cell.min.y * s) as u32);
        let (x1, y1) = ((cell.max.x * s) as u32, (cell.max.y * s) as u32);
        let mut inside = 0;
        for y in y0..=y1 {
            for x in x0..=x1 {
                inside += usize::from(img.get_pixel(x, y)[3] >= 128);
            }
        }
        inside as f32 / ((x1 - x0 + 1) * (y1 - y0 + 1)) as f32
    }

    #[test]
    fn cells_tile_the_atlas_and_denser_cells_cover_more() {
        let atlas = Atlas::new(&disc()).expect("atlas");
        assert_eq!(atlas.cells.len(), 13);
        assert_eq!((atlas.texture.width, atlas.texture.height), (512, 512));
        let leaf = &atlas.cells[0];
        assert!((leaf.max.x - leaf.min.x) > 0.49);
        // The single-leaf cell is the disc: about pi * 0.4^2 of it is opaque.
        assert!((opaque_fraction(&atlas, leaf) - 0.503).abs() < 0.05);
        for count in CLUSTER_COUNTS {
            let sparse = atlas.cell_for(count, 0.2);
            let dense = atlas.cell_for(count, 0.9);
            assert_eq!((sparse.count, dense.count), (count, count));
            assert!(opaque_fraction(&atlas, dense) > opaque_fraction(&atlas, sparse));
        }
        assert_eq!(Atlas::new(&disc()).expect("again"), atlas);
    }

    #[test]
    fn cells_are_chosen_by_count_then_density() {
        let atlas = Atlas::new(&disc()).expect("atlas");
        assert_eq!(atlas.cell_for(1, 0.1).count, 1);
        assert_eq!(atlas.cell_for(3, 0.5).count, 4);
        assert_eq!(atlas.cell_for(1000, 0.5).count, 16);
        assert_eq!(atlas.cell_for(6, 0.8).density, 0.8);
        assert_eq!(atlas.cell_for(6, f32::NAN).density, 0.8);
        let c = atlas.cell_for(2, 0.3);
        assert_eq!(c.map(Vec2::ZERO), c.min);
        assert_eq!(c.map(Vec2::ONE), c.max);
    }
}
