//! Geometry: what every generator produces and every exporter writes.
//!
//! A [`Model`] holds shared [`Mesh`]es and the instances that place them; a mesh owns its
//! [`Material`], which may carry a PNG or JPEG [`Texture`]. Trees also attach their branch
//! [`Skeleton`] to the bark mesh so games can read the graph back from the glTF extras, and
//! leaf meshes written for levels of detail their [`MeshLod`]; a forest's model records the
//! forest ([`ForestStats`]). [`binary`] is a model's exact binary form.

pub mod binary;
mod forest;
mod lod;
mod material;
mod mesh;
mod model;
mod resident;
mod skeleton;
mod tangents;
mod triangles;

pub use forest::{ForestPart, ForestStats, SpeciesCount, VariantCounts};
pub use lod::{GroupLod, LodError, LodLevel, LodSector, LodTable, MeshLod, PrimitiveLod};
pub use material::{AlphaMode, DiffuseTransmission, ImageFormat, Material, Texture};
pub use mesh::{GeometryError, Mesh, Primitive};
pub use model::{Instance, InstanceGroup, InstanceTransform, Model, PlacementLeaves, Stats};
pub use resident::{ResidentArena, SearchMemory};
pub use skeleton::{LeafPoint, Skeleton};
pub use triangles::DegenerateTest;
