//! The texture atlas of leaf clusters (seed 003 §2.4.3 "Generación del atlas de textura"):
//! one cell with the single leaf, larger than the others because the finest levels are seen
//! from closest, and cells showing clusters of leaves with different counts and densities
//! (the leaves' area over the cell's), rendered procedurally from the leaf texture with
//! random placements. A collapsed leaf takes the cell that best matches how many leaves it
//! stands for and how densely they cover it, so coarse levels show clusters, not giant
//! leaves. The leaf's normal and metallic-roughness maps get atlases of their own, drawn with
//! the same placements, so that the three line up.

use pge_engine::math;
use std::sync::Arc;

use glam::Vec2;
use pge_engine::geometry::{GeometryError, ImageFormat, Texture};
use rand_mt::Mt64;

use crate::mask;

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

/// The atlas textures and their cells; cell 0 is the single leaf. The normal and
/// metallic-roughness atlases, when made, show the same leaves at the same pixels as the
/// colour atlas, so one set of texture coordinates serves all three.
#[derive(Clone, Debug, PartialEq)]
pub struct Atlas {
    /// The RGBA texture (PNG) to put in the leaf material.
    pub texture: Arc<Texture>,
    /// The tangent-space normal atlas (RGB PNG, +Y up in the image), when the leaf had a
    /// normal map: each leaf's normals turned with the leaf, the flat normal elsewhere.
    pub normal: Option<Arc<Texture>>,
    /// The metallic-roughness atlas (RGB PNG), when the leaf had a metallic-roughness map:
    /// the leaf's texels, elsewhere the mean of the texels inside its silhouette.
    pub roughness: Option<Arc<Texture>>,
    /// The cells: the single leaf, then one per count of [`CLUSTER_COUNTS`] and density
    /// of [`CLUSTER_DENSITIES`], counts outermost.
    pub cells: Vec<Cell>,
    /// The alpha cutoff the atlas is drawn with, chosen with its texture
    /// ([`crate::mask::choose_cutoff`]): the atlas' mean alpha stays at least
    /// [`crate::mask::MARGIN`] above it, so a client's own mipmaps keep the clusters.
    pub alpha_cutoff: f32,
}

impl Atlas {
    /// Builds the colour atlas from the leaf texture (any size; alpha is the silhouette),
    /// without normal or roughness atlases. The same texture gives the same atlas, bytes
    /// included.
    pub fn new(leaf: &Texture) -> Result<Atlas, GeometryError> {
        Atlas::with_maps(leaf, None, None)
    }

