//! Layers: one species each, with how its trunks are placed (Poisson disk or jittered
//! grid), its density, the slope and altitude it accepts, its variants and scales.

use std::rc::Rc;
use std::sync::Arc;

use crate::ForestError;
use crate::poisson::block_size;
use crate::terrain::Raster;

/// How a layer's trunks are placed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Blue noise: Bridson's Poisson-disk sampling, block by block.
    Poisson,
    /// Seed 000's jittered grid: one tree per cell, moved by up to `jitter` of the cell
    /// (0 ≤ jitter < 0.5); the cell is `minDistance / (1 − 2 jitter)` so trunks keep it.
    Jittered {
        /// Fraction of the cell a trunk may move from the cell's centre, per axis.
        jitter: f64,
    },
}

/// The probability that a sampled point grows a tree.
#[derive(Clone)]
pub enum Density {
    /// The same everywhere, in [0, 1].
    Constant(f64),
    /// A greyscale map stretched over the world (white = 1; top row at −z).
    Map(Arc<Raster>),
    /// A function of `(x, z)` returning a value in [0, 1] (a script's function).
    Function(Rc<dyn Fn(f64, f64) -> Result<f64, pge_engine::Error>>),
}

impl std::fmt::Debug for Density {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Density::Constant(d) => write!(f, "Constant({d})"),
            Density::Map(_) => write!(f, "Map"),
            Density::Function(_) => write!(f, "Function"),
        }
    }
}

/// How many meshes a layer grows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variants {
    /// This many variants, each instanced by many trees.
    Count(u32),
    /// One tree per instance (seed 000's forests).
    Unique,
}

/// One species scattered over the terrain.
#[derive(Clone, Debug)]
pub struct Layer {
    /// The species' name: the script's file stem, or `layerN`.
    pub name: String,
    /// Poisson disk or jittered grid.
    pub method: Method,
    /// Metres between trunks of this layer, and from trunks of earlier layers.
    pub min_distance: f64,
    /// Probability of growing at a sampled point.
    pub density: Density,
    /// Allowed slope in degrees `[min, max]`.
    pub slope: [f64; 2],
    /// Allowed altitude in metres `[min, max]`.
    pub altitude: [f64; 2],
    /// Variant count or one per tree.
    pub variants: Variants,
    /// Per-instance scale range `[min, max]`.
    pub scale: [f64; 2],
}

impl Layer {
    /// A Poisson layer with the defaults of `forest:scatter` (density 1, any slope and
    /// altitude, 8 variants, scale 0.8..1.2).
    #[must_use]
    pub fn new(name: impl Into<String>, min_distance: f64) -> Layer {
        Layer {
            name: name.into(),
            method: Method::Poisson,
            min_distance,
            density: Density::Constant(1.0),
            slope: [0.0, 90.0],
            altitude: [f64::NEG_INFINITY, f64::INFINITY],
            variants: Variants::Count(8),
            scale: [0.8, 1.2],
        }
    }

    /// Checks the options; the error names the option and what it needs.
    pub fn check(&self) -> Result<(), ForestError> {
        let bad = |option: &'static str, message: String| ForestError::Option { option, message };
        if !(self.min_distance.is_finite() && self.min_distance > 0.0) {
            return Err(bad(
                "minDistance",
                format!(
                    "must be a positive number of metres, got {}",
                    self.min_distance
                ),
            ));
        }
        if let Density::Constant(d) = self.density
            && !(0.0..=1.0).contains(&d)
        {
            return Err(bad("density", format!("must be in [0, 1], got {d}")));
        }
        if let Method::Jittered { jitter } = self.method
            && !(0.0..0.5).contains(&jitter)
        {
            return Err(bad("jitter", format!("must be in [0, 0.5), got {jitter}")));
        }
        if self.slope[0].partial_cmp(&self.slope[1]) != Some(std::cmp::Ordering::Less)
            && self.slope[0] != self.slope[1]
        {
            return Err(bad(
                "slope",
                format!(
                    "is an empty range: {{{}, {}}} needs min <= max",
                    self.slope[0], self.slope[1]
                ),
            ));
        }
        if self.altitude[0].partial_cmp(&self.altitude[1]) != Some(std::cmp::Ordering::Less)
            && self.altitude[0] != self.altitude[1]
        {
            return Err(bad(
                "altitude",
                format!(
                    "is an empty range: {{{}, {}}} needs min <= max",
                    self.altitude[0], self.altitude[1]
                ),
            ));
        }
        if !(self.scale[0] > 0.0 && self.scale[0] <= self.scale[1] && self.scale[1].is_finite()) {
            return Err(bad(
                "scale",
                format!(
                    "needs 0 < min <= max, got {{{}, {}}}",
                    self.scale[0], self.scale[1]
                ),
            ));
        }
        if self.variants == Variants::Count(0) {
            return Err(bad("variants", "must be at least 1 or \"unique\"".into()));
        }
        Ok(())
    }

    /// The spacing of the jittered grid.
    pub(crate) fn cell(&self, jitter: f64) -> f64 {
        self.min_distance / (1.0 - 2.0 * jitter)
    }

    /// Distance beyond a region from which this layer's sampling reads earlier layers.
    pub(crate) fn reach(&self) -> f64 {
        match self.method {
            Method::Poisson => 4.0 * block_size(self.min_distance) + self.min_distance,
            Method::Jittered { jitter } => self.cell(jitter) + self.min_distance,
        }
    }

    pub(crate) fn estimate(&self, area: f64) -> f64 {
        let dmax = match self.density {
            Density::Constant(d) => d,
            _ => 1.0,
        };
        let per = match self.method {
            Method::Poisson => 0.75 / (self.min_distance * self.min_distance),
            Method::Jittered { jitter } => 1.0 / self.cell(jitter).powi(2),
        };
        area * per * dmax
    }
}
