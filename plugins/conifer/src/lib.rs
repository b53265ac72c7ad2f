//! Excurrent trees for PGE: conifers with a straight leader, first-order branches in whorls
//! laid down year by year, lengths that follow a crown shape (a cone by default), branches
//! that droop toward the base, and flat sprays of second- and third-order shoots that carry
//! the needles.
//!
//! The model ([`ConiferParams`], [`Whorl`], [`build`]) and the step-wise algorithm
//! ([`Conifer`], one step is one year) are plain Rust; [`ConiferPlugin`] adds
//! `pge.Conifer{...}` to Lua. The skeleton is the engine's
//! [`Skeleton`](pge_engine::geometry::Skeleton), meshed by [`pge_tree`] like every other tree.
//!
//! ```
//! use pge_engine::{Location, RunContext, algorithm::run};
//! use pge_conifer::{Conifer, ConiferParams};
//!
//! let params = ConiferParams { years: 12, ..ConiferParams::default() };
//! let mut tree = Conifer::new(params, Location::new("spruce.lua", 1)).unwrap();
//! let model = run(&mut tree, &RunContext::default(), &mut |_| {}).unwrap();
//! assert_eq!(tree.age(), 12);
//! let built = tree.build().unwrap();
//! // The leader: one node per whorl above the root.
//! assert_eq!(built.trunk.len(), 13);
//! assert!(model.stats.nodes > 100);
//! ```

mod build;
mod conifer;
#[cfg(feature = "lua")]
mod lua;
mod params;

pub use build::{Bud, Built, TooManyNodes, Whorl, build};
pub use conifer::Conifer;
#[cfg(feature = "lua")]
pub use lua::ConiferPlugin;
pub use params::{
    ConiferParams, Crown, DEFAULT_MAX_NODES, MAX_INTERWHORL, MAX_NODES, MAX_PER_WHORL, MAX_PROFILE,
    MAX_SEGMENTS, MAX_YEARS, ParamError, SprayPattern,
};
