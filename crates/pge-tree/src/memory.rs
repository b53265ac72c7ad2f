//! Memory for a tree's meshes made resident ahead of time, on an idle pool thread.
//!
//! The first write to a fresh page costs a page fault (the kernel zeroes the page), about
//! 2 µs each: for the oak's bark and leaves (1.4 MB) some 0.9 ms of the meshing, which is
//! all on its critical path. A generator that knows roughly how big its tree will be can
//! start a [`MeshMemory`] before it grows the skeleton: a job on the rayon pool allocates
//! the meshes' arrays and writes once into every page of them, while the calling thread
//! grows the tree; [`build_tree_in`](crate::build_tree_in) then writes the meshes into
//! those arrays. Only where the memory comes from changes: the same meshes, to the byte.
//! Arrays the job has not finished when the tree is built are left to it and dropped, and
//! the tree uses fresh memory as [`build_tree`](crate::build_tree) does; an array smaller
//! than the mesh grows as a fresh one would.

use glam::{Vec2, Vec3, Vec4};
use pge_engine::geometry::{LeafPoint, ResidentArena, SearchMemory};

use crate::TreeOptions;

/// How many elements a tree's mesh arrays are expected to reach (see
/// [`MeshSizes::of_nodes`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MeshSizes {
    /// The bark's vertices (positions, normals and uvs each).
    pub bark_vertices: usize,
    /// The bark's indices (three a triangle).
    pub bark_indices: usize,
    /// The leaves (four vertices and six indices each).
    pub leaves: usize,
}

impl MeshSizes {
    /// The sizes of a tree whose prepared skeleton (straight chains merged) has `nodes`
    /// nodes, meshed with `options`, a little over what the library's species need: their
    /// bark has 1.43-1.53 rings of `sides + 1` vertices and 6.7-6.8 indices a side per
    /// node, and their leaves number 0.17-0.21 times the most leaves a tip bears, per node.
    #[must_use]
    pub fn of_nodes(nodes: usize, options: &TreeOptions) -> MeshSizes {
        let sides = options.mesh.sides.clamp(3, 1024) as usize;
        let per_tip = options.leaves.as_ref().map_or(0, |l| {
            let (lo, hi) = l.per_tip;
            lo.max(hi) as usize
        });
        MeshSizes {
            bark_vertices: nodes * (sides + 1) * 8 / 5,
            bark_indices: nodes * sides * 7,
            leaves: nodes * per_tip / 4,
        }
    }
}

/// Arrays with room for a tree's meshes, every page of their room written once.
#[derive(Default)]
pub(crate) struct Buffers {
    pub(crate) bark: BarkBuffers,
    pub(crate) leaves: LeafBuffers,
}

/// The bark mesh's arrays.
#[derive(Default)]
pub(crate) struct BarkBuffers {
    pub(crate) positions: Vec<Vec3>,
    pub(crate) normals: Vec<Vec3>,
    pub(crate) uvs: Vec<Vec2>,
    pub(crate) indices: Vec<u32>,
}

/// The leaf mesh's arrays, the tip leaves and the leaf mesh's search.
#[derive(Default)]
pub(crate) struct LeafBuffers {
    pub(crate) tips: Vec<LeafPoint>,
    pub(crate) search: SearchMemory,
    pub(crate) positions: Vec<Vec3>,
    pub(crate) normals: Vec<Vec3>,
    pub(crate) uvs: Vec<Vec2>,
    pub(crate) colors: Vec<Vec4>,
    pub(crate) indices: Vec<u32>,
}

/// Memory for a tree's meshes, being made resident on the rayon pool while the tree grows
/// (a fault a page taken there, off the meshing's path); give it to
/// [`build_tree_in`](crate::build_tree_in), which writes the same meshes into it. Cloning
/// shares it: the first tree built takes what is ready, the others get fresh memory.
#[derive(Clone, Default)]
pub struct MeshMemory(ResidentArena<Buffers>);

/// Bark vertices below which a tree's memory is made ahead (a few MB at most): bigger trees
/// grow on the whole pool, and a wrong guess would waste more.
const AHEAD_BELOW: usize = 1 << 16;

impl MeshMemory {
    /// No memory made ahead: the meshes get fresh memory.
    #[must_use]
    pub fn none() -> MeshMemory {
        MeshMemory::default()
    }

    /// Starts making memory of `sizes` resident on a pool thread, when the calling thread is
    /// not one of the pool's (so the pool is idle while it grows the tree), the pool has more
    /// than one thread and the tree is small (under 64 k bark vertices); [`none`](Self::none)
    /// otherwise ([`ResidentArena::start`]).
    #[must_use]
    pub fn prepare(sizes: MeshSizes) -> MeshMemory {
        MeshMemory::prepare_after(sizes, || {})
    }

