//! Finding the triangles no client can use: degenerate ones and repeats of an earlier one.
//!
//! Each triangle gets a hash of its corners' bits that does not depend on the corner its
//! indices start at (a sum over its three edges, each edge hashed from its two corners in
//! turning order), and the first triangle of each hash is kept in an open-addressing table
//! of tags and triangle numbers; a later triangle whose tag matches is compared by its
//! corners (a repeat, or, very rarely, another triangle with the same tag). A corner's own
//! hash is computed once per vertex, not once per triangle it is a corner of (about six in
//! a mesh of tubes or grids).
//!
//! A small mesh is searched in one pass, in order. A large one is hashed and dealt into
//! shards by its hash, in runs of triangles in parallel; then each shard, in parallel, finds
//! its repeats with a table of its own, reading its triangles from the runs in order. A
//! repeat and the triangle it repeats share a hash, hence a shard, and a shard meets its
//! triangles in order, so the first of equal triangles is the one kept, whatever the number
//! of shards or threads.

use glam::Vec3;
use rayon::prelude::*;

use super::SearchMemory;

/// Triangles a thread hashes at a time.
const KEY_CHUNK: usize = 1 << 15;

/// Below this many triangles, one pass on the calling thread (the work is smaller than
/// handing it to another).
const SHARDED_FROM: usize = 1 << 15;

/// Shards of a large mesh, as a power of two: each shard's table of a 2 M-triangle mesh
/// holds about 16 k triangles (about 256 kB), which stays in the cache.
const SHARD_BITS: u32 = 7;

/// A run of triangles after pass 1: each shard's hashes with their triangles, and the
/// degenerate triangles, in increasing order.
type Run = (Vec<Vec<(u64, u32)>>, Vec<usize>);

/// What a triangle is to the search.
enum Look {
    /// A corner is past the vertices: kept (validation rejects the mesh).
    Outside,
    /// No area.
    Degenerate,
    /// Usable unless it repeats an earlier triangle of the same hash.
    Hashed(u64),
}

/// The triangles of `indices` (three a triangle) that no client can use, in increasing
/// order: degenerate ones (two corners at the same place, or all three on a line: zero
/// area) and repeats of an earlier triangle (the same three corner positions in the same
/// turning order; a back face is not a repeat). A small mesh is searched in `memory`'s
/// arrays (when they have room).
pub(super) fn unusable(positions: &[Vec3], indices: &[u32], memory: SearchMemory) -> Vec<usize> {
    let (triangles, _) = indices.as_chunks::<3>();
    // Whether triangles `a` and `b` have the same corners in the same turning order.
    let same = |a: u32, b: u32| {
        let key_of = |t: u32| corners(positions, &triangles[t as usize]).map(key);
        key_of(a) == key_of(b)
    };
    if triangles.len() < SHARDED_FROM {
        let SearchMemory {
            hashes: mut vertex_hashes,
            slots,
        } = memory;
        vertex_hashes.clear();
        vertex_hashes.extend(positions.iter().map(|&p| vertex_hash(p)));
        let mut firsts = SmallFirsts::in_memory(triangles.len(), slots);
        let mut unusable = Vec::new();
        for (t, tri) in triangles.iter().enumerate() {
            match look(positions, &vertex_hashes, tri) {
                Look::Outside => {}
                Look::Degenerate => unusable.push(t),
                Look::Hashed(h) => {
                    if firsts.repeats(h, t as u32, same) {
                        unusable.push(t);
                    }
                }
            }
        }
        return unusable;
    }
    let shards = 1usize << SHARD_BITS;
    // The shard of a hash comes from its middle bits, since a table uses the low bits for
    // its slot.
    let shard = |h: u64| ((h >> 32) & ((1 << SHARD_BITS) - 1)) as usize;
    let mut vertex_hashes = Vec::new();
    positions
        .par_iter()
        .with_min_len(KEY_CHUNK)
        .map(|&p| vertex_hash(p))
        .collect_into_vec(&mut vertex_hashes);
    // Pass 1, a run of triangles a task: each triangle's hash, dealt into its shard's list
    // with the triangle's number (in increasing order), and the degenerate triangles.
    let runs: Vec<Run> = triangles
        .par_chunks(KEY_CHUNK)
        .enumerate()
        .map(|(c, run)| {
            let mut dealt: Vec<Vec<(u64, u32)>> = (0..shards)
                .map(|_| Vec::with_capacity(run.len() / shards * 5 / 4))
                .collect();
            let mut degenerate_ones = Vec::new();
            for (k, tri) in run.iter().enumerate() {
                let t = c * KEY_CHUNK + k;
                match look(positions, &vertex_hashes, tri) {
                    Look::Outside => {}
                    Look::Degenerate => degenerate_ones.push(t),
                    Look::Hashed(h) => dealt[shard(h)].push((h, t as u32)),
                }
            }
            (dealt, degenerate_ones)
        })
        .collect();
    // Pass 2, a shard a task, meeting its triangles in increasing order.
    let repeats: Vec<Vec<usize>> = (0..shards)
        .into_par_iter()
        .map(|s| {
            let len = runs.iter().map(|(dealt, _)| dealt[s].len()).sum();
            let mut firsts = Firsts::with_room(len);
            runs.iter()
                .flat_map(|(dealt, _)| &dealt[s])
                .filter(|&&(h, t)| firsts.repeats(h, t, same))
                .map(|&(_, t)| t as usize)
                .collect()
        })
        .collect();
    let mut unusable: Vec<usize> = runs
        .iter()
        .flat_map(|(_, degenerate_ones)| degenerate_ones)
        .copied()
        .chain(repeats.into_iter().flatten())
        .collect();
    unusable.sort_unstable();
    unusable
}

