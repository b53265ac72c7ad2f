//! PGE forests (DESIGN.md §3.6): a terrain, species scattered over it in layers by blue noise
//! or a jittered grid, and every tree an instance of a few grown variants.
//!
//! The algorithm is plain Rust: a [`Forest`] holds the [`Terrain`] and the [`Layer`]s;
//! [`Forest::layout`] places the trees of the whole world or of one tile (tiles agree with
//! the whole, instance for instance); [`assemble()`] turns a layout and the grown variants into
//! a [`Model`](pge_engine::geometry::Model) with one instance group per variant. Variants
//! with foliage levels of detail keep their LOD tables ([`variant_extras`]; [`with_lod`]
//! gives them levels), and [`instance_leaves`] budgets each instance's leaves for a
//! [`Camera`] ([`assemble_budgeted`] writes them per placement). The Lua side,
//! `pge.Forest{...}`, lives in [`lua`] and grows the variants of a species script in
//! parallel, one session per variant.
//!
//! ```
//! use pge_forest::{Forest, Layer, Terrain, FbmOptions};
//!
//! let mut forest = Forest::new([200.0, 200.0], 7, Some(100.0)).unwrap();
//! forest.terrain = Terrain::fbm(forest.size, FbmOptions::default(), 7);
//! forest.layers.push(Layer::new("oak", 8.0));
//! let whole = forest.layout(None).unwrap();
//! let tile = forest.layout(Some((1, 0))).unwrap();
//! assert!(tile.instances.iter().all(|i| whole.instances.contains(i)));
//! ```

mod assemble;
mod cache;
mod codec;
mod jittered;
mod layer;
mod layout;
mod lod;
#[cfg(feature = "lua")]
pub mod lua;
mod poisson;
mod shared;
mod terrain;
mod trunks;

pub use assemble::{Grown, assemble, assemble_budgeted, layout_model, transform};
pub use cache::{GrownVariant, VariantCache, VariantKey};
pub use layer::{Density, Layer, Method, Variants};
pub use layout::{Forest, Instance, Layout, MAX_INSTANCES, Tile, unique_seed, variant_seed};
pub use lod::{
    Camera, ForestLod, VariantLod, check_budget, instance_leaves, variant_extras, variant_lod,
    with_lod,
};
#[cfg(feature = "lua")]
pub use lua::ForestPlugin;
pub use poisson::{Rect, Sample, block_size, poisson};
pub use shared::{VariantSharing, shared_layer, variants_model};
pub use terrain::{FbmOptions, Grid, Raster, Terrain};

/// Why a forest cannot be laid out.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ForestError {
    /// An option is outside its range.
    #[error("{option} {message}")]
    Option {
        /// The option's name as scripts write it.
        option: &'static str,
        /// What it needs.
        message: String,
    },
    /// An image (height or density map) cannot be read.
    #[error("cannot read the image '{path}': {message}")]
    Image {
        /// The file.
        path: String,
        /// Why.
        message: String,
    },
    /// The layout would hold more than [`MAX_INSTANCES`].
    #[error(
        "the layout would hold about {estimate} instances, more than the limit of 10000000 \
         (raise minDistance or lower density)"
    )]
    TooMany {
        /// How many it would hold.
        estimate: u64,
    },
    /// A tile was asked of a forest without `tile`.
    #[error("--tile needs a forest with tile = T (metres)")]
    NotTiled,
    /// The tile index is outside the grid of tiles.
    #[error("tile {i},{j} is out of range: the forest has {nx} x {nz} tiles (0..{nx}, 0..{nz})")]
    TileOutOfRange {
        /// Asked index along x.
        i: usize,
        /// Asked index along z.
        j: usize,
        /// Tiles along x.
        nx: usize,
        /// Tiles along z.
        nz: usize,
    },
    /// A script callback (a density function) failed.
    #[error("{0}")]
    Script(pge_engine::Error),
}
