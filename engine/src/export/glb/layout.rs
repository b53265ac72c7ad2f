//! The binary chunk in two passes: while the JSON is built every buffer view is only placed
//! (its offset and length computed, its data kept by reference), and at the end the bytes
//! are written straight into the output, in parallel over disjoint slices of it (rayon).
//! Each element's bytes depend only on the element, so the output is the same for any
//! number of threads.

use std::borrow::Cow;
use std::ops::Range;
use std::sync::Arc;

use rayon::prelude::*;

use glam::{Vec3, Vec3A, Vec4};

use crate::geometry::{Mesh, Texture};

/// Bytes of a piece of work when a view is cut up for the threads: large enough that a
/// piece costs far more than handing it to a thread, small enough to balance 2-8 threads
/// over a model of a few megabytes.
const PIECE_BYTES: usize = 1 << 18;

/// One attribute (or the indices) of a mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Attribute {
    /// `positions`: VEC3 floats.
    Positions,
    /// `normals`: VEC3 floats.
    Normals,
    /// `uvs`: VEC2 floats.
    Uvs,
    /// `colors`: linear RGBA as normalized unsigned bytes, rounded to the nearest of the 256
    /// steps.
    Colors,
    /// `indices`: unsigned 32-bit integers.
    Indices,
}

/// Where a buffer view's bytes come from.
pub(super) enum Data {
    /// An attribute of a mesh.
    Mesh(Arc<Mesh>, Attribute),
    /// Little-endian floats (per-instance data).
    Floats(Vec<f32>),
    /// An embedded image (PNG or JPEG), as it is.
    Image(Arc<Texture>),
}

impl Data {
    /// Bytes of one element.
    fn element_bytes(&self) -> usize {
        match self {
            Data::Mesh(_, Attribute::Positions | Attribute::Normals) => 12,
            Data::Mesh(_, Attribute::Uvs) => 8,
            Data::Mesh(_, Attribute::Colors | Attribute::Indices) | Data::Floats(_) => 4,
            Data::Image(_) => 1,
        }
    }

    /// Number of elements.
    fn count(&self) -> usize {
        match self {
            Data::Mesh(m, Attribute::Positions) => m.positions.len(),
            Data::Mesh(m, Attribute::Normals) => m.normals.len(),
            Data::Mesh(m, Attribute::Uvs) => m.uvs.len(),
            Data::Mesh(m, Attribute::Colors) => m.colors.len(),
            Data::Mesh(m, Attribute::Indices) => m.indices.len(),
            Data::Floats(f) => f.len(),
            Data::Image(t) => t.encoded.len(),
        }
    }

