//! From pixels to textures: normal maps from height fields, linear colour to sRGB bytes,
//! PNG encoding, and reading image files.

use pge_engine::math;
use std::path::Path;
use std::sync::{Arc, OnceLock};

use pge_engine::geometry::Texture;
use rayon::prelude::*;

use super::TextureSet;
use crate::TreeError;

/// The three maps of one material as raw pixels, before PNG encoding.
#[derive(Clone, Debug, PartialEq)]
pub struct Maps {
    /// Side of every map in pixels.
    pub size: u32,
    /// Base colour pixels, `channels` bytes each (sRGB).
    pub color: Vec<u8>,
    /// Bytes per base-colour pixel: 3 (RGB) or 4 (RGBA).
    pub channels: u8,
    /// Tangent-space normal map, RGB.
    pub normal: Vec<u8>,
    /// Metallic-roughness map, RGB: roughness in G, R and B zero.
    pub roughness: Vec<u8>,
}

/// A set's pixels before its normal map: the height field the normal map is made from,
/// base colour and roughness.
pub(super) struct Surface {
    /// Side of every map in pixels.
    pub(super) n: usize,
    /// Heights, `n x n`.
    pub(super) heights: Vec<f32>,
    /// Normal-map strength and whether the height field wraps (see [`normal_map`]).
    pub(super) strength: f32,
    pub(super) wrap: bool,
    /// Base colour pixels, `channels` bytes each.
    pub(super) color: Vec<u8>,
    pub(super) channels: u8,
    /// Metallic-roughness pixels, RGB.
    pub(super) roughness: Vec<u8>,
}

impl Surface {
    /// The three maps as pixels.
    pub(super) fn maps(self) -> Maps {
        Maps {
            size: self.n as u32,
            normal: normal_map(&self.heights, self.n, self.strength, self.wrap),
            color: self.color,
            channels: self.channels,
            roughness: self.roughness,
        }
    }

    /// The three maps PNG-encoded, named as [`encode_maps`] names them (see
    /// [`Surface::encode_as`]).
    pub(super) fn encode(self, what: &str) -> Result<TextureSet, TreeError> {
        self.encode_as(what, TextureFormat::Png)
    }

    /// The three maps encoded in `format`, named as [`encode_maps`] names them: the base
    /// colour and roughness maps are encoded while the normal map is made (its rows shared by
    /// whichever threads are free) and then encoded, so no core waits for the last encoder
    /// alone.
    pub(super) fn encode_as(
        self,
        what: &str,
        format: TextureFormat,
    ) -> Result<TextureSet, TreeError> {
        let n = self.n as u32;
        let encode =
            |map: Map, channels: u8, px: &[u8]| encode_map(what, map, n, channels, px, format);
        let ((color, roughness), normal) = rayon::join(
            || {
                rayon::join(
                    || encode(Map::Color, self.channels, &self.color),
                    || encode(Map::Roughness, 3, &self.roughness),
                )
            },
            || {
                let normal = normal_map(&self.heights, self.n, self.strength, self.wrap);
                encode(Map::Normal, 3, &normal)
            },
        );
        Ok(TextureSet {
            color: color?,
            normal: normal?,
            roughness: roughness?,
            alpha_cutoff: None,
        })
    }
}

/// A tangent-space normal map of an `n x n` height field: central differences (wrapping
/// around the edges when `wrap`, else clamped), `strength` times the height change per texel.
pub(super) fn normal_map(h: &[f32], n: usize, strength: f32, wrap: bool) -> Vec<u8> {
    let mut out = vec![0u8; n * n * 3];
    // The neighbour before and after index `i` of a row or column.
    let before = |i: usize| match (i, wrap) {
        (0, true) => n - 1,
        (0, false) => 0,
        _ => i - 1,
    };
    let after = |i: usize| match (i + 1 == n, wrap) {
        (true, true) => 0,
        (true, false) => i,
        _ => i + 1,
    };
    let k = 0.5 * strength;
    out.par_chunks_mut(n * 3).enumerate().for_each(|(y, row)| {
        let here = &h[y * n..][..n];
        let up = &h[before(y) * n..][..n];
        let down = &h[after(y) * n..][..n];
        for (x, px) in row.chunks_exact_mut(3).enumerate() {
            let dx = (here[after(x)] - here[before(x)]) * k;
            // Image rows grow downwards; +Y of the normal map points up the image.
            let dy = (up[x] - down[x]) * k;
            let inv = 1.0 / (dx * dx + dy * dy + 1.0).sqrt();
            let nrm = [-dx * inv, -dy * inv, inv];
            for i in 0..3 {
                px[i] = ((nrm[i] * 0.5 + 0.5) * 255.0 + 0.5) as u8;
            }
        }
    });
    out
}

/// How a texture set's maps are stored in the model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TextureFormat {
    /// Opaque maps as JPEG (a fraction of PNG's bytes): base colour at quality
    /// [`JPEG_COLOR_QUALITY`], the normal map at [`JPEG_NORMAL_QUALITY`], the roughness as a
    /// grey JPEG (glTF reads roughness from G and metalness from B, which the material's
    /// metallic factor 0 cancels); a map with alpha stays PNG (Lua `"jpeg"`).
    #[default]
    Jpeg,
    /// Every map lossless PNG (Lua `"png"`).
    Png,
}

