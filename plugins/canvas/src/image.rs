//! [`Image`]: an RGBA8 picture scripts read and write pixel by pixel.

use std::sync::Arc;

use glam::{Vec2, Vec3};
use pge_engine::geometry::{GeometryError, Material, Mesh, Texture};

/// The most pixels an image may have (2^28: 16384 x 16384).
pub const MAX_PIXELS: u64 = 1 << 28;

/// Why an image operation was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ImageError {
    /// A width or height of zero, or more than [`MAX_PIXELS`] pixels.
    #[error("an image must be between 1x1 and {MAX_PIXELS} pixels, got {width}x{height}")]
    BadSize {
        /// Width asked for.
        width: u64,
        /// Height asked for.
        height: u64,
    },
    /// A pixel coordinate outside the image.
    #[error(
        "pixel ({x}, {y}) is outside the {width}x{height} image (x in 0..{width}, y in 0..{height}, 0-based)"
    )]
    OutOfRange {
        /// Column asked for.
        x: i64,
        /// Row asked for.
        y: i64,
        /// Image width.
        width: u32,
        /// Image height.
        height: u32,
    },
    /// The bytes are not an image `image` can decode.
    #[error("cannot decode the image: {0}")]
    Decode(String),
    /// The PNG could not be encoded.
    #[error("cannot encode the image: {0}")]
    Encode(String),
}

/// An RGBA8 image (sRGB), row 0 at the top, pixel coordinates 0-based.
///
/// ```
/// use pge_canvas::Image;
///
/// let mut img = Image::new(4, 2, [0, 0, 0, 255]).unwrap();
/// img.set(3, 1, [255, 0, 0, 255]).unwrap();
/// assert_eq!(img.get(3, 1).unwrap(), [255, 0, 0, 255]);
/// assert!(img.get(4, 0).is_err());
/// let back = Image::decode(&img.png().unwrap()).unwrap();
/// assert_eq!(back, img);
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    width: u32,
    height: u32,
    rgba: Vec<u8>,
}

impl Image {
    /// A `width` x `height` image filled with `fill`.
    pub fn new(width: u32, height: u32, fill: [u8; 4]) -> Result<Image, ImageError> {
        check_size(u64::from(width), u64::from(height))?;
        let rgba = fill.repeat(width as usize * height as usize);
        Ok(Image {
            width,
            height,
            rgba,
        })
    }

    /// Decodes PNG (or any format the `image` crate reads) bytes.
    pub fn decode(bytes: &[u8]) -> Result<Image, ImageError> {
        let img = image::load_from_memory(bytes).map_err(|e| ImageError::Decode(e.to_string()))?;
        check_size(u64::from(img.width()), u64::from(img.height()))?;
        let img = img.to_rgba8();
        Ok(Image {
            width: img.width(),
            height: img.height(),
            rgba: img.into_raw(),
        })
    }

    /// Width in pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The pixels, RGBA8 row by row from the top.
    #[must_use]
    pub fn rgba(&self) -> &[u8] {
        &self.rgba
    }

    /// Whether `(x, y)` is a pixel of the image.
    #[must_use]
    pub fn contains(&self, x: i64, y: i64) -> bool {
        (0..i64::from(self.width)).contains(&x) && (0..i64::from(self.height)).contains(&y)
    }

    fn offset(&self, x: i64, y: i64) -> Result<usize, ImageError> {
        if !self.contains(x, y) {
            return Err(ImageError::OutOfRange {
                x,
                y,
                width: self.width,
                height: self.height,
            });
        }
        Ok((y as usize * self.width as usize + x as usize) * 4)
    }

    /// The pixel at `(x, y)`.
    pub fn get(&self, x: i64, y: i64) -> Result<[u8; 4], ImageError> {
        let o = self.offset(x, y)?;
        Ok([
            self.rgba[o],
            self.rgba[o + 1],
            self.rgba[o + 2],
            self.rgba[o + 3],
        ])
    }

    /// Sets the pixel at `(x, y)`.
    pub fn set(&mut self, x: i64, y: i64, rgba: [u8; 4]) -> Result<(), ImageError> {
        let o = self.offset(x, y)?;
        self.rgba[o..o + 4].copy_from_slice(&rgba);
        Ok(())
    }

