use crate::math;
use std::sync::Arc;

use super::GeometryError;

/// How the alpha channel of a material is used (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub enum AlphaMode {
    /// Alpha is ignored.
    #[default]
    Opaque,
    /// Fragments with alpha below the cutoff are discarded (leaves).
    Mask(f32),
    /// Alpha blending.
    Blend,
}

/// An image embedded in the model: PNG, or JPEG for maps without alpha.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Texture {
    /// Name written to the glTF image.
    pub name: String,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The image file's bytes, encoded as [`Texture::format`] says (PNG, or JPEG).
    #[serde(with = "super::binary::bytes")]
    pub encoded: Vec<u8>,
}

/// How a [`Texture`]'s bytes are encoded (read from the bytes' own header).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// A PNG file.
    Png,
    /// A baseline JPEG file (opaque maps).
    Jpeg,
}

/// The first bytes of every JPEG file (start of image, then a marker).
const JPEG_MAGIC: [u8; 3] = [0xFF, 0xD8, 0xFF];

impl Texture {
    /// The bytes it holds (its encoded image).
    #[must_use]
    pub fn heap_bytes(&self) -> usize {
        self.encoded.len()
    }

    /// How the bytes are encoded: JPEG when they start as a JPEG file does, PNG otherwise.
    #[must_use]
    pub fn format(&self) -> ImageFormat {
        if self.encoded.starts_with(&JPEG_MAGIC) {
            ImageFormat::Jpeg
        } else {
            ImageFormat::Png
        }
    }

