//! Options of tree meshing and leaves: plain Rust values with their defaults.
//!
//! The same options serve every tree generator (space colonization, the turtle, growth), so
//! a species reads the same whatever grew its skeleton. Scripts give them as a Lua table
//! (docs/lua-api.md), read by [`crate::lua::tree_options`].

use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;

use pge_engine::geometry::{Material, Texture};

use crate::textures::{BarkStyle, LeafShape, TextureFormat, card_share};

/// How branch radii are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RadiiMode {
    /// The pipe model from the tip radius: `r^n = r1^n + r2^n` at every fork (Lua `"pipe"`).
    #[default]
    Pipe,
    /// The radii already in the skeleton are kept (a turtle's widths; Lua `"keep"`).
    Keep,
}

/// A trunk flare: the base of every root tube widens into `roots` buttresses that spread
/// into the ground over the first `height` metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Flare {
    /// Number of root buttresses (2..=16, default 5).
    pub roots: u32,
    /// Extra radius at the ground, as a multiple of the trunk radius, on a buttress (> 0,
    /// default 1).
    pub spread: f32,
    /// Height over which the flare fades out, metres (> 0, default 1).
    pub height: f32,
}

impl Default for Flare {
    fn default() -> Self {
        Flare {
            roots: 5,
            spread: 1.0,
            height: 1.0,
        }
    }
}

/// Where a texture comes from.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum TextureSource {
    /// Generated procedurally (bark noise, leaf silhouette), no files needed.
    #[default]
    Procedural,
    /// A PNG file, read when the tree is built. A Lua adapter resolves the script's relative
    /// path (with `pge_engine::lua::resolve_path`) or loads the image itself.
    File(PathBuf),
    /// An image already loaded.
    Image(Arc<Texture>),
}

/// How the skeleton becomes the bark mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshOptions {
    /// Points per ring (3..=64, default 8); each ring has one more vertex for the UV seam.
    pub sides: u32,
    /// Close branch tips (and the base of each root) with a flat cap (default true).
    pub caps: bool,
    /// Pipe-model exponent `n` in `r^n = r1^n + r2^n` (1..=4, default 2.3).
    pub exponent: f32,
    /// Radius at branch tips for the pipe model (> 0, default 0.02).
    pub tip_radius: f32,
    /// Merge non-branching nodes whose chain turns less than this many degrees (0..=45);
    /// `None` (default) keeps every node.
    pub merge_straight: Option<f32>,
    /// Move each node this fraction of the way toward its parent (0..=1, default 0; seed 000
    /// uses 0.5), which lowers branching angles.
    pub smoothing: f32,
    /// Pipe model or keep the skeleton's radii.
    pub radii: RadiiMode,
    /// Bark colour (sRGB `#rrggbb`, stored linear) used by the procedural bark texture.
    pub color: [f32; 4],
    /// The bark texture: procedural (a PBR set of colour, normal and roughness maps of
    /// `bark` style), or a file (colour only).
    pub texture: TextureSource,
    /// The procedural bark's pattern.
    pub bark: BarkStyle,
    /// The procedural bark's relief in the normal map (0..=4, default 1).
    pub bark_depth: f32,
    /// Side of the procedural bark maps in pixels (16..=2048, default 512).
    pub texture_size: u32,
    /// How the procedural bark maps are stored: JPEG (default) or PNG.
    pub texture_format: TextureFormat,
    /// Metres of bark one texture tile covers, around and along every branch (> 0, default
    /// 0.6): the texel density is `texture_size / texture_scale` pixels per metre
    /// everywhere.
    pub texture_scale: f32,
    /// The direction light comes from (default up and to the side, `(0.45, 0.8, 0.35)`):
    /// the UV seam of every branch faces away from it.
    pub light: glam::Vec3,
    /// The trunk flare, or `None` (default).
    pub flare: Option<Flare>,
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions {
            sides: 8,
            caps: true,
            exponent: 2.3,
            tip_radius: 0.02,
            merge_straight: None,
            smoothing: 0.0,
            radii: RadiiMode::Pipe,
            color: hex(DEFAULT_BARK),
            texture: TextureSource::Procedural,
            bark: BarkStyle::Furrowed,
            bark_depth: 1.0,
            texture_size: 512,
            texture_format: TextureFormat::Jpeg,
            texture_scale: 0.6,
            light: glam::Vec3::new(0.45, 0.8, 0.35),
            flare: None,
        }
    }
}