    /// The view's bytes as the file holds them: borrowed where the model's memory already
    /// holds them (an embedded image; little-endian floats and integers on a little-endian
    /// host), converted otherwise (colours, and everything on a big-endian host), in pieces
    /// on the rayon pool when there are many.
    fn bytes(&self) -> Cow<'_, [u8]> {
        if let Some(bytes) = self.as_bytes() {
            return Cow::Borrowed(bytes);
        }
        let size = self.element_bytes();
        let mut out = vec![0; self.count() * size];
        let per_piece = (PIECE_BYTES / size).max(1) * size;
        if out.len() <= per_piece {
            self.fill(0, &mut out);
        } else {
            out.par_chunks_mut(per_piece)
                .enumerate()
                .for_each(|(k, piece)| self.fill(k * (per_piece / size), piece));
        }
        Cow::Owned(out)
    }

    /// The bytes of data whose memory is the file's bytes as they are.
    #[cfg(target_endian = "little")]
    fn as_bytes(&self) -> Option<&[u8]> {
        use bytemuck::cast_slice;
        match self {
            Data::Mesh(m, Attribute::Positions) => Some(cast_slice(&m.positions)),
            Data::Mesh(m, Attribute::Normals) => Some(cast_slice(&m.normals)),
            Data::Mesh(m, Attribute::Uvs) => Some(cast_slice(&m.uvs)),
            Data::Mesh(m, Attribute::Indices) => Some(cast_slice(&m.indices)),
            Data::Mesh(_, Attribute::Colors) => None,
            Data::Floats(f) => Some(cast_slice(f)),
            Data::Image(t) => Some(&t.encoded),
        }
    }

    /// The bytes of data whose memory is the file's bytes as they are: only an image's on a
    /// big-endian host (numbers are written byte by byte, little-endian).
    #[cfg(target_endian = "big")]
    fn as_bytes(&self) -> Option<&[u8]> {
        match self {
            Data::Image(t) => Some(&t.encoded),
            _ => None,
        }
    }

    /// Writes the elements from `first` on into `dst`, as many as it holds.
    fn fill(&self, first: usize, dst: &mut [u8]) {
        let n = dst.len() / self.element_bytes();
        let range = first..first + n;
        match self {
            Data::Mesh(m, Attribute::Positions) => {
                floats(dst, &m.positions[range], |p| p.to_array())
            }
            Data::Mesh(m, Attribute::Normals) => floats(dst, &m.normals[range], |p| p.to_array()),
            Data::Mesh(m, Attribute::Uvs) => floats(dst, &m.uvs[range], |p| p.to_array()),
            Data::Mesh(m, Attribute::Colors) => {
                for (d, c) in dst.chunks_exact_mut(4).zip(&m.colors[range]) {
                    d.copy_from_slice(&c.to_array().map(unit_byte));
                }
            }
            Data::Mesh(m, Attribute::Indices) => {
                for (d, i) in dst.chunks_exact_mut(4).zip(&m.indices[range]) {
                    d.copy_from_slice(&i.to_le_bytes());
                }
            }
            Data::Floats(f) => floats(dst, &f[range], |&x| [x]),
            Data::Image(t) => dst.copy_from_slice(&t.encoded[range]),
        }
    }
}

/// Writes `K` little-endian floats per item of `items` into `dst`.
fn floats<T, const K: usize>(dst: &mut [u8], items: &[T], array: impl Fn(&T) -> [f32; K]) {
    for (d, item) in dst.chunks_exact_mut(4 * K).zip(items) {
        for (d, f) in d.chunks_exact_mut(4).zip(array(item)) {
            d.copy_from_slice(&f.to_le_bytes());
        }
    }
}

/// A colour channel as a normalized unsigned byte: clamped to `0..=1`, times 255, rounded to
/// the nearest (halves away from zero, as `f32::round`; `NaN` gives 0), without a call to
/// `round` (the difference from the truncated value is exact below 2^23).
fn unit_byte(v: f32) -> u8 {
    let x = v.clamp(0.0, 1.0) * 255.0;
    let whole = x as u8;
    whole + u8::from(x - f32::from(whole) >= 0.5)
}

/// A view placed in the buffer.
struct View {
    offset: usize,
    data: Data,
}

/// The binary chunk's views, placed but not yet written.
#[derive(Default)]
pub(super) struct Layout {
    views: Vec<View>,
    len: usize,
}

impl Layout {
    /// Places `data` at the next 4-byte boundary: its offset and length in bytes.
    pub(super) fn place(&mut self, data: Data) -> (usize, usize) {
        let offset = self.len.next_multiple_of(4);
        let len = data.count() * data.element_bytes();
        self.len = offset + len;
        self.views.push(View { offset, data });
        (offset, len)
    }

    /// The number of views.
    pub(super) fn view_count(&self) -> usize {
        self.views.len()
    }

    /// The first view whose bytes the model does not hold as the file does (colours, and
    /// numbers on a big-endian host), converted when written: the views before it are
    /// written straight from the model's memory. The number of views when there is none.
    pub(super) fn first_converted(&self) -> usize {
        self.views
            .iter()
            .position(|view| view.data.as_bytes().is_none())
            .unwrap_or(self.views.len())
    }

    /// The buffer's length in bytes, padded to 4 bytes.
    pub(super) fn padded_len(&self) -> usize {
        self.len.next_multiple_of(4)
    }