    /// The image's media type as glTF names it: `image/jpeg` or `image/png`.
    #[must_use]
    pub fn mime_type(&self) -> &'static str {
        match self.format() {
            ImageFormat::Jpeg => "image/jpeg",
            ImageFormat::Png => "image/png",
        }
    }

    /// The usual file extension of the image: `jpg` or `png`.
    #[must_use]
    pub fn extension(&self) -> &'static str {
        match self.format() {
            ImageFormat::Jpeg => "jpg",
            ImageFormat::Png => "png",
        }
    }

    /// Encodes 8-bit pixels of `channels` (1: grey, 3: RGB) per pixel, row-major with the
    /// top row first, as a baseline JPEG of `quality` (1..=100, clamped) with no chroma
    /// subsampling: for opaque generated maps, where it costs a fraction of PNG's bytes.
    /// Deterministic: the same pixels always give the same bytes.
    pub fn from_pixels_jpeg(
        name: impl Into<String>,
        width: u32,
        height: u32,
        channels: u8,
        pixels: &[u8],
        quality: u8,
    ) -> Result<Texture, GeometryError> {
        let color = match channels {
            1 => jpeg_encoder::ColorType::Luma,
            3 => jpeg_encoder::ColorType::Rgb,
            _ => {
                return Err(GeometryError::Texture(format!(
                    "{channels} channels: a JPEG takes only 1 (grey) or 3 (RGB)"
                )));
            }
        };
        let expected = width as usize * height as usize * channels as usize;
        let side = |s: u32| u16::try_from(s).ok().filter(|&s| s > 0);
        let (Some(w), Some(h)) = (side(width), side(height)) else {
            return Err(GeometryError::Texture(format!(
                "{width}x{height}: a JPEG is 1 to 65535 pixels a side"
            )));
        };
        if pixels.len() != expected {
            return Err(GeometryError::Texture(format!(
                "{width}x{height} with {channels} channels needs {expected} bytes, got {}",
                pixels.len()
            )));
        }
        let mut jpeg = Vec::with_capacity(expected / 4);
        let mut encoder = jpeg_encoder::Encoder::new(&mut jpeg, quality.clamp(1, 100));
        encoder.set_sampling_factor(jpeg_encoder::SamplingFactor::R_4_4_4);
        encoder
            .encode(pixels, w, h, color)
            .map_err(|e| GeometryError::Texture(e.to_string()))?;
        Ok(Texture {
            name: name.into(),
            width,
            height,
            encoded: jpeg,
        })
    }

    /// A texture of encoded PNG or JPEG bytes as they are (not decoded, not re-encoded): its
    /// size read from the file's header. Anything else is an error.
    pub fn from_encoded(name: impl Into<String>, bytes: Vec<u8>) -> Result<Texture, GeometryError> {
        let format = if bytes.starts_with(&JPEG_MAGIC) {
            image::ImageFormat::Jpeg
        } else if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
            image::ImageFormat::Png
        } else {
            return Err(GeometryError::Texture("neither a PNG nor a JPEG".into()));
        };
        let (width, height) = image::ImageReader::with_format(std::io::Cursor::new(&bytes), format)
            .into_dimensions()
            .map_err(|e| GeometryError::Texture(e.to_string()))?;
        Ok(Texture {
            name: name.into(),
            width,
            height,
            encoded: bytes,
        })
    }

    /// Encodes RGBA8 pixels (row-major, top row first) as a PNG texture.
    ///
    /// The encoding is deterministic: the same pixels always give the same bytes.
    pub fn from_rgba(
        name: impl Into<String>,
        width: u32,
        height: u32,
        rgba: &[u8],
    ) -> Result<Texture, GeometryError> {
        let expected = width as usize * height as usize * 4;
        if rgba.len() != expected || width == 0 || height == 0 {
            return Err(GeometryError::Texture(format!(
                "{width}x{height} RGBA needs {expected} bytes, got {}",
                rgba.len()
            )));
        }
        let mut png = Vec::new();
        let encoder = image::codecs::png::PngEncoder::new(&mut png);
        image::ImageEncoder::write_image(
            encoder,
            rgba,
            width,
            height,
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|e| GeometryError::Texture(e.to_string()))?;
        Ok(Texture {
            name: name.into(),
            width,
            height,
            encoded: png,
        })
    }

    /// Encodes 8-bit pixels of `channels` (3: RGB, 4: RGBA) per pixel, row-major with the top
    /// row first, as a PNG texture with fast compression and the `Sub` row filter: for large
    /// generated maps (bark, leaves), where encoding time matters more than a few percent of
    /// size. Deterministic like [`Texture::from_rgba`].
    pub fn from_pixels_fast(
        name: impl Into<String>,
        width: u32,
        height: u32,
        channels: u8,
        pixels: &[u8],
    ) -> Result<Texture, GeometryError> {
        use image::codecs::png::{CompressionType, FilterType, PngEncoder};
        let (color, per) = match channels {
            3 => (image::ExtendedColorType::Rgb8, 3),
            4 => (image::ExtendedColorType::Rgba8, 4),
            _ => {
                return Err(GeometryError::Texture(format!(
                    "{channels} channels: only 3 (RGB) or 4 (RGBA)"
                )));
            }
        };
        let expected = width as usize * height as usize * per;
        if pixels.len() != expected || width == 0 || height == 0 {
            return Err(GeometryError::Texture(format!(
                "{width}x{height} with {channels} channels needs {expected} bytes, got {}",
                pixels.len()
            )));
        }
        let mut png = Vec::with_capacity(expected / 2);
        let encoder =
            PngEncoder::new_with_quality(&mut png, CompressionType::Fast, FilterType::Sub);
        image::ImageEncoder::write_image(encoder, pixels, width, height, color)
            .map_err(|e| GeometryError::Texture(e.to_string()))?;
        Ok(Texture {
            name: name.into(),
            width,
            height,
            encoded: png,
        })
    }

    /// Reads a texture from PNG (or any format `image` decodes) bytes, re-encoded as PNG.
    pub fn from_image_bytes(
        name: impl Into<String>,
        bytes: &[u8],
    ) -> Result<Texture, GeometryError> {
        let img = image::load_from_memory(bytes)
            .map_err(|e| GeometryError::Texture(e.to_string()))?
            .to_rgba8();
        Texture::from_rgba(name, img.width(), img.height(), img.as_raw())
    }
}

