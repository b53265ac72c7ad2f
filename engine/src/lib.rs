//! PGE's engine: the Lua host, the support library, geometry and export.
//!
//! An [`Engine`] holds the [`Plugin`]s and the limits; each [`Session`] is one sandboxed Lua
//! 5.4 state in which a script runs and returns something that grows (an [`Algorithm`]) or a
//! finished model. The result is a [`geometry::Model`], written to glTF by [`export`].
//!
//! ```
//! use pge_engine::{Engine, SessionOptions};
//!
//! let engine = Engine::builder().build().unwrap();
//! let session = engine.session(SessionOptions::default()).unwrap();
//! let value = session
//!     .eval_value("return pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }")
//!     .unwrap();
//! let mut algorithm = session.algorithm_from(value).unwrap();
//! let model = pge_engine::algorithm::run(&mut *algorithm, &session.context(), &mut |_| {}).unwrap();
//! assert_eq!(model.triangle_count(), 1);
//! let glb = pge_engine::export::glb_bytes(&model, &Default::default()).unwrap();
//! assert_eq!(&glb[0..4], b"glTF");
//! ```

pub mod algorithm;
pub mod approx;
mod budget;
pub mod clock;
#[cfg(feature = "lua")]
mod engine;
mod error;
pub mod export;
#[cfg(feature = "lua")]
pub mod files;
pub mod geometry;
pub mod import;
#[cfg(feature = "lua")]
pub mod lua;
pub mod math;
#[cfg(feature = "lua")]
mod plugin;
pub mod random;
#[cfg(feature = "lua")]
mod session;

pub use algorithm::{Algorithm, RunContext, Step};
pub use budget::{Budget, Charge};
#[cfg(feature = "lua")]
pub use engine::{Engine, EngineBuilder, Limits};
pub use error::{Error, Location, OptionError, Result};
#[cfg(feature = "lua")]
pub use lua::params::{OverrideError, ParamInfo, ParamValue};
#[cfg(feature = "lua")]
pub use plugin::Plugin;
#[cfg(feature = "lua")]
pub use session::{Generated, GrowOptions, Session, SessionOptions, Started};

/// The `mlua` crate the engine is built with, for plugins and host applications.
#[cfg(feature = "lua")]
pub use mlua;
