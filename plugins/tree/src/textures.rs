//! Procedural textures: bark from noise and an alpha-masked leaf silhouette, so a tree needs
//! no image files. Both are deterministic and cached per process (the same options give the
//! same `Arc<Texture>`), and both tile where they must: bark in `u` (around the branch) and
//! `v` (along it).

use std::collections::HashMap;
use std::f64::consts::TAU;
use std::path::Path;
use std::sync::{Arc, Mutex, OnceLock};

use noise::{NoiseFn, Perlin};
use pge_engine::geometry::Texture;

use crate::TreeError;
use crate::options::TextureSource;

/// Side of the procedural bark texture in pixels.
pub const BARK_SIZE: u32 = 128;
/// Side of the procedural leaf texture in pixels.
pub const LEAF_SIZE: u32 = 128;

#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum Key {
    Bark([u32; 4]),
    Leaf,
}

fn cache() -> &'static Mutex<HashMap<Key, Arc<Texture>>> {
    static CACHE: OnceLock<Mutex<HashMap<Key, Arc<Texture>>>> = OnceLock::new();
    CACHE.get_or_init(|| Mutex::new(HashMap::new()))
}

fn cached(
    key: Key,
    make: impl FnOnce() -> Result<Texture, TreeError>,
) -> Result<Arc<Texture>, TreeError> {
    if let Some(t) = cache().lock().ok().and_then(|c| c.get(&key).cloned()) {
        return Ok(t);
    }
    let t = Arc::new(make()?);
    if let Ok(mut c) = cache().lock() {
        c.insert(key, t.clone());
    }
    Ok(t)
}

/// The bark texture of `color` (linear RGBA): vertical furrows and plates from 4D Perlin
/// noise sampled on a torus, so it tiles in both directions. The grey pattern is computed
/// once per process; each colour only tints and encodes it.
pub fn bark_texture(color: [f32; 4]) -> Result<Arc<Texture>, TreeError> {
    cached(Key::Bark(color.map(f32::to_bits)), || {
        let shade = bark_shade();
        let mut rgba = Vec::with_capacity(shade.len() * 4);
        for s in shade {
            for c in &color[..3] {
                rgba.push(linear_to_srgb8(c * s));
            }
            rgba.push(255);
        }
        Ok(Texture::from_rgba("bark", BARK_SIZE, BARK_SIZE, &rgba)?)
    })
}

/// Perlin noise sampled on a `g x g` grid over the torus (`fu` cycles-ish around, `fv`
/// along), to be read back with [`wrapped`].
fn torus_grid(perlin: &Perlin, g: usize, fu: f64, fv: f64) -> Vec<f32> {
    let mut out = Vec::with_capacity(g * g);
    for y in 0..g {
        let b = TAU * y as f64 / g as f64;
        for x in 0..g {
            let a = TAU * x as f64 / g as f64;
            out.push(perlin.get([a.cos() * fu, a.sin() * fu, b.cos() * fv, b.sin() * fv]) as f32);
        }
    }
    out
}

/// Bilinear read of a `g x g` periodic grid at `(u, v)` in `[0, 1)`.
fn wrapped(grid: &[f32], g: usize, u: f32, v: f32) -> f32 {
    let (x, y) = (u * g as f32, v * g as f32);
    let (x0, y0) = (x.floor() as usize % g, y.floor() as usize % g);
    let (x1, y1) = ((x0 + 1) % g, (y0 + 1) % g);
    let (fx, fy) = (x.fract(), y.fract());
    let at = |x: usize, y: usize| grid[y * g + x];
    let top = at(x0, y0) + (at(x1, y0) - at(x0, y0)) * fx;
    let bottom = at(x0, y1) + (at(x1, y1) - at(x0, y1)) * fx;
    top + (bottom - top) * fy
}

