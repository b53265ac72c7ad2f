//! Metaballs and marching cubes, the organic modeller of the PGE thesis (§3.4.4): a
//! [`Metaballs`] field of charged particles and [`MarchingCubes`], which extracts its
//! isosurface as a closed mesh with normals from the field's gradient.

mod field;
mod march;
pub mod table;

pub use field::{FieldError, MAX_PARTICLES, Metaballs, Particle};
pub use march::{MAX_RESOLUTION, MarchError, MarchOptions, MarchStats, MarchingCubes};