/// Leaves hung at branch tips.
#[derive(Clone, Debug, PartialEq)]
pub struct LeafOptions {
    /// Leaves per tip, drawn uniformly in `min..=max` (default 3..=6; max 1000).
    pub per_tip: (u32, u32),
    /// Leaf length (> 0, default 0.25).
    pub size: f32,
    /// Leaf width as a fraction of its length (> 0 and at most 4, default 1: square quads;
    /// 0.2 gives needles).
    pub width: f32,
    /// Each leaf's colour is drawn between these two (linear RGBA).
    pub colors: [[f32; 4]; 2],
    /// A tip's leaves hang on its last `max_depth + 1` segments: 0 puts them on the tip
    /// segment only (0..=1000, default 2).
    pub max_depth: u32,
    /// Leaves drawn on each card (1..=[`MAX_PER_CARD`], default 1): 1 draws one leaf, the card
    /// `size` long; more draw a twig bearing that many leaves, each about `size` long, on a
    /// card [`LeafOptions::card_length`] long (for `Needles`, shoots of needles). `per_tip`
    /// and `along` count cards.
    pub per_card: u32,
    /// Cards along the branches as well as at the tips, or `None` (default: tips only).
    pub along: Option<Along>,
    /// The leaf texture: procedural (a PBR set with the silhouette of `shape` in alpha), or
    /// a file (colour only).
    pub texture: TextureSource,
    /// The procedural leaf's silhouette and veins.
    pub shape: LeafShape,
    /// Side of the procedural leaf maps in pixels (16..=2048, default 512).
    pub texture_size: u32,
    /// The colour of a leaf's underside and of the light passing through it (linear RGBA;
    /// default `#c8dc64`, a light yellow green): the leaf material's
    /// `KHR_materials_diffuse_transmission` colour, the preview's back-face tint.
    pub back_color: [f32; 4],
    /// The share of light passing through a leaf, 0..=1 (default 0.3); 0 writes no
    /// transmission and shades both faces alike.
    pub translucency: f32,
    /// Where the options were given (`FILE:LINE`), for warnings; empty when not from a
    /// script.
    pub source: String,
}

impl Default for LeafOptions {
    fn default() -> Self {
        LeafOptions {
            per_tip: (3, 6),
            size: 0.25,
            width: 1.0,
            colors: [hex(DEFAULT_LEAF_COLORS[0]), hex(DEFAULT_LEAF_COLORS[1])],
            max_depth: 2,
            per_card: 1,
            along: None,
            texture: TextureSource::Procedural,
            shape: LeafShape::Ovate,
            texture_size: 512,
            back_color: hex(DEFAULT_LEAF_BACK_COLOR),
            translucency: 0.3,
            source: String::new(),
        }
    }
}

/// The most leaves a card draws.
pub const MAX_PER_CARD: u32 = 12;

impl LeafOptions {
    /// The length of a card whose leaves are `leaf` long: `leaf` for one leaf a card, longer
    /// for a twig of [`LeafOptions::per_card`] leaves (the twig's layout draws each leaf at
    /// a fixed share of the card, [`card_share`]).
    #[must_use]
    pub fn card_length(&self, leaf: f32) -> f32 {
        leaf / card_share(self.per_card)
    }
}

/// Cards along the last branch orders (counted from the tips, Horton-Strahler: a tip's
/// branch is order 1, a branch where two of order k meet is k + 1), one every `spacing`
/// metres of path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Along {
    /// How many orders from the tips bear cards (1..=8, default 2).
    pub orders: u32,
    /// Path length between two cards along a branch, metres (> 0, default 0.3).
    pub spacing: f32,
}

impl Default for Along {
    fn default() -> Self {
        Along {
            orders: 2,
            spacing: 0.3,
        }
    }
}

/// Everything [`build_tree`](crate::build_tree) needs besides the skeleton.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TreeOptions {
    /// Bark meshing and radii.
    pub mesh: MeshOptions,
    /// Tip leaves; `None` for none. Leaf points already in the skeleton (a turtle's `~`) are
    /// meshed either way, styled by these options or their defaults.
    pub leaves: Option<LeafOptions>,
    /// Foliage levels of detail (docs/lua-api.md): the leaf mesh is simplified and written in
    /// the order of the vector V with its LOD table in the extras; `None` for none.
    pub lod: Option<pge_lod::LodOptions>,
}

const DEFAULT_BARK: &str = "#6b5444";
const DEFAULT_LEAF_COLORS: [&str; 2] = ["#2f6b1f", "#7da83a"];
const DEFAULT_LEAF_BACK_COLOR: &str = "#c8dc64";

fn hex(s: &str) -> [f32; 4] {
    Material::from_hex("", s)
        .map(|m| m.base_color)
        .unwrap_or([1.0; 4])
}

impl fmt::Display for RadiiMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RadiiMode::Pipe => "pipe",
            RadiiMode::Keep => "keep",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults() {
        let o = TreeOptions::default();
        assert_eq!(o.mesh.sides, 8);
        assert_eq!(o.mesh.exponent, 2.3);
        assert_eq!(o.mesh.radii, RadiiMode::Pipe);
        assert!(o.leaves.is_none());
        assert_eq!(LeafOptions::default().per_tip, (3, 6));
        assert_eq!(RadiiMode::Keep.to_string(), "keep");
    }
}
