//! The growth's per-node arrays made resident ahead, by the tree's mesh memory job
//! ([`pge_tree::MeshMemory::prepare_after`]) before the meshes' arrays: the growth then
//! pushes its nodes into pages already written instead of taking a page fault (about 2 µs)
//! each few hundred nodes on the calling thread. Only where the memory comes from changes:
//! the state's arrays are moved into the room made ahead with the same contents.

use glam::Vec3;
use pge_engine::geometry::ResidentArena;

use super::state::{Pull, State};

/// Room for the state's per-node arrays.
#[derive(Default)]
struct Arrays {
    nodes: Vec<Vec3>,
    parents: Vec<Option<u32>>,
    dirs: Vec<Vec3>,
    headings: Vec<Vec3>,
    has_child: Vec<bool>,
    refused: Vec<u32>,
    pulls: Vec<Pull>,
}

/// The per-node arrays being made ahead (shared by clones; each array is adopted once).
#[derive(Clone)]
pub(super) struct NodeMemory(ResidentArena<Arrays>);

impl Default for NodeMemory {
    /// Memory its [`job`](NodeMemory::job) makes, if someone runs it.
    fn default() -> Self {
        NodeMemory(ResidentArena::open())
    }
}

impl NodeMemory {
    /// The job making room for `nodes` nodes, array by array.
    pub(super) fn job(&self, nodes: usize) -> impl FnOnce() + Send + 'static {
        let arena = self.0.clone();
        move || {
            arena.vec(nodes, Vec3::ZERO, |a| &mut a.nodes);
            arena.vec(nodes, None, |a| &mut a.parents);
            arena.vec(nodes, Vec3::ZERO, |a| &mut a.dirs);
            arena.vec(nodes, Vec3::ZERO, |a| &mut a.headings);
            arena.vec(nodes, false, |a| &mut a.has_child);
            arena.vec(nodes, 0, |a| &mut a.refused);
            arena.vec(nodes, Pull::NONE, |a| &mut a.pulls);
        }
    }

    /// Moves `st`'s per-node arrays into the room made ahead since the last call (each
    /// array once, as it is made): each keeps its contents; one not made yet stays as it
    /// is, for a later call.
    pub(super) fn adopt(&self, st: &mut State) {
        let a = self.0.take_ready();
        move_into(&mut st.nodes, a.nodes);
        move_into(&mut st.parents, a.parents);
        move_into(&mut st.dirs, a.dirs);
        move_into(&mut st.headings, a.headings);
        move_into(&mut st.has_child, a.has_child);
        move_into(&mut st.refused, a.refused);
        move_into(&mut st.pulls, a.pulls);
    }
}

/// `v`'s elements moved into `room` when it has more room than `v`.
fn move_into<T: Copy>(v: &mut Vec<T>, mut room: Vec<T>) {
    if room.capacity() > v.capacity() {
        room.clear();
        room.extend_from_slice(v);
        *v = room;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moved_arrays_keep_their_contents_in_the_larger_room() {
        let mut v = vec![1u32, 2, 3];
        move_into(&mut v, Vec::with_capacity(1000));
        assert_eq!(v, [1, 2, 3]);
        assert!(v.capacity() >= 1000);
        // Too little room: left as it is.
        let mut w = Vec::with_capacity(64);
        w.extend([4u32, 5]);
        move_into(&mut w, Vec::with_capacity(2));
        assert_eq!((w.as_slice(), w.capacity()), (&[4u32, 5][..], 64));
    }

    #[test]
    fn adopted_state_has_the_same_nodes_with_room_and_is_adopted_once() {
        let memory = NodeMemory::default();
        memory.job(500)();
        let mut st = State::new(vec![Vec3::ONE, Vec3::X], 1.0);
        let p = super::super::Params::new(crate::shape::Shape::Ellipsoid {
            center: Vec3::ZERO,
            radii: Vec3::ONE,
        });
        let root = st.push_node(Vec3::ZERO, None, &p);
        st.push_node(Vec3::Y, Some(root), &p);
        let (nodes, parents) = (st.nodes.clone(), st.parents.clone());
        memory.adopt(&mut st);
        assert_eq!((st.nodes.clone(), st.parents.clone()), (nodes, parents));
        assert!(st.nodes.capacity() >= 500 && st.pulls.capacity() >= 500);
        assert_eq!(st.has_child, [true, false]);
        // Adopted: nothing is given again.
        let again = memory.0.take_ready();
        assert_eq!(again.nodes.capacity() + again.pulls.capacity(), 0);
    }
}
