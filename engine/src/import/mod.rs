//! glTF in: the reader beside the [`export`](crate::export) writer.
//!
//! Every file is validated before a byte of it is read, so that a damaged or hostile file
//! is an [`ImportError`], never a panic: accessor indices in range ([`open`]), every
//! accessor inside its view, every view inside its buffer, every buffer inside its data and
//! no `byteStride` smaller than its element ([`check_bounds`]).
//!
//! Two readers share those checks: [`read_mesh`] (with [`read_instances`] and
//! [`leaf_counts`]) reads PGE's own glb back into [`Mesh`](crate::geometry::Mesh)es, materials
//! and placements (what `pge merge` joins), and [`scene_triangles`] reads the triangles of
//! any glTF's default scene, placed by its node transforms (a mesh envelope).
//!
//! ```
//! use glam::Vec3;
//! use pge_engine::export::glb_bytes;
//! use pge_engine::geometry::{Mesh, Model};
//!
//! let mesh = Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).unwrap();
//! let glb = glb_bytes(&Model::from_mesh(mesh), &Default::default()).unwrap();
//! let (positions, triangles) = pge_engine::import::scene_triangles(&glb).unwrap();
//! assert_eq!((positions.len(), triangles), (3, vec![[0, 1, 2]]));
//! ```

mod read;
mod scene;

pub use read::{
    check_bounds, check_layout, leaf_counts, read_instances, read_mesh, relative_file, split_lod,
};
pub use scene::{open, scene_triangles};

/// Why a glTF file cannot be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImportError {
    /// Not glTF or glb, or glTF the `gltf` crate refuses.
    #[error("{0}")]
    Gltf(#[from] gltf::Error),
    /// An `extras` text that is not JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// A primitive attribute names an accessor that does not exist.
    #[error("meshes[{mesh}].primitives[{primitive}] names accessor {accessor} of {count}")]
    AccessorIndex {
        /// The mesh.
        mesh: usize,
        /// The primitive in the mesh.
        primitive: usize,
        /// The accessor named.
        accessor: usize,
        /// How many accessors there are.
        count: usize,
    },
    /// A buffer is longer than the data present for it.
    #[error("buffer {buffer} is not in {what}")]
    BufferMissing {
        /// The buffer.
        buffer: usize,
        /// Where its data should be: the binary chunk, or the file it names.
        what: &'static str,
    },
    /// A buffer view goes past the end of its buffer.
    #[error("buffer view {0} goes past its buffer")]
    ViewPastBuffer(usize),
    /// A sparse accessor.
    #[error("accessor {0} is sparse, which PGE never writes")]
    Sparse(usize),
    /// An accessor without a buffer view.
    #[error("accessor {0} has no buffer view")]
    NoView(usize),
    /// A view's `byteStride` is smaller than the element of an accessor in it.
    #[error(
        "accessor {accessor}: its view's byteStride {stride} is smaller than its {size}-byte element"
    )]
    StrideTooSmall {
        /// The accessor.
        accessor: usize,
        /// The view's stride.
        stride: usize,
        /// The accessor's element size in bytes.
        size: usize,
    },
    /// An accessor goes past the end of its buffer view.
    #[error("accessor {0} goes past its buffer view")]
    AccessorPastView(usize),
    /// A node's leaf counts (`extras.pge.lod.leaves`) do not match its placements.
    #[error("a node's extras.pge.lod.leaves do not match its {placements} placements")]
    LeafCounts {
        /// The node's placements.
        placements: usize,
    },
    /// An instancing node lacks a float accessor for an attribute.
    #[error("an instancing node without a float {0} accessor")]
    InstancingMissing(&'static str),
    /// An instancing accessor has the wrong type.
    #[error("the instancing {attribute} accessor is not {expected}")]
    InstancingType {
        /// The attribute (TRANSLATION, ROTATION, SCALE).
        attribute: &'static str,
        /// The type it needs.
        expected: &'static str,
    },
    /// An instancing accessor's data cannot be read.
    #[error("the instancing {0} data is missing")]
    InstancingData(&'static str),
    /// The instancing accessors have different lengths.
    #[error("the instancing accessors differ in length")]
    InstancingLengths,
    /// A primitive mode PGE does not write (points, strips, fans).
    #[error("mesh {mesh}: {mode} primitives are not PGE's")]
    Primitive {
        /// The mesh's name.
        mesh: String,
        /// The mode.
        mode: String,
    },
    /// A mesh lacks an attribute PGE always writes.
    #[error("mesh {mesh}: no {attribute}")]
    MissingAttribute {
        /// The mesh's name.
        mesh: String,
        /// What is missing: positions, indices.
        attribute: &'static str,
    },
    /// POSITION is not float VEC3, as glTF requires.
    #[error("accessor {0} (POSITION) must be FLOAT VEC3")]
    PositionType(usize),
    /// Indices are not unsigned integer scalars, as glTF requires.
    #[error("accessor {0} (indices) must be an unsigned integer SCALAR")]
    IndexType(usize),
    /// A vertex attribute whose accessor type glTF does not allow for it.
    #[error("accessor {accessor} ({attribute}) must be {expected}")]
    AttributeType {
        /// The accessor.
        accessor: usize,
        /// The attribute (NORMAL, TEXCOORD_0, COLOR_0).
        attribute: String,
        /// The types it may have.
        expected: &'static str,
    },
    /// The node graph has a cycle or a shared child.
    #[error("the node hierarchy is not a tree (a cycle or a shared child)")]
    NotATree,
    /// An image that is not in a buffer view of the file.
    #[error("an image outside the .glb")]
    ImageOutsideGlb,
    /// An image view outside its buffer.
    #[error("an image outside its buffer")]
    ImageOutsideBuffer,
    /// An image that is neither a PNG nor a JPEG.
    #[error("an image that is neither a PNG nor a JPEG")]
    NotPng,
    /// A buffer URI that is not a relative file name.
    #[error("buffer URI '{0}' is not a relative file")]
    BufferUri(String),
}

impl ImportError {
    fn missing(mesh: &str, attribute: &'static str) -> ImportError {
        ImportError::MissingAttribute {
            mesh: mesh.to_string(),
            attribute,
        }
    }
}