/// The grey bark pattern, `BARK_SIZE` squared values around 1, computed once per process.
/// Noise is sampled on coarse periodic grids and interpolated (a few thousand noise calls
/// instead of one per pixel and octave), plus a per-pixel hashed grain.
fn bark_shade() -> &'static [f32] {
    static SHADE: OnceLock<Vec<f32>> = OnceLock::new();
    SHADE.get_or_init(|| {
        let n = BARK_SIZE as usize;
        let perlin = Perlin::new(7);
        // Around the branch the pattern changes fast, along it slowly: furrows.
        let furrows = torus_grid(&perlin, 32, 2.2, 0.6);
        let plates = torus_grid(&perlin, 48, 5.0, 3.0);
        let fine = torus_grid(&perlin, 64, 10.0, 8.0);
        let mut out = Vec::with_capacity(n * n);
        for y in 0..n {
            let v = y as f32 / n as f32;
            for x in 0..n {
                let u = x as f32 / n as f32;
                let furrow = (1.0 - wrapped(&furrows, 32, u, v).abs() * 2.0).max(0.0);
                let detail = wrapped(&plates, 48, u, v) * 0.5 + wrapped(&fine, 64, u, v) * 0.25;
                let hash = ((x as u32).wrapping_mul(0x9e37_79b1)
                    ^ (y as u32).wrapping_mul(0x85eb_ca77))
                .wrapping_mul(0xc2b2_ae3d);
                let grain = (hash >> 24) as f32 / 255.0 - 0.5;
                out.push(
                    (0.62 + 0.38 * furrow.powf(0.7) + 0.18 * detail + 0.06 * grain)
                        .clamp(0.15, 1.3),
                );
            }
        }
        out
    })
}

/// Half-width of the leaf blade at `t` along it (0 at the stalk end of the blade, 1 at the
/// tip), in texture units.
fn blade_half_width(t: f64) -> f64 {
    if !(0.0..=1.0).contains(&t) {
        return 0.0;
    }
    0.44 * (std::f64::consts::PI * t.powf(0.8)).sin().powf(0.85) * (1.0 - 0.25 * t)
}

/// The leaf texture: a light leaf silhouette (stalk at `v = 0`, tip at `v = 1`) with a
/// midrib and veins, alpha 255 inside and 0 outside for alpha masking. It is nearly white so
/// that each leaf's vertex colour gives its hue.
pub fn leaf_texture() -> Result<Arc<Texture>, TreeError> {
    cached(Key::Leaf, || {
        let n = LEAF_SIZE as usize;
        let perlin = Perlin::new(11);
        let mottles: Vec<f32> = (0..16 * 16)
            .map(|i| {
                perlin.get([(i % 16) as f64 * 9.0 / 16.0, (i / 16) as f64 * 9.0 / 16.0]) as f32
            })
            .collect();
        let mut rgba = Vec::with_capacity(n * n * 4);
        for y in 0..n {
            let v = (y as f64 + 0.5) / n as f64;
            let t = (v - 0.12) / 0.86;
            let edge = blade_half_width(t) * (1.0 + 0.06 * perlin.get([v * 40.0, 0.5]));
            for x in 0..n {
                let u = (x as f64 + 0.5) / n as f64;
                let across = (u - 0.5).abs();
                let stalk = v < 0.14 && across < 0.018;
                let inside = stalk || across < edge;
                let mottle = f64::from(wrapped(&mottles, 16, u as f32, v as f32)) * 0.06;
                let midrib = across < 0.012;
                let vein = ((v - across * 0.9) * 9.0).fract() < 0.07 && across < edge * 0.85;
                let shade = if midrib || stalk {
                    1.0
                } else if vein {
                    0.93
                } else {
                    0.8 + mottle - 0.12 * (across / edge.max(1e-3))
                };
                let g = linear_to_srgb8(shade.clamp(0.0, 1.0) as f32);
                rgba.extend_from_slice(&[g, g, g, if inside { 255 } else { 0 }]);
            }
        }
        Ok(Texture::from_rgba("leaf", LEAF_SIZE, LEAF_SIZE, &rgba)?)
    })
}