/// Whether no triangle of `indices` is unusable, shown without searching for repeats, for a
/// generator whose triangles are distinct by construction: no two of them have the same
/// three corners (as vertex numbers, whatever the turning order) once each vertex of a pair
/// in `twins` is taken as the other. Then two triangles can only have the same corner
/// positions through two vertices at one place, and it is enough that no triangle is
/// degenerate and that no two vertices share a position, except the pairs of `twins`
/// (`(vertex, other)`, in increasing order of `vertex`: the seam of a tube, a cap's copy of
/// a ring). `false` also when it cannot tell: a repeated position elsewhere, or an index
/// past the vertices.
pub(super) fn usable_by_construction(
    positions: &[Vec3],
    indices: &[u32],
    twins: &[(u32, u32)],
) -> bool {
    let (triangles, _) = indices.as_chunks::<3>();
    !any_degenerate(positions, triangles) && distinct_positions(positions, twins)
}

/// Whether a triangle is degenerate ([`degenerate`]) or has a corner past the vertices.
fn any_degenerate(positions: &[Vec3], triangles: &[[u32; 3]]) -> bool {
    let mut test = DegenerateTest::default();
    for tri in triangles {
        let Some(c) = corners(positions, tri) else {
            return true;
        };
        test.push(c);
    }
    test.found()
}

/// Triangles a [`DegenerateTest`] tests side by side.
const LANES: usize = 8;

/// Whether a triangle is degenerate, by the test [`Mesh::remove_unusable_triangles`] applies
/// (twice its area at most a millionth of its longest side squared), for many triangles:
/// eight at a time, their corners laid out by coordinate so that the test's operations, the
/// same in the same order, run side by side. A generator can test its triangles as it
/// writes them, while their corners are at hand, and then show its mesh usable with
/// [`Mesh::distinct_positions`].
///
/// [`Mesh::remove_unusable_triangles`]: super::Mesh::remove_unusable_triangles
/// [`Mesh::distinct_positions`]: super::Mesh::distinct_positions
#[derive(Clone, Debug, Default)]
pub struct DegenerateTest {
    /// Corner, axis, lane of the triangles not tested yet.
    at: [[[f32; LANES]; 3]; 3],
    /// Lanes filled.
    len: usize,
    found: bool,
}

impl DegenerateTest {
    /// Tests a triangle given by its corners in turning order (the order of its indices).
    #[inline]
    pub fn push(&mut self, corners: [Vec3; 3]) {
        let lane = self.len % LANES;
        for (k, corner) in corners.iter().enumerate() {
            for axis in 0..3 {
                self.at[k][axis][lane] = corner[axis];
            }
        }
        self.len = lane + 1;
        if self.len == LANES {
            self.found |= flat_lanes(&self.at);
            self.len = 0;
        }
    }