/// A PBR metallic-roughness material as glTF describes it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Material {
    /// Name written to the glTF material.
    pub name: String,
    /// Linear RGBA base colour factor.
    pub base_color: [f32; 4],
    /// Base colour texture, multiplied by `base_color`.
    #[serde(with = "super::binary::shared_option")]
    pub texture: Option<Arc<Texture>>,
    /// Tangent-space normal map (glTF `normalTexture`: RGB = XYZ, +Y up in the image).
    #[serde(with = "super::binary::shared_option")]
    pub normal_texture: Option<Arc<Texture>>,
    /// Metallic-roughness map (glTF `metallicRoughnessTexture`: roughness in G, metalness in
    /// B), multiplied by `roughness` and `metallic`.
    #[serde(with = "super::binary::shared_option")]
    pub metallic_roughness_texture: Option<Arc<Texture>>,
    /// How alpha is used.
    pub alpha: AlphaMode,
    /// Whether back faces are rendered (leaves).
    pub double_sided: bool,
    /// Metallic factor, 0 for plants.
    pub metallic: f32,
    /// Roughness factor.
    pub roughness: f32,
    /// Light that passes through the surface to its other side (leaves), written as glTF
    /// `KHR_materials_diffuse_transmission`; `None` for opaque surfaces.
    pub transmission: Option<DiffuseTransmission>,
}

/// Diffuse light passing through a thin surface, as glTF `KHR_materials_diffuse_transmission`
/// describes it: a leaf lit from behind glows in the colour of what passes through, and its
/// back face is seen in that colour.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DiffuseTransmission {
    /// The share of diffuse light that passes through, in `[0, 1]`
    /// (`diffuseTransmissionFactor`).
    pub factor: f32,
    /// Linear RGB tint of the light that passes through (`diffuseTransmissionColorFactor`).
    pub color: [f32; 3],
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            base_color: [0.8, 0.8, 0.8, 1.0],
            texture: None,
            normal_texture: None,
            metallic_roughness_texture: None,
            alpha: AlphaMode::Opaque,
            double_sided: false,
            metallic: 0.0,
            roughness: 0.9,
            transmission: None,
        }
    }
}

impl Material {
    /// A plain material of the given sRGB colour `#rrggbb` (or `#rrggbbaa`).
    pub fn from_hex(name: impl Into<String>, hex: &str) -> Result<Material, GeometryError> {
        Ok(Material {
            name: name.into(),
            base_color: parse_hex_color(hex)?,
            ..Material::default()
        })
    }
}

/// Parses `#rrggbb` or `#rrggbbaa` (sRGB) into a linear RGBA colour.
pub fn parse_hex_color(hex: &str) -> Result<[f32; 4], GeometryError> {
    let digits = hex.strip_prefix('#').unwrap_or(hex);
    let bad = || GeometryError::Color(hex.to_string());
    if !(digits.len() == 6 || digits.len() == 8) || !digits.is_ascii() {
        return Err(bad());
    }
    let byte = |i: usize| u8::from_str_radix(&digits[i..i + 2], 16).map_err(|_| bad());
    let alpha = if digits.len() == 8 {
        byte(6)? as f32 / 255.0
    } else {
        1.0
    };
    Ok([
        srgb_to_linear(byte(0)? as f32 / 255.0),
        srgb_to_linear(byte(2)? as f32 / 255.0),
        srgb_to_linear(byte(4)? as f32 / 255.0),
        alpha,
    ])
}