/// The texture a source gives: the procedural one from `procedural`, a file read and
/// re-encoded as PNG, or the image as it is.
pub fn resolve_texture(
    source: &TextureSource,
    name: &str,
    procedural: impl FnOnce() -> Result<Arc<Texture>, TreeError>,
) -> Result<Arc<Texture>, TreeError> {
    match source {
        TextureSource::Procedural => procedural(),
        TextureSource::Image(t) => Ok(t.clone()),
        TextureSource::File(path) => load_png(path, name),
    }
}

/// Reads an image file (PNG, or anything `image` decodes) as a texture called `name`.
pub fn load_png(path: &Path, name: &str) -> Result<Arc<Texture>, TreeError> {
    let bytes = std::fs::read(path).map_err(|e| TreeError::Texture {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    Texture::from_image_bytes(name, &bytes)
        .map(Arc::new)
        .map_err(|e| TreeError::Texture {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
}

/// Linear [0, 1] to an sRGB byte.
fn linear_to_srgb8(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rgba(t: &Texture) -> image::RgbaImage {
        image::load_from_memory(&t.png).expect("decodes").to_rgba8()
    }

    #[test]
    fn bark_is_cached_and_deterministic() {
        let a = bark_texture([0.2, 0.1, 0.05, 1.0]).expect("bark");
        let b = bark_texture([0.2, 0.1, 0.05, 1.0]).expect("bark");
        assert!(Arc::ptr_eq(&a, &b));
        assert_eq!((a.width, a.height), (BARK_SIZE, BARK_SIZE));
        let c = bark_texture([0.3, 0.1, 0.05, 1.0]).expect("bark");
        assert_ne!(a.png, c.png);
        let img = rgba(&a);
        assert!(img.pixels().all(|p| p[3] == 255));
        // It tiles: the first and last columns are neighbours on the torus, close in value.
        let (w, h) = img.dimensions();
        for y in 0..h {
            let (l, r) = (
                img.get_pixel(0, y)[0] as i32,
                img.get_pixel(w - 1, y)[0] as i32,
            );
            assert!((l - r).abs() < 40, "row {y}: {l} vs {r}");
        }
    }

    #[test]
    fn leaf_silhouette_is_a_mask() {
        let t = leaf_texture().expect("leaf");
        assert_eq!((t.width, t.height), (LEAF_SIZE, LEAF_SIZE));
        let img = rgba(&t);
        let n = LEAF_SIZE;
        assert_eq!(
            img.get_pixel(n / 2, n / 2)[3],
            255,
            "the blade's middle is opaque"
        );
        assert_eq!(img.get_pixel(n / 2, 2)[3], 255, "the stalk is opaque");
        assert_eq!(img.get_pixel(2, n / 2)[3], 0, "the sides are transparent");
        assert_eq!(img.get_pixel(n - 3, n - 3)[3], 0);
        assert!(
            img.pixels().all(|p| p[3] == 0 || p[3] == 255),
            "a binary mask"
        );
        assert_eq!(blade_half_width(-0.1), 0.0);
        assert_eq!(blade_half_width(0.0), 0.0);
        assert!(blade_half_width(0.5) > 0.3);
        assert!(blade_half_width(1.0) < 0.01);
    }

    #[test]
    fn srgb_bytes() {
        assert_eq!(linear_to_srgb8(0.0), 0);
        assert_eq!(linear_to_srgb8(1.0), 255);
        assert_eq!(linear_to_srgb8(0.214_041_14), 128);
    }

    #[test]
    fn missing_files_name_the_path() {
        let e = load_png(Path::new("/nonexistent/leaf.png"), "leaf").expect_err("missing");
        assert!(e.to_string().contains("/nonexistent/leaf.png"), "{e}");
    }
}
