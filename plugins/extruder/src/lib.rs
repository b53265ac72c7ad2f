//! The extrusion modeller of the PGE thesis (§3.4.4): [`Extruder`] sweeps a 2D shape along a
//! path, [`MatrixManipulator`] moves the path and the shape.

mod extruder;
mod matrix;
mod triangulate;

pub use extruder::{Extruder, ExtruderError, ExtruderOptions, MAX_SHAPE_POINTS, MAX_STATE_DEPTH};
pub use matrix::{MAX_STACK_DEPTH, MatrixError, MatrixManipulator};
pub use triangulate::triangulate;