    /// Sets every pixel.
    pub fn fill(&mut self, rgba: [u8; 4]) {
        for px in self.rgba.chunks_exact_mut(4) {
            px.copy_from_slice(&rgba);
        }
    }

    /// The image as PNG bytes (deterministic: the same pixels give the same bytes).
    pub fn png(&self) -> Result<Vec<u8>, ImageError> {
        Ok(self
            .texture("image")
            .map_err(|e| ImageError::Encode(e.to_string()))?
            .encoded)
    }

    /// The image as a texture for a material.
    pub fn texture(&self, name: &str) -> Result<Texture, GeometryError> {
        Texture::from_rgba(name, self.width, self.height, &self.rgba)
    }

    /// A quad in the XZ plane covering `[0, width] x [0, height]` (one unit per pixel, pixel
    /// `(x, y)` over the square at `(x, y)`), facing +Y, textured with the image.
    pub fn plane_mesh(&self) -> Result<Mesh, GeometryError> {
        let (w, h) = (self.width as f32, self.height as f32);
        let texture = Arc::new(self.texture("image")?);
        Ok(Mesh {
            name: "image".into(),
            positions: vec![
                Vec3::ZERO,
                Vec3::new(w, 0.0, 0.0),
                Vec3::new(w, 0.0, h),
                Vec3::new(0.0, 0.0, h),
            ],
            normals: vec![Vec3::Y; 4],
            uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
            indices: vec![0, 2, 1, 0, 3, 2],
            material: Arc::new(Material {
                name: "image".into(),
                base_color: [1.0; 4],
                texture: Some(texture),
                roughness: 1.0,
                ..Material::default()
            }),
            ..Mesh::default()
        })
    }
}

fn check_size(width: u64, height: u64) -> Result<(), ImageError> {
    if width == 0 || height == 0 || width * height > MAX_PIXELS {
        return Err(ImageError::BadSize { width, height });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_keeps_every_pixel() {
        let mut img = Image::new(7, 5, [10, 20, 30, 255]).expect("ok");
        for y in 0..5 {
            for x in 0..7 {
                img.set(x, y, [(x * 30) as u8, (y * 40) as u8, 7, 200 + x as u8])
                    .expect("in range");
            }
        }
        let png = img.png().expect("encodes");
        assert_eq!(&png[1..4], b"PNG");
        assert_eq!(png, img.png().expect("encodes"), "deterministic");
        let back = Image::decode(&png).expect("decodes");
        assert_eq!(back, img);
        assert_eq!(back.get(6, 4).expect("in range"), [180, 160, 7, 206]);
    }

    #[test]
    fn out_of_range_and_bad_sizes_are_errors() {
        let mut img = Image::new(3, 2, [0; 4]).expect("ok");
        assert_eq!(
            img.get(-1, 0),
            Err(ImageError::OutOfRange {
                x: -1,
                y: 0,
                width: 3,
                height: 2
            })
        );
        assert!(img.set(0, 2, [1; 4]).is_err());
        assert!(img.contains(2, 1));
        assert!(!img.contains(3, 1));
        assert_eq!(
            Image::new(0, 5, [0; 4]),
            Err(ImageError::BadSize {
                width: 0,
                height: 5
            })
        );
        assert!(Image::new(1 << 15, 1 << 15, [0; 4]).is_err());
        assert!(matches!(
            Image::decode(b"not an image"),
            Err(ImageError::Decode(_))
        ));
        img.fill([9; 4]);
        assert_eq!(img.get(2, 1).expect("ok"), [9; 4]);
    }

    #[test]
    fn plane_is_textured_and_faces_up() {
        let img = Image::new(4, 2, [255; 4]).expect("ok");
        let m = img.plane_mesh().expect("ok");
        m.validate().expect("valid");
        let [a, b, c] = [0, 1, 2].map(|i| m.positions[m.indices[i] as usize]);
        assert!(
            (b - a).cross(c - a).y > 0.0,
            "counter-clockwise seen from above"
        );
        assert_eq!(
            m.material.texture.as_ref().map(|t| (t.width, t.height)),
            Some((4, 2))
        );
    }
}
