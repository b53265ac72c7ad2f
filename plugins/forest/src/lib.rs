//! PGE forests (DESIGN.md §3.6): a terrain, species scattered over it in layers by blue noise
//! or a jittered grid, and every tree an instance of a few grown variants.
//!
//! The algorithm is plain Rust: a [`Forest`] holds the [`Terrain`] and the [`Layer`]s;
//! [`Forest::layout`] places the trees of the whole world or of one tile (tiles agree with
//! the whole, instance for instance); [`assemble()`] turns a layout and the grown variants into
//! a [`Model`](pge_engine::geometry::Model) with one instance group per variant. Variants
//! with foliage levels of detail keep their LOD tables ([`variant_mesh_lod`]; [`with_lod`]
//! gives them levels), and [`instance_leaves`] budgets each instance's leaves for a
//! [`Camera`] ([`assemble_budgeted`] writes them per placement).
//!
//! A whole run is a [`ForestRun`] of a [`ForestSpec`] (the forest, each layer's
//! [`Species`], the levels of detail, the tile): the layout, then the variants (script
//! species grown in parallel by the host's [`SpeciesGrower`], through a [`VariantCache`]
//! when its [`ForestConfig`] has one), then the assembly; its errors are [`ForestError`]s
//! that keep the engine's typed errors inside. The Lua side, `pge.Forest{...}`, lives in
//! [`lua`]: it reads option tables into a spec and grows species scripts in sessions of
//! their own ([`lua::SessionGrower`]).
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
mod grow;
mod jittered;
mod layer;
mod layout;
mod lod;
#[cfg(feature = "lua")]
pub mod lua;
mod poisson;
mod run;
mod shared;
mod spec;
mod terrain;
mod trunks;

pub use assemble::{
    CHECK_EVERY, Grown, assemble, assemble_budgeted, assemble_checked, layout_model, transform,
};
pub use cache::{GrownVariant, VariantCache, VariantKey};
pub use grow::{ForestConfig, SpeciesGrower};
pub use layer::{Density, Layer, Method, Variants};
pub use layout::{Forest, Instance, Layout, MAX_INSTANCES, Tile, unique_seed, variant_seed};
pub use lod::{
    Camera, ForestLod, VariantLod, check_budget, instance_leaves, instance_leaves_within,
    variant_lod, variant_mesh_lod, with_lod,
};
#[cfg(feature = "lua")]
pub use lua::ForestPlugin;
pub use poisson::{Rect, Sample, block_size, poisson};
pub use run::{ForestRun, levels};
pub use shared::{VariantSharing, shared_layer, variants_model};
pub use spec::{ForestSpec, ScriptSpecies, Species, TILE_BYTES, VariantFn};
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
        /// The layer whose options made it so many (the one that drew the most samples, or
        /// was being laid out when the count passed the limit), when one did.
        layer: Option<usize>,
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
    /// A callback of the host failed (a density function, a species function): the engine's
    /// error as it was, with its file and line.
    #[error("{0}")]
    Script(pge_engine::Error),
    /// A variant of a script species could not be grown: `error` is the error of its
    /// session as it was (a [`pge_engine::Error::TimeLimit`] when the script ran out of
    /// time), and the first of the run's failures in (layer, variant) order.
    #[error("species '{species}' failed: {error}")]
    Species {
        /// The layer (0-based).
        layer: usize,
        /// The species script, as its session was given it.
        species: String,
        /// What went wrong, with the species script's file and line.
        error: pge_engine::Error,
    },
    /// A grown variant cannot be given the forest's levels of detail.
    #[error("lod: variant {variant} of layer {} ({name}): {error}", .layer + 1)]
    Lod {
        /// The layer (0-based).
        layer: usize,
        /// Its species' name.
        name: String,
        /// The variant (0-based).
        variant: usize,
        /// Why.
        error: pge_lod::LodError,
    },
    /// A layer's species is a script and the run has no [`SpeciesGrower`] to grow it.
    #[error("species scripts need a session created by an engine")]
    NoGrower {
        /// The first such layer (0-based).
        layer: usize,
    },
    /// A camera's leaf budget was asked of a tile that refers to shared variants.
    #[error(
        "lod.camera needs the variants' leaves, which a tile referring to shared variants \
         (--variants) does not grow: write standalone tiles"
    )]
    CameraWithSharedVariants,
}

impl ForestError {
    /// The engine's error inside, if any: a callback's, or a species session's (which a host
    /// matches to tell a limit, [`pge_engine::Error::is_limit`], from a mistake).
    #[must_use]
    pub fn engine_error(&self) -> Option<&pge_engine::Error> {
        match self {
            ForestError::Script(e) | ForestError::Species { error: e, .. } => Some(e),
            _ => None,
        }
    }
}
