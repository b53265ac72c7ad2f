//! A small tree's bark written by two threads: the calling thread, and the leaves' thread
//! once the leaves are made.

use std::collections::VecDeque;
use std::sync::{Mutex, PoisonError};
use std::time::Instant;

use pge_engine::geometry::{DistinctTest, Mesh, Skeleton};

use super::Tubes;
use super::rings::{Checks, Scratch, Slices};
use crate::options::MeshOptions;

/// Chunks a [`SharedBark`]'s tubes are dealt in (of about as many vertices each): fewer
/// leave one thread waiting longer for the other's last chunk, more cost more claims.
const CHUNKS: usize = 32;

/// A bark mesh written in chunks of consecutive tubes, taken by the calling thread from the
/// front and by a helper from the back, every tube checked as it is written (see
/// [`SharedBark::finish`]). Its arrays are allocated zeroed, which for fresh memory touches
/// no page: each page is first touched by the thread that writes it.
pub(crate) struct SharedBark {
    tubes: Tubes,
    mesh: Mesh,
}

/// The chunks of a [`SharedBark`] not taken yet.
pub(crate) struct Chunks<'a> {
    tubes: &'a Tubes,
    /// The mesh's vertices.
    vertices: usize,
    queue: Mutex<VecDeque<Chunk<'a>>>,
}

/// Consecutive tubes from tube `first` on, each with its slices of the mesh.
struct Chunk<'a> {
    first: usize,
    sinks: Vec<Slices<'a>>,
}

/// What one thread wrote: each chunk's first tube with the chunk's checks, the positions it
/// wrote (added to a [`DistinctTest`] tube by tube, while in the cache), and when its last
/// chunk was done (`None` when it found none left).
pub(crate) struct Written {
    chunks: Vec<(usize, Checks)>,
    places: DistinctTest,
    pub(crate) done: Option<Instant>,
}

impl SharedBark {
    /// The bark of `skeleton` (see [`append_bark`](super::append_bark)), placed in a mesh
    /// named `bark` and not written yet.
    pub(crate) fn new(skeleton: &Skeleton, options: &MeshOptions) -> SharedBark {
        let tubes = Tubes::of(skeleton, options);
        let (vertices, indices) = tubes.size();
        let mesh = Mesh {
            name: "bark".into(),
            positions: bytemuck::zeroed_vec(vertices),
            normals: bytemuck::zeroed_vec(vertices),
            uvs: bytemuck::zeroed_vec(vertices),
            indices: vec![0; indices],
            ..Mesh::default()
        };
        SharedBark { tubes, mesh }
    }

    /// The tubes in chunks, for [`Chunks::write`].
    pub(crate) fn chunks(&mut self) -> Chunks<'_> {
        let (vertices, _) = self.tubes.size();
        let per_chunk = vertices.div_ceil(CHUNKS).max(1);
        let mut queue = VecDeque::with_capacity(CHUNKS + 1);
        let mut chunk = Chunk {
            first: 0,
            sinks: Vec::new(),
        };
        let mut filled = 0;
        let sinks = self.tubes.sinks(&mut self.mesh, 0, 0);
        for ((k, sink), &(tube_vertices, _)) in
            sinks.into_iter().enumerate().zip(&self.tubes.counts)
        {
            chunk.sinks.push(sink);
            filled += tube_vertices;
            if filled >= per_chunk {
                let next = Chunk {
                    first: k + 1,
                    sinks: Vec::new(),
                };
                queue.push_back(std::mem::replace(&mut chunk, next));
                filled = 0;
            }
        }
        if !chunk.sinks.is_empty() {
            queue.push_back(chunk);
        }
        Chunks {
            tubes: &self.tubes,
            vertices,
            queue: Mutex::new(queue),
        }
    }

    /// The mesh, once every chunk is written (by the [`Written`] given), and whether it is
    /// shown to have no unusable triangle by construction: its tubes' triangles are
    /// distinct, so only degenerate triangles (none was found as they were written) and
    /// vertices at one place other than the twins named as they were written (see
    /// [`Mesh::distinct_positions`]) could make one. `false` when that was not shown (then
    /// search it).
    pub(crate) fn finish(self, written: impl IntoIterator<Item = Written>) -> (Mesh, bool) {
        let mut places = DistinctTest::new(self.mesh.positions.len());
        let mut chunks: Vec<(usize, Checks)> = Vec::new();
        for w in written {
            places.merge(&w.places);
            chunks.extend(w.chunks);
        }
        chunks.sort_unstable_by_key(|&(first, _)| first);
        let degenerate = chunks.iter().any(|(_, checks)| checks.test.found());
        let twins: Vec<(u32, u32)> = chunks
            .iter()
            .flat_map(|(_, checks)| &checks.twins)
            .copied()
            .collect();
        let clean = !degenerate && places.distinct(&self.mesh.positions, &twins);
        (self.mesh, clean)
    }
}

impl Chunks<'_> {
    /// Writes chunks, each taken from the front (or the back) of those left, until none is
    /// left.
    pub(crate) fn write(&self, from_front: bool) -> Written {
        let mut scratch = Scratch::default();
        let mut written = Written {
            chunks: Vec::new(),
            places: DistinctTest::new(self.vertices),
            done: None,
        };
        loop {
            let next = {
                let mut queue = self.queue.lock().unwrap_or_else(PoisonError::into_inner);
                if from_front {
                    queue.pop_front()
                } else {
                    queue.pop_back()
                }
            };
            let Some(chunk) = next else {
                return written;
            };
            let mut checks = Checks::default();
            for (k, mut sink) in (chunk.first..).zip(chunk.sinks) {
                let twins = checks.twins.len();
                self.tubes
                    .emit(k, &mut scratch, &mut sink, Some(&mut checks));
                let first = sink.first as usize;
                written
                    .places
                    .add(first, sink.positions, &checks.twins[twins..]);
            }
            written.chunks.push((chunk.first, checks));
            written.done = Some(Instant::now());
        }
    }
}
