//! Memory made resident ahead of the work that fills it.
//!
//! The first write to a fresh page costs a page fault (the kernel zeroes the page), about
//! 2 µs on this project's machines: for a small tree's meshes, more than the code writing
//! them. Memory allocated and written once by an idle thread, then handed to the work,
//! costs that work no fault. Only where the memory comes from changes, never what is
//! written into it.

use std::mem::size_of;

/// An empty vector with room for `n` elements, one element of the room written (with
/// `fill`) in every 4 kB so every page of it is resident; the written elements are not
/// part of the vector.
#[must_use]
pub fn resident_vec<T: Copy>(n: usize, fill: T) -> Vec<T> {
    let mut v = Vec::with_capacity(n);
    if size_of::<T>() == 0 {
        // No memory (and a room of `usize::MAX`).
        return v;
    }
    // At most 4 kB apart: every page holds a written byte.
    let stride = (4096 / size_of::<T>()).max(1);
    for slot in v.spare_capacity_mut()[..n].iter_mut().step_by(stride) {
        slot.write(fill);
    }
    v
}

/// Memory for the unusable-triangle search of a small mesh
/// ([`Mesh::unusable_triangles_in`](super::Mesh::unusable_triangles_in)): its vertices'
/// hashes and its table. The default has none (the search allocates it).
#[derive(Debug, Default)]
pub struct SearchMemory {
    pub(super) hashes: Vec<u64>,
    pub(super) slots: Vec<u32>,
}

impl SearchMemory {
    /// Resident memory for a mesh of up to `vertices` vertices and `triangles` triangles.
    #[must_use]
    pub fn resident(vertices: usize, triangles: usize) -> SearchMemory {
        SearchMemory {
            hashes: resident_vec(vertices, 0),
            slots: resident_vec(super::triangles::small_table_len(triangles), 0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resident_vectors_are_empty_with_their_room() {
        for n in [0, 1, 341, 342, 10_000] {
            let v = resident_vec(n, glam::Vec3::ONE);
            assert!(v.is_empty());
            assert!(v.capacity() >= n);
        }
        assert!(resident_vec(100, ()).capacity() >= 100);
        let m = SearchMemory::resident(400, 200);
        assert!(m.hashes.is_empty() && m.hashes.capacity() >= 400);
        assert!(m.slots.is_empty() && m.slots.capacity() >= 400);
    }
}
