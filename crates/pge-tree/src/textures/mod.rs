//! Procedural PBR textures: bark and leaves as sets of three maps (base colour, tangent-space
//! normal, roughness), so a tree needs no image files.
//!
//! Every map is a pure function of its parameters ([`BarkParams`], [`LeafParams`]): a height
//! field from fast hashed noise (periodic value noise and stretched cellular noise), the
//! normal map derived from that height field by central differences, colour and roughness
//! from the same field. Rows are computed in parallel (rayon) and the three maps are encoded
//! in parallel (bark: JPEG by default, or PNG with fast compression; leaves, which need
//! alpha: PNG); none of it depends on the thread count.
//!
//! Sets are generated once per distinct parameter set and process ([`TextureCache`]): the
//! variants of a forest, built in parallel sessions, share one set per species. Bark tiles
//! in `u` (around the branch) and `v` (along it).

mod bark;
mod blade;
mod cache;
mod leaves;
mod maps;
mod needles;
mod noise;
mod twig;

use std::sync::Arc;

use pge_engine::geometry::Texture;

pub use bark::{bark_maps, bark_set};
pub use cache::{TextureCache, bark_textures, leaf_textures};
pub use leaves::{leaf_maps, leaf_set};
pub use maps::{Maps, TextureFormat, encode_maps, encode_maps_as, load_png};
// The Lua adapter decodes a script's own PNG maps.
#[cfg(feature = "lua")]
pub use maps::decode_png;

/// The pattern of the procedural bark.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BarkStyle {
    /// Deep vertical furrows between long ridges, from stretched cellular noise (oak; Lua
    /// `"furrowed"`).
    #[default]
    Furrowed,
    /// Irregular flat plates split by narrow cracks (pine; Lua `"plated"`).
    Plated,
    /// Smooth mottled bark with horizontal lenticels (beech, birch; Lua `"smooth"`).
    Smooth,
    /// Interlaced fibrous ridges (willow; Lua `"fibrous"`).
    Fibrous,
    /// Small thin scales, the plated pattern finer and flatter (spruce; Lua `"scaly"`).
    Scaly,
}

impl BarkStyle {
    /// The Lua names, in the order of the variants.
    pub const NAMES: [&'static str; 5] = ["furrowed", "plated", "smooth", "fibrous", "scaly"];

    /// The style of a Lua name.
    #[must_use]
    pub fn from_name(name: &str) -> Option<BarkStyle> {
        match name {
            "furrowed" => Some(BarkStyle::Furrowed),
            "plated" => Some(BarkStyle::Plated),
            "smooth" => Some(BarkStyle::Smooth),
            "fibrous" => Some(BarkStyle::Fibrous),
            "scaly" => Some(BarkStyle::Scaly),
            _ => None,
        }
    }
}

/// The silhouette of the procedural leaf texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LeafShape {
    /// An egg-shaped blade with a midrib and side veins (Lua `"ovate"`).
    #[default]
    Ovate,
    /// An oak leaf: rounded lobes and deep sinuses (Lua `"lobed"`).
    Lobed,
    /// A long narrow willow blade (Lua `"lanceolate"`).
    Lanceolate,
    /// A maple leaf: five pointed lobes with veins from the stalk (Lua `"palmate"`).
    Palmate,
    /// A conifer's needle spray: needles on both sides of a twig (Lua `"needles"`).
    Needles,
}

impl LeafShape {
    /// The Lua names, in the order of the variants.
    pub const NAMES: [&'static str; 5] = ["ovate", "lobed", "lanceolate", "palmate", "needles"];

    /// The shape of a Lua name.
    #[must_use]
    pub fn from_name(name: &str) -> Option<LeafShape> {
        match name {
            "ovate" => Some(LeafShape::Ovate),
            "lobed" => Some(LeafShape::Lobed),
            "lanceolate" => Some(LeafShape::Lanceolate),
            "palmate" => Some(LeafShape::Palmate),
            "needles" => Some(LeafShape::Needles),
            _ => None,
        }
    }
}

/// The length of one leaf of a twig card of `per_card` leaves as a share of the card's
/// length: 1 for a single leaf, then less as the twig bears more (so the leaves cover about
/// the same share of every card).
#[must_use]
pub fn card_share(per_card: u32) -> f32 {
    match per_card {
        0 | 1 => 1.0,
        n => (1.6 / ((n + 1) as f32).sqrt()).min(0.7),
    }
}

/// The parameters a bark texture set is made from: its cache key.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BarkParams {
    /// The pattern.
    pub style: BarkStyle,
    /// The bark colour (linear RGBA): the colour of the ridges' sides; furrows are darker,
    /// ridge tops lighter.
    pub color: [f32; 4],
    /// Side of every map in pixels.
    pub size: u32,
    /// Relief: how deep furrows and cracks look in the normal map (0 flat, 1 the style's
    /// own, up to 4).
    pub depth: f32,
    /// How the maps are stored: JPEG (default) or PNG.
    pub format: TextureFormat,
}

/// The parameters a leaf texture set is made from: its cache key.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeafParams {
    /// The silhouette and its veins.
    pub shape: LeafShape,
    /// Side of every map in pixels.
    pub size: u32,
    /// Leaves (or needle shoots) drawn on the card: 1 a single leaf, more a twig
    /// ([`crate::LeafOptions::per_card`]).
    pub per_card: u32,
}

/// One material's maps.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureSet {
    /// Base colour (sRGB; RGBA with the silhouette in alpha for leaves).
    pub color: Arc<Texture>,
    /// Tangent-space normal map (glTF convention: +X right, +Y up in the image).
    pub normal: Arc<Texture>,
    /// glTF metallic-roughness map: roughness in G, metalness (0) in B.
    pub roughness: Arc<Texture>,
    /// The alpha cutoff chosen with an alpha-masked colour map (leaves: its mean alpha at
    /// least [`pge_lod::mask::MARGIN`] above it, see [`pge_lod::mask`]); `None` for an
    /// opaque set.
    pub alpha_cutoff: Option<f32>,
}

/// Test helpers shared by the submodules' tests.
#[cfg(test)]
mod test_support {
    use super::*;

    /// A map's image (PNG or JPEG) decoded.
    pub fn decode(t: &Texture) -> image::RgbaImage {
        image::load_from_memory(&t.encoded)
            .expect("decodes")
            .to_rgba8()
    }

    /// Dark brown bark of `style` at relief 1.
    pub fn bark(style: BarkStyle, size: u32) -> BarkParams {
        BarkParams {
            style,
            color: [0.2, 0.12, 0.07, 1.0],
            size,
            depth: 1.0,
            format: TextureFormat::Png,
        }
    }
}
