//! Memory made resident ahead of the work that fills it.
//!
//! The first write to a fresh page costs a page fault (the kernel zeroes the page), about
//! 2 µs on this project's machines: for a small tree's meshes, more than the code writing
//! them. Memory allocated and written once by an idle thread, then handed to the work,
//! costs that work no fault ([`ResidentArena`]). Only where the memory comes from changes,
//! never what is written into it.

use std::mem::size_of;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

/// A set of arrays `T` (its default holds none) made resident ahead: a job on an idle
/// rayon pool thread ([`ResidentArena::start`]) allocates them part by part, writing once
/// into every page of each ([`ResidentArena::vec`], [`ResidentArena::part`]), while the
/// calling thread does other work; that work then takes them once ([`ResidentArena::take`])
/// and writes into them. Parts not made by then are the default (the work allocates fresh
/// memory as it would without an arena) and are not made any more (or the work takes them
/// as they come, [`ResidentArena::take_ready`]). Cloning shares the arena: the first to
/// take gets what is ready, the others the default.
pub struct ResidentArena<T> {
    /// The arrays made so far (`None` once taken); no slot when nothing is made ahead.
    slot: Option<Arc<Mutex<Option<T>>>>,
}

impl<T> Clone for ResidentArena<T> {
    fn clone(&self) -> Self {
        ResidentArena {
            slot: self.slot.clone(),
        }
    }
}

impl<T> Default for ResidentArena<T> {
    fn default() -> Self {
        ResidentArena::none()
    }
}

impl<T> std::fmt::Debug for ResidentArena<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let state = match &self.slot {
            None => "none",
            Some(slot) if lock(slot).is_some() => "open",
            Some(_) => "taken",
        };
        f.debug_struct("ResidentArena")
            .field("state", &state)
            .finish()
    }
}

impl<T> ResidentArena<T> {
    /// Nothing made ahead: [`take`](Self::take) gives the default.
    #[must_use]
    pub fn none() -> ResidentArena<T> {
        ResidentArena { slot: None }
    }

    /// Whether parts can still be made: the arena was opened and not taken yet.
    #[must_use]
    pub fn is_open(&self) -> bool {
        self.slot.as_ref().is_some_and(|slot| lock(slot).is_some())
    }
}

impl<T: Default> ResidentArena<T> {
    /// An arena whose parts are made by the caller ([`vec`](Self::vec),
    /// [`part`](Self::part)) on the thread it chooses.
    #[must_use]
    pub fn open() -> ResidentArena<T> {
        ResidentArena {
            slot: Some(Arc::new(Mutex::new(Some(T::default())))),
        }
    }

