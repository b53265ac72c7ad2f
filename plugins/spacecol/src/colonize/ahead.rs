//! The growth's per-node arrays made resident ahead, by the tree's mesh memory job
//! ([`pge_tree::MeshMemory::prepare_after`]) before the meshes' arrays: the growth then
//! pushes its nodes into pages already written instead of taking a page fault (about 2 µs)
//! each few hundred nodes on the calling thread. Only where the memory comes from changes:
//! the state's arrays are moved into the room made ahead with the same contents.

use std::sync::{Arc, Mutex, PoisonError};

use glam::Vec3;
use pge_engine::geometry::resident_vec;

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

/// The per-node arrays being made ahead (shared by clones; the first to adopt them takes
/// them).
#[derive(Clone, Default)]
pub(super) struct NodeMemory(Arc<Mutex<Option<Arrays>>>);

impl NodeMemory {
    /// The job making room for `nodes` nodes; it puts the arrays here when done.
    pub(super) fn job(&self, nodes: usize) -> impl FnOnce() + Send + 'static {
        let slot = Arc::clone(&self.0);
        move || {
            let arrays = Arrays {
                nodes: resident_vec(nodes, Vec3::ZERO),
                parents: resident_vec(nodes, None),
                dirs: resident_vec(nodes, Vec3::ZERO),
                headings: resident_vec(nodes, Vec3::ZERO),
                has_child: resident_vec(nodes, false),
                refused: resident_vec(nodes, 0),
                pulls: resident_vec(nodes, Pull::NONE),
            };
            *slot.lock().unwrap_or_else(PoisonError::into_inner) = Some(arrays);
        }
    }

    /// Moves `st`'s per-node arrays into the room made ahead, if it is ready (once): each
    /// array keeps its contents.
    pub(super) fn adopt(&self, st: &mut State) {
        let ready = self.0.lock().unwrap_or_else(PoisonError::into_inner).take();
        let Some(a) = ready else {
            return;
        };
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
        move_into(&mut v, resident_vec(1000, 7));
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
        assert!(memory.0.lock().expect("not poisoned").is_none());
    }
}