    /// Builds the colour atlas from the leaf texture and, for each of the leaf's normal and
    /// metallic-roughness maps given (any size each, covering the same leaf), the atlas of
    /// that map: the placements are drawn once and every layer is drawn with them, so the
    /// three atlases line up texel for texel and share the colour atlas' coverage (a pixel
    /// is a leaf's where the colour texture's alpha is at least half). The same textures
    /// give the same atlases, bytes included.
    pub fn with_maps(
        leaf: &Texture,
        normal: Option<&Texture>,
        roughness: Option<&Texture>,
    ) -> Result<Atlas, GeometryError> {
        let sprite = Sprite::decode(leaf)?;
        let normal = normal.map(Sprite::decode).transpose()?;
        let roughness = roughness.map(Sprite::decode).transpose()?;
        let n = ATLAS_SIZE as usize;
        let mut layers = Layers {
            rgba: vec![0u8; n * n * 4],
            normal: normal.as_ref().map(|_| FLAT_NORMAL.repeat(n * n)),
            roughness: roughness
                .as_ref()
                .map(|r| r.mean_inside(&sprite).repeat(n * n)),
        };
        let maps = Maps {
            color: &sprite,
            normal: normal.as_ref(),
            roughness: roughness.as_ref(),
        };
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
            draw(&mut layers, n, (x0, y0, size), &maps, &placements);
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
        let alpha = mask::alpha_of(&layers.rgba);
        let alpha_cutoff = match mask::choose_cutoff(&alpha, n, n) {
            Some(c) => c,
            None => {
                // Clusters too sparse for any cutoff (a leaf texture of a few texels):
                // thickened until the lowest cutoff keeps them.
                let lowest = mask::CUTOFFS[mask::CUTOFFS.len() - 1];
                mask::widen_alpha(&mut layers.rgba, n, n, lowest + mask::MARGIN);
                lowest
            }
        };
        // Between the leaves, the colour of the nearest leaf: no halo in filtered levels.
        mask::dilate_color(&mut layers.rgba, n, n, 128);
        let texture = Texture::from_rgba("leaf atlas", ATLAS_SIZE, ATLAS_SIZE, &layers.rgba)?;
        let rgb = |name: &str, pixels: Option<Vec<u8>>| {
            pixels
                .map(|px| {
                    Texture::from_pixels_fast(name, ATLAS_SIZE, ATLAS_SIZE, 3, &px).map(Arc::new)
                })
                .transpose()
        };
        Ok(Atlas {
            texture: Arc::new(texture),
            normal: rgb("leaf atlas normal", layers.normal)?,
            roughness: rgb("leaf atlas roughness", layers.roughness)?,
            cells,
            alpha_cutoff,
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
        let log = math::log2(count as f32);
        let nearest_count = (0..CLUSTER_COUNTS.len())
            .min_by(|&a, &b| {
                let da = (math::log2(CLUSTER_COUNTS[a] as f32) - log).abs();
                let db = (math::log2(CLUSTER_COUNTS[b] as f32) - log).abs();
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

/// The flat tangent-space normal, +Z, as normal-map bytes.
const FLAT_NORMAL: [u8; 3] = [128, 128, 255];

/// A decoded leaf map, RGBA.
struct Sprite {
    width: u32,
    height: u32,
    rgba: Vec<u8>,
}

impl Sprite {
    fn decode(texture: &Texture) -> Result<Sprite, GeometryError> {
        let format = match texture.format() {
            ImageFormat::Png => image::ImageFormat::Png,
            ImageFormat::Jpeg => image::ImageFormat::Jpeg,
        };
        let img = image::load_from_memory_with_format(&texture.encoded, format)
            .map_err(|e| GeometryError::Texture(format!("{}: {e}", texture.name)))?
            .to_rgba8();
        Ok(Sprite {
            width: img.width(),
            height: img.height(),
            rgba: img.into_raw(),
        })
    }

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

    /// The mean RGB of this map's pixels inside `silhouette`'s (rounded; all pixels when
    /// none is inside): what the atlas holds between leaves, so that filtering at a leaf's
    /// edge blends with values like the leaf's own.
    fn mean_inside(&self, silhouette: &Sprite) -> [u8; 3] {
        let mut sum = [0u64; 3];
        let mut count = 0u64;
        for pass in [true, false] {
            for y in 0..self.height {
                for x in 0..self.width {
                    let uv = Vec2::new(
                        (x as f32 + 0.5) / self.width as f32,
                        (y as f32 + 0.5) / self.height as f32,
                    );
                    if pass && silhouette.at(uv)[3] < 128 {
                        continue;
                    }
                    let i = (y as usize * self.width as usize + x as usize) * 4;
                    for (total, &b) in sum.iter_mut().zip(&self.rgba[i..i + 3]) {
                        *total += u64::from(b);
                    }
                    count += 1;
                }
            }
            if count > 0 {
                break;
            }
        }
        let count = count.max(1);
        sum.map(|s| ((s + count / 2) / count) as u8)
    }
}

/// The leaf's maps the atlas layers are drawn from.
struct Maps<'a> {
    color: &'a Sprite,
    normal: Option<&'a Sprite>,
    roughness: Option<&'a Sprite>,
}

/// The atlas' pixels: RGBA colour, and RGB normal and metallic-roughness layers when made.
struct Layers {
    rgba: Vec<u8>,
    normal: Option<Vec<u8>>,
    roughness: Option<Vec<u8>>,
}

/// A normal-map texel turned by `angle` as the leaf is: the drawn leaf is its texture
/// rotated by `angle` in image coordinates (rows growing downwards), so the normal's
/// `(x, y)`, whose +Y points up the image, turns by `-angle`; Z is kept.
fn rotate_normal(texel: [u8; 4], (sin, cos): (f32, f32)) -> [u8; 3] {
    let decode = |b: u8| f32::from(b) / 255.0 * 2.0 - 1.0;
    let encode = |v: f32| ((v.clamp(-1.0, 1.0) * 0.5 + 0.5) * 255.0 + 0.5) as u8;
    let (x, y) = (decode(texel[0]), decode(texel[1]));
    [
        encode(cos * x + sin * y),
        encode(-sin * x + cos * y),
        texel[2],
    ]
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

/// Draws the placements into the cell `(x0, y0, size)` of every layer of an `n`-pixel-wide
/// atlas, later ones over earlier ones where their silhouette (the colour's alpha) is
/// opaque: a pixel takes all its layers from the same leaf at the same texture coordinates.
fn draw(
    layers: &mut Layers,
    n: usize,
    (x0, y0, size): (u32, u32, u32),
    maps: &Maps,
    placements: &[Placement],
) {
    for py in 0..size {
        for px in 0..size {
            let p = Vec2::new(
                (px as f32 + 0.5) / size as f32,
                (py as f32 + 0.5) / size as f32,
            );
            let pixel = (y0 + py) as usize * n + (x0 + px) as usize;
            let i = pixel * 4;
            for leaf in placements {
                let (sin, cos) = math::sin_cos(leaf.angle);
                let d = p - leaf.center;
                let local = Vec2::new(cos * d.x + sin * d.y, -sin * d.x + cos * d.y) / leaf.size
                    + Vec2::splat(0.5);
                if !(0.0..1.0).contains(&local.x) || !(0.0..1.0).contains(&local.y) {
                    continue;
                }
                let texel = maps.color.at(local);
                if texel[3] >= 128 {
                    for (out, &b) in layers.rgba[i..i + 3].iter_mut().zip(&texel) {
                        *out = (f32::from(b) * leaf.shade) as u8;
                    }
                    layers.rgba[i + 3] = 255;
                    if let (Some(out), Some(map)) = (&mut layers.normal, maps.normal) {
                        out[pixel * 3..pixel * 3 + 3]
                            .copy_from_slice(&rotate_normal(map.at(local), (sin, cos)));
                    }
                    if let (Some(out), Some(map)) = (&mut layers.roughness, maps.roughness) {
                        out[pixel * 3..pixel * 3 + 3].copy_from_slice(&map.at(local)[..3]);
                    }
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
        let img = image::load_from_memory(&atlas.texture.encoded)
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

    /// A texture of `n`² pixels from a function of the pixel's centre in `[0, 1)²`.
    fn texture(name: &str, n: u32, pixel: impl Fn(Vec2) -> [u8; 4]) -> Texture {
        let mut rgba = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let uv = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) / n as f32;
                rgba.extend_from_slice(&pixel(uv));
            }
        }
        Texture::from_rgba(name, n, n, &rgba).expect("png")
    }

    fn decode(texture: &Texture) -> image::RgbaImage {
        image::load_from_memory(&texture.encoded)
            .expect("decode")
            .to_rgba8()
    }

    /// A normal-map byte triple's `(x, y)`, +Y up the image.
    fn normal_xy(p: &[u8]) -> Vec2 {
        Vec2::new(f32::from(p[0]), f32::from(p[1])) / 255.0 * 2.0 - Vec2::ONE
    }

    #[test]
    fn a_turned_leaf_has_its_normals_turned_with_it() {
        // Only the right half of the leaf is opaque, and its normals lean towards the right
        // (+X): wherever the leaf is turned, they must lean towards where that half went.
        let color = texture("leaf", 32, |uv| {
            [90, 160, 60, if uv.x > 0.5 { 255 } else { 0 }]
        });
        let normal = texture("normal", 32, |_| [230, 128, 220, 255]);
        let sprites = (
            Sprite::decode(&color).expect("color"),
            Sprite::decode(&normal).expect("normal"),
        );
        let maps = Maps {
            color: &sprites.0,
            normal: Some(&sprites.1),
            roughness: None,
        };
        let n = 64usize;
        for degrees in [0.0f32, 90.0, -90.0, 180.0, 35.0] {
            let mut layers = Layers {
                rgba: vec![0; n * n * 4],
                normal: Some(FLAT_NORMAL.repeat(n * n)),
                roughness: None,
            };
            let leaf = Placement {
                center: Vec2::splat(0.5),
                size: 0.7,
                angle: degrees.to_radians(),
                shade: 1.0,
            };
            draw(&mut layers, n, (0, 0, n as u32), &maps, &[leaf]);
            let normals = layers.normal.expect("normal layer");
            // Where the opaque half lies from the leaf's centre, +Y up the image.
            let (mut sum, mut count) = (Vec2::ZERO, 0);
            for y in 0..n {
                for x in 0..n {
                    if layers.rgba[(y * n + x) * 4 + 3] == 255 {
                        sum += Vec2::new(x as f32 + 0.5 - 32.0, 32.0 - (y as f32 + 0.5));
                        count += 1;
                        let tilt = normal_xy(&normals[(y * n + x) * 3..]);
                        assert!(tilt.length() > 0.7, "{degrees}: {tilt}");
                    }
                }
            }
            let side = (sum / count as f32).normalize();
            for y in 0..n {
                for x in 0..n {
                    let p = &normals[(y * n + x) * 3..(y * n + x) * 3 + 3];
                    if layers.rgba[(y * n + x) * 4 + 3] == 255 {
                        let tilt = normal_xy(p).normalize();
                        assert!(
                            tilt.dot(side) > 0.98,
                            "{degrees} degrees: the normal leans {tilt}, the half lies {side}"
                        );
                        assert_eq!(p[2], 220, "Z is kept");
                    } else {
                        assert_eq!(p, FLAT_NORMAL, "flat outside the leaf");
                    }
                }
            }
        }
    }

    #[test]
    fn the_three_layers_share_coverage_and_are_deterministic() {
        let color = disc();
        // A tilted normal everywhere (never flat, however turned) at another size; roughness
        // 60 on the left, 100 on the right, 250 outside the disc (at twice the disc's
        // resolution, each of its texels inside or outside as the disc's texel there).
        let normal = texture("normal", 16, |_| [200, 90, 225, 255]);
        let roughness = texture("roughness", 64, |uv| {
            let texel = ((uv * 32.0).floor() + Vec2::splat(0.5)) / 32.0;
            let inside = (texel - Vec2::splat(0.5)).length() < 0.4;
            let g = match (inside, uv.x < 0.5) {
                (false, _) => 250,
                (true, true) => 60,
                (true, false) => 100,
            };
            [0, g, 0, 255]
        });
        let atlas = Atlas::with_maps(&color, Some(&normal), Some(&roughness)).expect("atlas");
        let (c, nm, r) = (
            decode(&atlas.texture),
            decode(atlas.normal.as_deref().expect("normal atlas")),
            decode(atlas.roughness.as_deref().expect("roughness atlas")),
        );
        assert_eq!((nm.width(), r.width()), (ATLAS_SIZE, ATLAS_SIZE));
        // Between leaves, the mean roughness inside the leaf: about halfway.
        let fill = r.get_pixel(0, 0)[1];
        assert!((75..=85).contains(&fill), "{fill}");
        let mut covered = 0;
        for (x, y, p) in c.enumerate_pixels() {
            let (n, g) = (nm.get_pixel(x, y), r.get_pixel(x, y)[1]);
            if p[3] >= 128 {
                covered += 1;
                assert_ne!(&n.0[..3], &FLAT_NORMAL, "({x}, {y})");
                assert!(g == 60 || g == 100, "({x}, {y}): {g}");
            } else {
                assert_eq!((&n.0[..3], g), (&FLAT_NORMAL[..], fill), "({x}, {y})");
            }
        }
        assert!(covered > 512 * 512 / 8, "{covered}");
        // The colour atlas is the same with or without the maps, and the same textures give
        // the same bytes.
        let plain = Atlas::new(&color).expect("plain");
        assert_eq!(plain.texture, atlas.texture);
        assert_eq!((plain.normal, plain.roughness), (None, None));
        let again = Atlas::with_maps(&color, Some(&normal), Some(&roughness)).expect("again");
        assert_eq!(again, atlas);
        // A client's own mipmaps keep the clusters: the mean alpha is over the cutoff, and
        // between the leaves lies the leaves' colour, not black.
        let alpha: Vec<u8> = c.pixels().map(|p| p[3]).collect();
        assert!(crate::mask::mean_alpha(&alpha) >= atlas.alpha_cutoff + crate::mask::MARGIN);
        assert!(
            c.pixels().all(|p| p[0] >= 150),
            "no dark texel under a clear one"
        );
        // The single-leaf cell shows the leaf unturned: its normals are the leaf's.
        let cell = &atlas.cells[0];
        let centre = ((cell.map(Vec2::splat(0.5)) * ATLAS_SIZE as f32).as_uvec2()).to_array();
        assert_eq!(&nm.get_pixel(centre[0], centre[1]).0[..3], &[200, 90, 225]);
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
