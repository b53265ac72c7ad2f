//! Space colonization for PGE (Runions et al. 2007): trees that grow toward attraction
//! points scattered in an envelope — a crown shape, a revolved profile, a closed mesh, their
//! unions and differences, or a Lua predicate.
//!
//! The algorithm ([`SpaceColonization`]) and the envelopes ([`Shape`]) are plain Rust; the
//! [`SpaceColonizationPlugin`] adds `pge.SpaceColonization{...}` and `pge.shape.*` to Lua
//! (docs/lua-api.md). The grown skeleton becomes bark and leaves through [`pge_tree`].
//!
//! ```
//! use glam::Vec3;
//! use pge_engine::{Location, RunContext, algorithm::run};
//! use pge_spacecol::{Params, Shape, SpaceColonization};
//!
//! let crown = Shape::Sphere { center: Vec3::new(0.0, 4.0, 0.0), radius: 2.0 };
//! let mut params = Params::new(crown);
//! params.points = Some(400);
//! let mut tree = SpaceColonization::new(params, Location::new("oak.lua", 1)).unwrap();
//! let model = run(&mut tree, &RunContext::default(), &mut |_| {}).unwrap();
//! assert!(model.stats.nodes > 20);
//! ```

mod colonize;
mod grid;
#[cfg(feature = "lua")]
mod lua;
mod points;
mod shape;
mod trimesh;

pub use colonize::{Params, ParamsError, SpaceColonization};
pub use grid::PointGrid;
#[cfg(feature = "lua")]
pub use lua::{LuaShape, SpaceColonizationPlugin};
pub use points::{DEFAULT_POINTS, Mode, generate};
pub use shape::{PredicateFn, Shape, ShapeSizeError};
pub use trimesh::{MeshError, TriMesh};
