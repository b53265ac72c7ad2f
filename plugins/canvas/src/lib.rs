//! Lines and images, the thesis' behaviour modellers (§3.5): [`Lines`] draws coloured 3D
//! segments (fireworks, explorers' trails) exported as glTF lines; [`Image`] is a picture
//! scripts create or load, read and write pixel by pixel, save as PNG and use as a texture
//! (the explorers' map).

mod image;
mod lines;

pub use crate::image::{Image, ImageError, MAX_PIXELS};
pub use lines::{Lines, LinesError, MAX_SEGMENTS};