impl TextureFormat {
    /// The Lua names, in the order of the variants.
    pub const NAMES: [&'static str; 2] = ["jpeg", "png"];

    /// The format of a Lua name.
    #[must_use]
    pub fn from_name(name: &str) -> Option<TextureFormat> {
        match name {
            "jpeg" => Some(TextureFormat::Jpeg),
            "png" => Some(TextureFormat::Png),
            _ => None,
        }
    }
}

/// JPEG quality of base colour maps.
pub(super) const JPEG_COLOR_QUALITY: u8 = 90;

/// JPEG quality of normal maps: high, so the decoded normals keep their tilt (their mean
/// within a degree of the lossless map's, a test holds it).
pub(super) const JPEG_NORMAL_QUALITY: u8 = 95;

/// Which of a set's three maps a map is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Map {
    Color,
    Normal,
    Roughness,
}

impl Map {
    fn name(self) -> &'static str {
        match self {
            Map::Color => "color",
            Map::Normal => "normal",
            Map::Roughness => "roughness",
        }
    }
}

/// Map `map` of set `what`, `n x n` pixels of `channels` bytes, encoded in `format` and
/// named `<what> <map>`: PNG (fast compression) for PNG and for any map with alpha, else
/// JPEG, the metallic-roughness map as a grey JPEG of its G channel.
fn encode_map(
    what: &str,
    map: Map,
    n: u32,
    channels: u8,
    px: &[u8],
    format: TextureFormat,
) -> Result<Arc<Texture>, pge_engine::geometry::GeometryError> {
    let name = format!("{what} {}", map.name());
    if format == TextureFormat::Png || channels == 4 {
        return Texture::from_pixels_fast(name, n, n, channels, px).map(Arc::new);
    }
    match map {
        Map::Roughness => {
            let grey: Vec<u8> = px.chunks_exact(3).map(|p| p[1]).collect();
            Texture::from_pixels_jpeg(name, n, n, 1, &grey, JPEG_COLOR_QUALITY)
        }
        Map::Normal => Texture::from_pixels_jpeg(name, n, n, 3, px, JPEG_NORMAL_QUALITY),
        Map::Color => Texture::from_pixels_jpeg(name, n, n, channels, px, JPEG_COLOR_QUALITY),
    }
    .map(Arc::new)
}

/// Encodes the three maps of a set in parallel as PNG, named `<what> color`, `<what> normal`
/// and `<what> roughness`.
pub fn encode_maps(what: &str, maps: Maps) -> Result<TextureSet, TreeError> {
    encode_maps_as(what, maps, TextureFormat::Png)
}

/// [`encode_maps`] in `format`.
pub fn encode_maps_as(
    what: &str,
    maps: Maps,
    format: TextureFormat,
) -> Result<TextureSet, TreeError> {
    let n = maps.size;
    let jobs = [
        (Map::Color, maps.channels, maps.color),
        (Map::Normal, 3, maps.normal),
        (Map::Roughness, 3, maps.roughness),
    ];
    let mut maps = jobs
        .into_par_iter()
        .map(|(map, channels, px)| encode_map(what, map, n, channels, &px, format))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter();
    let mut next = || {
        maps.next()
            .ok_or_else(|| TreeError::Generated("a map is missing".into()))
    };
    Ok(TextureSet {
        color: next()?,
        normal: next()?,
        roughness: next()?,
        alpha_cutoff: None,
    })
}

/// Reads an image file (PNG, or anything `image` decodes) as a texture called `name`.
pub fn load_png(path: &Path, name: &str) -> Result<Arc<Texture>, TreeError> {
    let bytes = std::fs::read(path).map_err(|e| TreeError::Texture {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    decode_png(path, &bytes, name)
}

/// Decodes the bytes of the image file at `path` (read by the caller) as [`load_png`] does.
pub fn decode_png(path: &Path, bytes: &[u8], name: &str) -> Result<Arc<Texture>, TreeError> {
    Texture::from_image_bytes(name, bytes)
        .map(Arc::new)
        .map_err(|e| TreeError::Texture {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
}

/// Linear [0, 1] to sRGB bytes through a table of 4096 steps (a `powf` per channel and
/// pixel would cost more than the noise): the table is found once per map, not per pixel.
#[derive(Clone, Copy)]
pub(super) struct Srgb(&'static [u8; 4097]);

impl Srgb {
    /// The process's table.
    pub(super) fn table() -> Srgb {
        static TABLE: OnceLock<[u8; 4097]> = OnceLock::new();
        Srgb(TABLE.get_or_init(|| {
            std::array::from_fn(|i| {
                let c = i as f32 / 4096.0;
                let s = if c <= 0.003_130_8 {
                    c * 12.92
                } else {
                    1.055 * math::powf(c, 1.0 / 2.4) - 0.055
                };
                (s * 255.0 + 0.5) as u8
            })
        }))
    }

    /// The sRGB byte of linear `c` (clamped to [0, 1]).
    #[inline]
    pub(super) fn byte(self, c: f32) -> u8 {
        let i = (c.clamp(0.0, 1.0) * 4096.0 + 0.5) as usize;
        self.0[i.min(4096)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_bytes() {
        let srgb = Srgb::table();
        assert_eq!(srgb.byte(0.0), 0);
        assert_eq!(srgb.byte(1.0), 255);
        assert_eq!(srgb.byte(0.214_041_14), 128);
        assert_eq!(srgb.byte(-3.0), 0);
        assert_eq!(srgb.byte(f32::NAN), 0);
    }

    #[test]
    fn missing_files_name_the_path() {
        let e = load_png(Path::new("/nonexistent/leaf.png"), "leaf").expect_err("missing");
        assert!(e.to_string().contains("/nonexistent/leaf.png"), "{e}");
    }
}