    /// Writes every view into `bin`, which holds [`Layout::padded_len`] zero bytes: the
    /// views' bytes in pieces of about [`PIECE_BYTES`] on the current rayon pool's threads
    /// (the padding between them stays zero).
    pub(super) fn write(&self, bin: &mut [u8]) {
        let mut pieces = Vec::with_capacity(self.views.len() + self.len / PIECE_BYTES);
        let mut rest = bin;
        let mut at = 0;
        for view in &self.views {
            let size = view.data.element_bytes();
            let (_, tail) = rest.split_at_mut(view.offset - at);
            let (mut bytes, tail) = tail.split_at_mut(view.data.count() * size);
            rest = tail;
            at = view.offset + bytes.len();
            let per_piece = (PIECE_BYTES / size).max(1) * size;
            let mut first = 0;
            while !bytes.is_empty() {
                let (piece, more) = bytes.split_at_mut(per_piece.min(bytes.len()));
                pieces.push((&view.data, first, piece));
                first += per_piece / size;
                bytes = more;
            }
        }
        pieces
            .into_par_iter()
            .for_each(|(data, first, piece)| data.fill(first, piece));
    }

    /// The views `views` of the binary chunk as slices to write in order: each view's bytes
    /// ([`Data::bytes`]: borrowed from the model where they can be), after the zero bytes
    /// that align it, and after the last view of the chunk the zero bytes that pad it (all
    /// the views: [`Layout::padded_len`] bytes).
    pub(super) fn slices(&self, views: Range<usize>) -> Vec<Cow<'_, [u8]>> {
        const ZEROS: &[u8] = &[0; 3];
        let end = |view: &View| view.offset + view.data.count() * view.data.element_bytes();
        let mut at = views
            .start
            .checked_sub(1)
            .and_then(|k| self.views.get(k))
            .map_or(0, end);
        let last = views.end == self.views.len();
        let views = self.views.get(views).unwrap_or_default();
        let mut out = Vec::with_capacity(2 * views.len() + 1);
        for view in views {
            if view.offset > at {
                out.push(Cow::Borrowed(&ZEROS[..view.offset - at]));
            }
            let bytes = view.data.bytes();
            at = view.offset + bytes.len();
            out.push(bytes);
        }
        if last && self.padded_len() > at {
            out.push(Cow::Borrowed(&ZEROS[..self.padded_len() - at]));
        }
        out
    }
}

/// Points whose bounds one thread finds at a time.
pub(super) const BOUNDS_PIECE: usize = 1 << 16;

/// The per-axis minimum and maximum of `points` (infinities when empty), in pieces on the
/// rayon pool when there are many. The pieces' bounds are combined in order, with the same
/// `min` and `max` as within a piece, so the result is the one-pass fold's to the bit (which
/// zero of a `-0.0` / `0.0` tie wins included), whatever the number of threads.
pub(super) fn vec3_bounds(points: &[Vec3]) -> ([f32; 3], [f32; 3]) {
    let (lo, hi) = if points.len() <= 2 * BOUNDS_PIECE {
        piece_bounds(points)
    } else {
        let pieces: Vec<_> = points.par_chunks(BOUNDS_PIECE).map(piece_bounds).collect();
        pieces.into_iter().fold(
            (Vec3A::INFINITY, Vec3A::NEG_INFINITY),
            |(lo, hi), (plo, phi)| (plo.min(lo), phi.max(hi)),
        )
    };
    (lo.to_array(), hi.to_array())
}

