//! Growth by nutrient transport for PGE (seed 001, McDonald 2020).

mod growth;
mod transport;

pub use growth::{DEFAULT_MAX_BRANCHES, Growth, GrowthParams, MAX_STEPS};
pub use transport::{
    CapExceeded, Feeding, INITIAL_AREA, MIN_FEED, NONE, TransportParams, TransportTree,
};