/// Converts one sRGB channel in [0, 1] to linear.
#[must_use]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        math::powf((c + 0.055) / 1.055, 2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_colors_parse_to_linear() {
        let c = parse_hex_color("#ff0080").expect("valid");
        assert_eq!(c[0], 1.0);
        assert_eq!(c[1], 0.0);
        assert!((c[2] - 0.2158605).abs() < 1e-5);
        assert_eq!(c[3], 1.0);
        assert!(parse_hex_color("#ff00").is_err());
        assert!(parse_hex_color("zz0000").is_err());
    }

    #[test]
    fn texture_encoding_is_deterministic() {
        let px: Vec<u8> = (0..4 * 4 * 4).map(|i| i as u8).collect();
        let a = Texture::from_rgba("t", 4, 4, &px).expect("encodes");
        let b = Texture::from_rgba("t", 4, 4, &px).expect("encodes");
        assert_eq!(a.encoded, b.encoded);
        assert!(Texture::from_rgba("t", 4, 4, &px[1..]).is_err());
        let back = Texture::from_image_bytes("t", &a.encoded).expect("decodes");
        assert_eq!(back.encoded, a.encoded);
        let rgb: Vec<u8> = (0..4 * 4 * 3).map(|i| i as u8).collect();
        let fast = Texture::from_pixels_fast("t", 4, 4, 3, &rgb).expect("encodes");
        let decoded = image::load_from_memory(&fast.encoded)
            .expect("png")
            .to_rgb8();
        assert_eq!(decoded.as_raw(), &rgb);
        assert!(Texture::from_pixels_fast("t", 4, 4, 4, &rgb).is_err());
        assert!(Texture::from_pixels_fast("t", 4, 4, 2, &rgb).is_err());
        assert_eq!((fast.mime_type(), fast.extension()), ("image/png", "png"));
    }

    #[test]
    fn jpeg_textures_are_deterministic_close_and_named_as_jpeg() {
        // A smooth gradient, as generated maps are at the scale of a JPEG block.
        let rgb: Vec<u8> = (0..32 * 32)
            .flat_map(|i| [(i % 32 * 8) as u8, (i / 32 * 8) as u8, 128])
            .collect();
        let a = Texture::from_pixels_jpeg("t", 32, 32, 3, &rgb, 95).expect("encodes");
        let b = Texture::from_pixels_jpeg("t", 32, 32, 3, &rgb, 95).expect("encodes");
        assert_eq!(a.encoded, b.encoded);
        assert_eq!(a.format(), ImageFormat::Jpeg);
        assert_eq!((a.mime_type(), a.extension()), ("image/jpeg", "jpg"));
        let decoded = image::load_from_memory(&a.encoded).expect("jpeg").to_rgb8();
        let worst = decoded
            .as_raw()
            .iter()
            .zip(&rgb)
            .map(|(a, b)| a.abs_diff(*b))
            .max();
        assert!(worst.is_some_and(|d| d <= 6), "{worst:?}");
        let grey: Vec<u8> = (0..16 * 16).map(|i| i as u8).collect();
        let g = Texture::from_pixels_jpeg("g", 16, 16, 1, &grey, 90).expect("encodes");
        assert_eq!(
            image::load_from_memory(&g.encoded).expect("jpeg").color(),
            image::ColorType::L8
        );
        assert!(Texture::from_pixels_jpeg("t", 32, 32, 4, &rgb, 90).is_err());
        assert!(Texture::from_pixels_jpeg("t", 32, 31, 3, &rgb, 90).is_err());
        // Read back as it is, its size from its header; PNG too; nothing else.
        let back = Texture::from_encoded("t", a.encoded.clone()).expect("a jpeg");
        assert_eq!(
            (back.width, back.height, &back.encoded),
            (32, 32, &a.encoded)
        );
        let png = Texture::from_rgba("p", 3, 2, &[0; 24]).expect("png");
        let back = Texture::from_encoded("p", png.encoded.clone()).expect("a png");
        assert_eq!((back.width, back.height), (3, 2));
        assert!(Texture::from_encoded("x", b"glTF".to_vec()).is_err());
        assert!(Texture::from_encoded("x", JPEG_MAGIC.to_vec()).is_err());
    }
}