    /// [`prepare`](Self::prepare), the job first running `first` (the generator's own
    /// memory, needed sooner than the meshes'); `first` is not run when no job starts.
    #[must_use]
    pub fn prepare_after(sizes: MeshSizes, first: impl FnOnce() + Send + 'static) -> MeshMemory {
        if sizes.bark_vertices >= AHEAD_BELOW {
            return MeshMemory::none();
        }
        MeshMemory(ResidentArena::start(move |arena| {
            first();
            make(arena, sizes);
        }))
    }

    /// Memory made ahead on the calling thread (tests).
    #[cfg(test)]
    pub(crate) fn made_now(sizes: MeshSizes) -> MeshMemory {
        let arena = ResidentArena::open();
        make(&arena, sizes);
        MeshMemory(arena)
    }

    /// The arrays made so far (empty ones for the rest); the job stops making more.
    pub(crate) fn take(&self) -> Buffers {
        self.0.take()
    }
}

/// Makes each array in turn, the bark's first (the calling thread's), unless the arrays
/// were taken meanwhile.
fn make(arena: &ResidentArena<Buffers>, sizes: MeshSizes) {
    let origin = LeafPoint {
        node: 0,
        position: Vec3::ZERO,
        direction: Vec3::ZERO,
        side: Vec3::ZERO,
        size: 0.0,
    };
    let (v, i, l) = (sizes.bark_vertices, sizes.bark_indices, sizes.leaves);
    arena.vec(v, Vec3::ZERO, |b| &mut b.bark.positions);
    arena.vec(v, Vec3::ZERO, |b| &mut b.bark.normals);
    arena.vec(v, Vec2::ZERO, |b| &mut b.bark.uvs);
    arena.vec(i, 0, |b| &mut b.bark.indices);
    arena.vec(l, origin, |b| &mut b.leaves.tips);
    arena.vec(4 * l, Vec3::ZERO, |b| &mut b.leaves.positions);
    arena.vec(4 * l, Vec3::ZERO, |b| &mut b.leaves.normals);
    arena.vec(4 * l, Vec2::ZERO, |b| &mut b.leaves.uvs);
    arena.vec(4 * l, Vec4::ZERO, |b| &mut b.leaves.colors);
    arena.vec(6 * l, 0, |b| &mut b.leaves.indices);
    arena.part(
        || SearchMemory::resident(4 * l, 2 * l),
        |b| &mut b.leaves.search,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LeafOptions, MeshOptions};

    #[test]
    fn sizes_follow_the_nodes_sides_and_leaves_per_tip() {
        let options = TreeOptions {
            mesh: MeshOptions {
                sides: 10,
                ..MeshOptions::default()
            },
            leaves: Some(LeafOptions {
                per_tip: (6, 9),
                ..LeafOptions::default()
            }),
            lod: None,
        };
        let sizes = MeshSizes::of_nodes(1000, &options);
        assert_eq!(
            sizes,
            MeshSizes {
                bark_vertices: 17_600,
                bark_indices: 70_000,
                leaves: 2_250,
            }
        );
        let bare = TreeOptions {
            leaves: None,
            ..options
        };
        assert_eq!(MeshSizes::of_nodes(1000, &bare).leaves, 0);
    }

    #[test]
    fn made_memory_is_empty_with_room_and_taken_once() {
        let sizes = MeshSizes {
            bark_vertices: 5000,
            bark_indices: 20_000,
            leaves: 300,
        };
        let memory = MeshMemory::made_now(sizes);
        let shared = memory.clone();
        let b = memory.take();
        assert!(b.bark.positions.is_empty() && b.bark.positions.capacity() >= 5000);
        assert!(b.bark.normals.capacity() >= 5000 && b.bark.uvs.capacity() >= 5000);
        assert!(b.bark.indices.is_empty() && b.bark.indices.capacity() >= 20_000);
        assert!(b.leaves.tips.is_empty() && b.leaves.tips.capacity() >= 300);
        assert!(b.leaves.colors.is_empty() && b.leaves.colors.capacity() >= 1200);
        assert!(b.leaves.indices.capacity() >= 1800);
        // Taken: a clone (or a second tree) gets fresh memory.
        assert_eq!(shared.take().bark.positions.capacity(), 0);
        assert_eq!(MeshMemory::none().take().leaves.tips.capacity(), 0);
    }

    #[test]
    fn a_big_tree_starts_no_job_and_runs_nothing_first() {
        let sizes = MeshSizes {
            bark_vertices: AHEAD_BELOW,
            bark_indices: 0,
            leaves: 0,
        };
        let memory = MeshMemory::prepare_after(sizes, || panic!("run for a big tree"));
        assert!(!memory.0.is_open());
    }
}