    /// Starts `job` making the arena's parts on the rayon pool when the calling thread is
    /// not one of the pool's and the pool has more than one thread (so a pool thread is idle
    /// while the caller works); [`none`](Self::none), without running `job`, otherwise.
    #[must_use]
    pub fn start(job: impl FnOnce(&ResidentArena<T>) + Send + 'static) -> ResidentArena<T>
    where
        T: Send + 'static,
    {
        let idle_pool = rayon::current_thread_index().is_none() && rayon::current_num_threads() > 1;
        if !idle_pool {
            return ResidentArena::none();
        }
        let arena = ResidentArena::open();
        let shared = arena.clone();
        rayon::spawn(move || job(&shared));
        arena
    }

    /// Makes the part `field` of the arrays an empty vector with room for `n` elements,
    /// every page of its room written once (with `fill`), unless the arrays were taken.
    /// Returns whether they were still open.
    pub fn vec<E: Copy>(
        &self,
        n: usize,
        fill: E,
        field: impl FnOnce(&mut T) -> &mut Vec<E>,
    ) -> bool {
        self.part(|| resident_vec(n, fill), field)
    }

    /// Makes a part with `make` (memory made resident, as [`SearchMemory::resident`] does)
    /// and puts it where `field` says, unless the arrays were taken (then `make` is not
    /// run). Returns whether they were still open.
    pub fn part<P>(&self, make: impl FnOnce() -> P, field: impl FnOnce(&mut T) -> &mut P) -> bool {
        let Some(slot) = &self.slot else {
            return false;
        };
        if lock(slot).is_none() {
            return false;
        }
        let part = make();
        match lock(slot).as_mut() {
            Some(arrays) => {
                *field(arrays) = part;
                true
            }
            None => false,
        }
    }

    /// The arrays made so far (the default for the parts not made); no part is made after.
    pub fn take(&self) -> T {
        self.slot
            .as_ref()
            .and_then(|slot| lock(slot).take())
            .unwrap_or_default()
    }

    /// The parts made so far (the default for the others), leaving the arena open: the
    /// parts made later are for the next call. For work that can adopt memory part by part
    /// as it arrives.
    pub fn take_ready(&self) -> T {
        self.slot
            .as_ref()
            .and_then(|slot| lock(slot).as_mut().map(std::mem::take))
            .unwrap_or_default()
    }
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// An empty vector with room for `n` elements, one element of the room written (with
/// `fill`) in every 4 kB so every page of it is resident; the written elements are not
/// part of the vector.
#[must_use]
pub(super) fn resident_vec<T: Copy>(n: usize, fill: T) -> Vec<T> {
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

    /// Arrays of the tests' arenas.
    #[derive(Default)]
    struct Arrays {
        points: Vec<glam::Vec3>,
        indices: Vec<u32>,
        search: SearchMemory,
    }

    #[test]
    fn an_arena_gives_its_parts_once_with_their_room() {
        let arena = ResidentArena::<Arrays>::open();
        assert!(arena.is_open());
        assert!(arena.vec(5000, glam::Vec3::ZERO, |a| &mut a.points));
        assert!(arena.part(|| SearchMemory::resident(300, 100), |a| &mut a.search));
        let shared = arena.clone();
        let a = arena.take();
        assert!(a.points.is_empty() && a.points.capacity() >= 5000);
        assert!(a.search.hashes.capacity() >= 300);
        // The part not made is the default: fresh memory.
        assert_eq!(a.indices.capacity(), 0);
        // Taken: a clone gets the default, and nothing more is made.
        assert!(!shared.is_open());
        assert_eq!(shared.take().points.capacity(), 0);
        let made = !shared.part(
            || -> Vec<u32> { panic!("made after the take") },
            |a| &mut a.indices,
        );
        assert!(made);
        assert!(!shared.vec(10, 0, |a| &mut a.indices));
    }

    #[test]
    fn parts_taken_as_they_come_are_taken_once_each() {
        let arena = ResidentArena::<Arrays>::open();
        arena.vec(100, 1u32, |a| &mut a.indices);
        let first = arena.take_ready();
        assert!(first.indices.capacity() >= 100 && first.points.capacity() == 0);
        // Still open: the next part is for the next call, the first is not given again.
        assert!(arena.vec(200, glam::Vec3::ONE, |a| &mut a.points));
        let second = arena.take_ready();
        assert!(second.points.capacity() >= 200 && second.indices.capacity() == 0);
        assert_eq!(arena.take_ready().points.capacity(), 0);
        assert!(arena.is_open());
    }

    #[test]
    fn an_arena_of_nothing_made_ahead_runs_no_part() {
        let none = ResidentArena::<Arrays>::none();
        assert!(!none.is_open());
        assert!(!none.part(|| -> Vec<u32> { panic!("made") }, |a| &mut a.indices));
        assert_eq!(none.take().points.capacity(), 0);
        // On a pool thread no job starts: the pool is busy with the caller's work.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("pool");
        let started = pool.install(|| {
            ResidentArena::<Arrays>::start(|_| panic!("started on a busy pool")).is_open()
        });
        assert!(!started);
    }

    #[test]
    fn a_started_arena_makes_its_parts_on_an_idle_pool() {
        // A test's thread is none of the global pool's: the job starts when that pool has
        // a thread to spare.
        let (done, wait) = std::sync::mpsc::channel();
        let arena = ResidentArena::<Arrays>::start(move |arena| {
            arena.vec(1000, 7u32, |a| &mut a.indices);
            done.send(()).expect("sent");
        });
        if rayon::current_num_threads() > 1 {
            assert!(arena.is_open());
            wait.recv().expect("the job ran");
            assert!(arena.take().indices.capacity() >= 1000);
        } else {
            assert!(!arena.is_open());
            assert!(wait.recv().is_err(), "no job on a pool of one thread");
        }
    }
}
