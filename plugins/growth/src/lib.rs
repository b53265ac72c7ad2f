//! Growth by nutrient transport for PGE (seed 001, Nicholas McDonald 2020): a tree fed at
//! its root, whose branches thicken, lengthen and split as the nutrient flows up.
//!
//! The model ([`TransportTree`]) and the step-wise algorithm ([`Growth`], one step is one
//! feeding) are plain Rust; [`GrowthPlugin`] adds `pge.Growth{...}` to Lua (docs/lua-api.md). The
//! grown branches become the engine's [`Skeleton`](pge_engine::geometry::Skeleton), meshed
//! by [`pge_tree`] like every other tree.
//!
//! ```
//! use pge_engine::{Location, RunContext, algorithm::run};
//! use pge_growth::{Growth, GrowthParams};
//!
//! let params = GrowthParams { steps: 40, ..GrowthParams::default() };
//! let mut tree = Growth::new(params, Location::new("oak.lua", 1)).unwrap();
//! let model = run(&mut tree, &RunContext::default(), &mut |_| {}).unwrap();
//! assert!(model.stats.nodes > 20);
//! let skeleton = tree.skeleton().unwrap();
//! assert_eq!(skeleton.parents[0], None);
//! ```

mod growth;
#[cfg(feature = "lua")]
mod lua;
mod transport;

pub use growth::{DEFAULT_MAX_BRANCHES, Growth, GrowthError, GrowthParams, MAX_STEPS};
#[cfg(feature = "lua")]
pub use lua::GrowthPlugin;
pub use transport::{
    CapExceeded, Feeding, INITIAL_AREA, MIN_FEED, NONE, TransportParams, TransportTree,
};
