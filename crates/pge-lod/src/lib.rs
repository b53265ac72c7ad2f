//! PGE foliage levels of detail (seed 003, chapter 2, and its paper "Efficient
//! representation and rendering of trees"): leaves are most of a tree's triangles and all of
//! a forest's cost, so they are simplified by collapsing pairs of leaves into one, and the
//! whole simplification is laid out as one vector V and a LOD table so that any level is
//! drawn with two contiguous ranges of V and every instance of a species shares the same
//! buffers.
//!
//! - [`simplify()`]: the leaf-collapse chain with the thesis' weighted distance and bounds
//!   ([`Weights`], [`Bounds`]) and its new leaf ([`Leaf::collapse`]);
//! - [`LodTable`]: V and the table by V_init and V_fill ([`v_init`], [`v_fill`]), drawn by
//!   [`LodTable::ranges`] (V_render);
//! - [`lod_mesh`]: a leaf mesh rewritten in V's order with its [`MeshLod`](pge_engine::geometry::MeshLod), optionally per
//!   angular sector and with an [`Atlas`] of leaf clusters;
//! - [`assign`]: the leaf budget of a forest (the thesis' Scaling);
//! - [`mask`]: alpha cutoffs chosen with their texture, so that alpha-masked leaves keep
//!   their coverage in a client's own mipmaps, and colour dilated under transparent texels.
//!
//! All of it is plain Rust; the `lua` feature adds the Lua adapter ([`LodPlugin`]:
//! `pge.lod.budget{...}`, and the reading of `lod = {...}` options).
//!
//! ```
//! use glam::Vec3;
//! use pge_lod::{Leaf, LodTable, Selection, simplify};
//!
//! // Eight square leaves in a row, each half overlapping the next.
//! let leaves: Vec<Leaf> = (0..8)
//!     .map(|i| {
//!         let corners = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)]
//!             .map(|(x, y)| Vec3::new(x + i as f32 * 0.5, y, 0.0));
//!         Leaf::from_quad(corners, None).unwrap()
//!     })
//!     .collect();
//! let chain = simplify(&leaves, &Selection::default());
//! let table = LodTable::new(&chain);
//! // The coarsest level draws the roots, the finest the eight leaves.
//! assert_eq!(table.rows[0].a + table.rows[0].c, table.roots);
//! let [first, second] = table.ranges(table.levels() - 1);
//! assert_eq!((first.len(), second.len()), (8, 0));
//! ```

mod atlas;
mod budget;
mod foliage;
mod leaf;
#[cfg(feature = "lua")]
pub mod lua;
pub mod mask;
mod simplify;
mod vector;

pub use atlas::{ATLAS_SIZE, Atlas, CLUSTER_COUNTS, CLUSTER_DENSITIES, Cell};
pub use budget::{Budget, BudgetError, assign, assign_into};
pub use foliage::{
    LodError, LodOptions, MAX_SECTORS, Sector, leaves_of, lod_mesh, mesh_lod, simplify_sectors,
};
pub use leaf::Leaf;
#[cfg(feature = "lua")]
pub use lua::LodPlugin;
pub use simplify::{Axis, Bounds, Chain, Selection, Weights, simplify};
pub use vector::{LodTable, Row, first_levels, v_fill, v_init};