/// The bounds of `points` as the point-by-point fold ([`widen`]) finds them, to the bit, with
/// a quarter of its instructions: the floats 12 at a time (4 points) in three 4-lane pairs of
/// bounds, whose lanes hold the axes x y z x, y z x y and z x y z, combined at the end; the
/// last points one at a time. A bound that is not zero has one bit pattern for its value (a
/// `NaN` is skipped either way), so the order the lanes saw the points in does not matter;
/// a zero bound is the fold's first zero on that axis (`-0.0` or `0.0`: the fold keeps the
/// first of a tie), found again by a search that stops there.
fn piece_bounds(points: &[Vec3]) -> (Vec3A, Vec3A) {
    let floats: &[f32] = bytemuck::cast_slice(points);
    let mut lo = [Vec4::INFINITY; 3];
    let mut hi = [Vec4::NEG_INFINITY; 3];
    let mut fours = floats.chunks_exact(12);
    for twelve in &mut fours {
        for (k, four) in twelve.chunks_exact(4).enumerate() {
            let v = Vec4::from_slice(four);
            lo[k] = v.min(lo[k]);
            hi[k] = v.max(hi[k]);
        }
    }
    // The (pair, lane)s that hold x, y and z: x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3.
    const LANES: [[(usize, usize); 4]; 3] = [
        [(0, 0), (0, 3), (1, 2), (2, 1)],
        [(0, 1), (1, 0), (1, 3), (2, 2)],
        [(0, 2), (1, 1), (2, 0), (2, 3)],
    ];
    let gather = |v: &[Vec4; 3], widest: fn(f32, f32) -> f32, empty: f32| {
        Vec3A::from_array(LANES.map(|lanes| {
            lanes
                .iter()
                .fold(empty, |b, &(pair, lane)| widest(v[pair][lane], b))
        }))
    };
    let lanes = (
        gather(&lo, f32::min, f32::INFINITY),
        gather(&hi, f32::max, f32::NEG_INFINITY),
    );
    let rest = &points[points.len() - fours.remainder().len() / 3..];
    let (lo, hi) = rest.iter().map(|&p| Vec3A::from(p)).fold(lanes, widen);
    let first_zero = |bound: Vec3A| {
        Vec3A::from_array(std::array::from_fn(|a| {
            if bound[a] == 0.0 {
                points
                    .iter()
                    .map(|p| p[a])
                    .find(|&c| c == 0.0)
                    .unwrap_or(0.0)
            } else {
                bound[a]
            }
        }))
    };
    (first_zero(lo), first_zero(hi))
}

/// Bounds `(lo, hi)` widened to hold `p`, the three axes at once (4 lanes: a quarter of the
/// instructions of one axis at a time). `p.min(lo)`, not `lo.min(p)`: on SSE `minps` keeps
/// its second operand on a tie or a `NaN`, so a bound keeps the zero it holds against the
/// other zero (as `f32::min` of one axis at a time does) and skips a `NaN`.
fn widen((lo, hi): (Vec3A, Vec3A), p: Vec3A) -> (Vec3A, Vec3A) {
    (p.min(lo), p.max(hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_bytes_round_as_f32_round_does() {
        let round = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
        // Every 97th float of 0..=1, and each half-way point between two steps with its
        // neighbours.
        let spread = (0..=1.0f32.to_bits()).step_by(97).map(f32::from_bits);
        let halves = (0..255).flat_map(|k| {
            let h = (k as f32 + 0.5) / 255.0;
            [
                f32::from_bits(h.to_bits() - 1),
                h,
                f32::from_bits(h.to_bits() + 1),
            ]
        });
        let edges = [f32::NAN, -0.0, -0.1, 1.1, f32::INFINITY, f32::NEG_INFINITY];
        for v in spread.chain(halves).chain(edges) {
            assert_eq!(unit_byte(v), round(v), "{v}");
        }
    }

    #[test]
    fn views_are_written_at_their_offsets_in_pieces() {
        let mesh = Arc::new(Mesh {
            indices: (0..200_000u32).collect(),
            ..Mesh::default()
        });
        let mut layout = Layout::default();
        let floats = vec![1.5f32, -2.0, 3.25];
        assert_eq!(layout.place(Data::Floats(floats.clone())), (0, 12));
        let png = Arc::new(Texture {
            name: "three bytes".into(),
            width: 1,
            height: 1,
            encoded: vec![7, 8, 9],
        });
        assert_eq!(layout.place(Data::Image(png)), (12, 3));
        let (offset, len) = layout.place(Data::Mesh(mesh.clone(), Attribute::Indices));
        assert_eq!((offset, len), (16, 800_000));
        let mut bin = vec![0xAA; layout.padded_len()];
        bin[15] = 0;
        layout.write(&mut bin);
        let want: Vec<u8> = floats
            .iter()
            .flat_map(|f| f.to_le_bytes())
            .chain([7, 8, 9, 0])
            .chain(mesh.indices.iter().flat_map(|i| i.to_le_bytes()))
            .collect();
        assert_eq!(bin, want);
    }
}