    /// Tests the strip of quads between two rows of vertices given by coordinate (`[x, y,
    /// z]`; rows of `n + 1` vertices make `n` quads, a longer row is cut to the other's
    /// length): quad `k` as the triangles `(below[k], below[k + 1], above[k + 1])` and
    /// `(below[k], above[k + 1], above[k])`, in that turning order (a tube between two of
    /// its rings). The same decisions as [`DegenerateTest::push`] of each triangle: the same
    /// operations on the same numbers, a quad's diagonal computed once for its two triangles,
    /// and an edge's square length taken from the edge the other way round (`a - b` is
    /// `-(b - a)` exactly, so their squares are equal), side by side along the strip.
    pub fn strip(&mut self, below: [&[f32]; 3], above: [&[f32]; 3]) {
        let len = below
            .iter()
            .chain(&above)
            .map(|c| c.len())
            .min()
            .unwrap_or(0);
        if len < 2 {
            return;
        }
        let [bx, by, bz] = below.map(|c| &c[..len]);
        let [ax, ay, az] = above.map(|c| &c[..len]);
        let mut flat = false;
        for k in 0..len - 1 {
            let (p0, p1) = ([bx[k], by[k], bz[k]], [bx[k + 1], by[k + 1], bz[k + 1]]);
            let (c0, c1) = ([ax[k], ay[k], az[k]], [ax[k + 1], ay[k + 1], az[k + 1]]);
            let edge = |p: [f32; 3], q: [f32; 3]| [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
            let dot = |p: [f32; 3]| p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
            // `u.cross(v)` as glam writes it.
            let cross = |u: [f32; 3], v: [f32; 3]| {
                [
                    u[1] * v[2] - v[1] * u[2],
                    u[2] * v[0] - v[2] * u[0],
                    u[0] * v[1] - v[0] * u[1],
                ]
            };
            let diagonal = edge(p0, c1);
            let diagonal_squared = dot(diagonal);
            // (p0, p1, c1): sides p1 - p0, c1 - p1 and p0 - c1 (the diagonal's square).
            let u = edge(p0, p1);
            let twice_area = dot(cross(u, diagonal)).sqrt();
            let longest = dot(u).max(dot(edge(p1, c1))).max(diagonal_squared);
            flat |= twice_area <= 1e-6 * longest;
            // (p0, c1, c0): sides c1 - p0, c0 - c1 and p0 - c0 (c0 - p0's square).
            let v = edge(p0, c0);
            let twice_area = dot(cross(diagonal, v)).sqrt();
            let longest = diagonal_squared.max(dot(edge(c1, c0))).max(dot(v));
            flat |= twice_area <= 1e-6 * longest;
        }
        self.found |= flat;
    }

    /// Whether a triangle pushed so far is degenerate.
    #[must_use]
    pub fn found(&self) -> bool {
        let corner = |k: usize, l: usize| Vec3::from_array(self.at[k].map(|axis| axis[l]));
        self.found || (0..self.len).any(|l| degenerate([0, 1, 2].map(|k| corner(k, l))))
    }
}

/// Whether one of the [`LANES`] triangles of `at` (corner, axis, lane) is [`degenerate`]:
/// the same operations in the same order, side by side.
#[inline]
fn flat_lanes(at: &[[[f32; LANES]; 3]; 3]) -> bool {
    let [a, b, c] = at;
    let mut flat = false;
    for l in 0..LANES {
        let edge = |p: &[[f32; LANES]; 3], q: &[[f32; LANES]; 3]| {
            [q[0][l] - p[0][l], q[1][l] - p[1][l], q[2][l] - p[2][l]]
        };
        let dot = |p: [f32; 3]| p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        let (u, v) = (edge(a, b), edge(a, c));
        // `u.cross(v)` as glam writes it.
        let cross = [
            u[1] * v[2] - v[1] * u[2],
            u[2] * v[0] - v[2] * u[0],
            u[0] * v[1] - v[0] * u[1],
        ];
        let twice_area = dot(cross).sqrt();
        let longest = dot(u).max(dot(edge(b, c))).max(dot(edge(c, a)));
        flat |= twice_area <= 1e-6 * longest;
    }
    flat
}

/// Whether no two vertices share a position, except a vertex and its other in `twins` (see
/// [`usable_by_construction`]). A bit a position (from its hash) in a table that stays in
/// the cache finds the few vertices whose bit another set too; only those are compared, by
/// their positions, after sorting.
pub(super) fn distinct_positions(positions: &[Vec3], twins: &[(u32, u32)]) -> bool {
    // At least eight bits a vertex: at most about one vertex in eight shares its bit.
    let table_bits = (8 * positions.len()).max(1 << 12).next_power_of_two();
    let shift = 64 - table_bits.trailing_zeros();
    let mut once = vec![0u64; table_bits / 64];
    let mut twice = vec![0u64; table_bits / 64];
    for_each_placed(positions, twins, |_, h| {
        let bit = (h >> shift) as usize;
        let (word, mask) = (bit / 64, 1u64 << (bit % 64));
        twice[word] |= once[word] & mask;
        once[word] |= mask;
    });
    let mut shared = Vec::new();
    for_each_placed(positions, twins, |v, h| {
        let bit = (h >> shift) as usize;
        if twice[bit / 64] & (1 << (bit % 64)) != 0 {
            shared.push(position_bits(positions[v]));
        }
    });
    shared.sort_unstable();
    shared.windows(2).all(|w| w[0] != w[1])
}

/// Calls `f` with every vertex not at the place of its other in `twins` (see
/// [`usable_by_construction`]) and its position's [`vertex_hash`].
#[inline]
fn for_each_placed(positions: &[Vec3], twins: &[(u32, u32)], mut f: impl FnMut(usize, u64)) {
    let mut twins = twins.iter().peekable();
    for (v, &p) in positions.iter().enumerate() {
        let mut twin = None;
        while let Some(&&(a, b)) = twins.peek()
            && a as usize <= v
        {
            if a as usize == v {
                twin = Some(b as usize);
            }
            twins.next();
        }
        let at_twin = twin
            .and_then(|w| positions.get(w))
            .is_some_and(|&q| position_bits(q) == position_bits(p));
        if !at_twin {
            f(v, vertex_hash(p));
        }
    }
}

/// A position's bits, `-0.0` as `0.0`: equal for the same place.
fn position_bits(p: Vec3) -> [u32; 3] {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// The first triangle of every hash met so far: an open-addressing table (linear probing,
/// at most half full) of the hash's high half (its tag, never 0) above the triangle's
/// number; 0 is an empty slot.
struct Firsts {
    slots: Vec<u64>,
    mask: usize,
}

impl Firsts {
    /// A table for up to `n` triangles.
    fn with_room(n: usize) -> Firsts {
        let len = (2 * n).max(16).next_power_of_two();
        Firsts {
            slots: vec![0; len],
            mask: len - 1,
        }
    }

    /// Whether triangle `t` of hash `h` repeats an earlier triangle (`same(earlier)`, asked
    /// of the earlier ones with the same tag); if not, `t` is recorded.
    #[inline]
    fn repeats(&mut self, h: u64, t: u32, same: impl Fn(u32, u32) -> bool) -> bool {
        let tag = (h >> 32) | 1;
        let mut at = h as usize & self.mask;
        loop {
            let slot = self.slots[at];
            if slot == 0 {
                self.slots[at] = (tag << 32) | u64::from(t);
                return false;
            }
            if slot >> 32 == tag && same(slot as u32, t) {
                return true;
            }
            at = (at + 1) & self.mask;
        }
    }
}

/// [`Firsts`] for fewer than [`SHARDED_FROM`] triangles, in half the memory (fresh memory
/// costs a page fault a page): each slot holds the hash's top 17 bits (its tag, odd, so
/// never 0) above the triangle's number in 15 bits.
struct SmallFirsts {
    slots: Vec<u32>,
    mask: usize,
}

/// Bits of a triangle's number in a [`SmallFirsts`] slot.
const SMALL_BITS: u32 = SHARDED_FROM.trailing_zeros();

/// The slots of a [`SmallFirsts`] for `n` triangles.
pub(super) fn small_table_len(n: usize) -> usize {
    (2 * n).max(16).next_power_of_two()
}

impl SmallFirsts {
    /// A table for up to `n` triangles (`n <= SHARDED_FROM`), in `slots` when it has room
    /// (fresh zeroed memory otherwise).
    fn in_memory(n: usize, mut slots: Vec<u32>) -> SmallFirsts {
        let len = small_table_len(n);
        if slots.capacity() >= len {
            slots.clear();
            slots.resize(len, 0);
        } else {
            slots = vec![0; len];
        }
        SmallFirsts {
            slots,
            mask: len - 1,
        }
    }

    /// [`Firsts::repeats`] (`t < SHARDED_FROM`).
    #[inline]
    fn repeats(&mut self, h: u64, t: u32, same: impl Fn(u32, u32) -> bool) -> bool {
        let tag = ((h >> (64 - (32 - SMALL_BITS))) as u32) | 1;
        let mut at = h as usize & self.mask;
        loop {
            let slot = self.slots[at];
            if slot == 0 {
                self.slots[at] = (tag << SMALL_BITS) | t;
                return false;
            }
            if slot >> SMALL_BITS == tag && same(slot & ((1 << SMALL_BITS) - 1), t) {
                return true;
            }
            at = (at + 1) & self.mask;
        }
    }
}

/// A triangle's corners checked: past the vertices, degenerate, or hashed (from
/// `vertex_hashes`, one [`vertex_hash`] a position).
#[inline]
fn look(positions: &[Vec3], vertex_hashes: &[u64], tri: &[u32; 3]) -> Look {
    match corners(positions, tri) {
        None => Look::Outside,
        Some(c) if degenerate(c) => Look::Degenerate,
        // `corners` found every index within the positions, which `vertex_hashes` matches.
        Some(_) => Look::Hashed(hash_of_corners(tri.map(|i| vertex_hashes[i as usize]))),
    }
}

/// `indices` without the triangles listed in `dropped` (in increasing order; a number out
/// of order or past the last triangle is ignored).
pub(super) fn without(indices: &[u32], dropped: &[usize]) -> Vec<u32> {
    let mut kept = Vec::with_capacity(indices.len().saturating_sub(3 * dropped.len()));
    let mut from = 0;
    for &t in dropped {
        let start = t.saturating_mul(3);
        if start < from || start.saturating_add(3) > indices.len() {
            continue;
        }
        kept.extend_from_slice(&indices[from..start]);
        from = start + 3;
    }
    kept.extend_from_slice(&indices[from..]);
    kept
}

/// The corners of a triangle, `None` if one is past the vertices.
fn corners(positions: &[Vec3], tri: &[u32; 3]) -> Option<[Vec3; 3]> {
    let [a, b, c] = tri.map(|i| positions.get(i as usize).copied());
    Some([a?, b?, c?])
}

/// Whether a triangle has no area: twice its area at most a millionth of its longest side
/// squared.
fn degenerate([a, b, c]: [Vec3; 3]) -> bool {
    let twice_area = (b - a).cross(c - a).length();
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    twice_area <= 1e-6 * longest
}

/// The corners' bits in turning order, starting from the smallest (`+ 0.0` turns -0.0 into
/// 0.0, so both spell the same position).
#[inline]
fn key(corners: [Vec3; 3]) -> [u32; 9] {
    let keys = corners.map(|p| (p + Vec3::ZERO).to_array().map(f32::to_bits));
    let first = (0..3).min_by_key(|&k| keys[k]).unwrap_or(0);
    let mut out = [0; 9];
    for k in 0..3 {
        out[3 * k..3 * k + 3].copy_from_slice(&keys[(first + k) % 3]);
    }
    out
}

/// A 64-bit hash of a position's bits (`-0.0` as `0.0`): a triangle's corners' hashes make
/// its hash ([`hash_of_corners`]).
fn vertex_hash(p: Vec3) -> u64 {
    let [x, y, z] = (p + Vec3::ZERO).to_array().map(f32::to_bits);
    let xy = (u64::from(x) | (u64::from(y) << 32)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    xy ^ (xy >> 29) ^ u64::from(z).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
}

/// A 64-bit hash of a triangle's corners, from their [`vertex_hash`]es in turning order,
/// that is the same whichever corner it starts at, and differs for the other turning order:
/// a sum over the three edges of a hash of the edge's two corners in order, then a final mix
/// so that every bit depends on every corner. Equal keys ([`key`]) have equal hashes.
#[inline]
fn hash_of_corners([a, b, c]: [u64; 3]) -> u64 {
    let edge = |from: u64, to: u64| (from ^ to.rotate_left(23)).wrapping_mul(0x1656_67B1_9E37_79F9);
    let mut h = edge(a, b).wrapping_add(edge(b, c)).wrapping_add(edge(c, a));
    h ^= h >> 31;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^ (h >> 29)
}

#[cfg(test)]
mod tests;
