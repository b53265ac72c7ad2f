//! Geometry: what every generator produces and every exporter writes.
//!
//! A [`Model`] holds shared [`Mesh`]es and the instances that place them; a mesh owns its
//! [`Material`], which may carry a PNG [`Texture`]. Trees also attach their branch
//! [`Skeleton`] to the bark mesh so games can read the graph back from the glTF extras.

mod material;
mod mesh;
mod model;
mod resident;
mod skeleton;
mod tangents;
mod triangles;

pub use material::{AlphaMode, DiffuseTransmission, Material, Texture};
pub use mesh::{GeometryError, Mesh, Primitive};
pub use model::{Instance, InstanceGroup, InstanceTransform, Model, PlacementLeaves, Stats};
pub use resident::{SearchMemory, resident_vec};
pub use skeleton::{LeafPoint, Skeleton};
pub use triangles::DegenerateTest;
