//! A mesh's `extras.pge` (its skeleton and own extras), serialized from borrowed views of
//! the model. A skeleton (most of a tree's JSON: four numbers a node) is not serialized
//! with the rest: its place holds a marker, and its text, formatted ahead of the export
//! ([`Prepared`], for skeletons written several times) or in parallel pieces when the file is
//! written, takes the marker's place in the file's JSON chunk ([`JsonText`]).

use std::ops::Range;
use std::sync::Arc;

use gltf_json as json;
use rayon::prelude::*;
use serde::ser::{Serialize, SerializeMap, Serializer};
use serde_json::Value as JsonValue;
use serde_json::ser::{CompactFormatter, Formatter};
use serde_json::value::RawValue;

use super::lod_extras::LodJson;
use crate::geometry::{Mesh, MeshLod, Model, Skeleton};
use crate::{Error, Result};

/// Numbers of a skeleton's array a thread formats at a time (about 60 µs of floats).
const PIECE_NUMBERS: usize = 1 << 11;

/// Fewest numbers of the skeletons formatted on the rayon pool (fewer are formatted on the
/// calling thread, in less time than handing them to another). An oak's 7 k numbers take
/// 0.3 ms on one thread, the file's JSON waits for them.
const FORMAT_IN_PARALLEL: usize = 2 * PIECE_NUMBERS;

/// One value of a mesh's `extras.pge`: the skeleton of a mesh, one of the mesh's own
/// extras, or its levels of detail.
#[derive(Clone, Copy)]
pub(super) enum Extra<'m> {
    Skeleton(&'m Arc<Mesh>),
    Value(&'m JsonValue),
    Lod(&'m MeshLod),
}

/// A mesh's `extras.pge` in order, borrowed from the model.
#[derive(Default)]
pub(super) struct MeshExtras<'m>(pub(super) Vec<(&'m str, Extra<'m>)>);

impl MeshExtras<'_> {
    /// `{"pge": {...}}` as the mesh's extras, serialized in one pass (no `Value` tree), a
    /// skeleton as the marker of its place in `skeletons` (which it joins).
    pub(super) fn extras(&self, skeletons: &mut Vec<Arc<Mesh>>) -> Result<json::Extras> {
        let export = |e: serde_json::Error| Error::Export(e.to_string());
        let mut markers = Vec::new();
        for (_, value) in &self.0 {
            if let Extra::Skeleton(mesh) = value {
                markers.push(RawValue::from_string(marker(skeletons.len())).map_err(export)?);
                skeletons.push(Arc::clone(mesh));
            }
        }
        let entries = Entries([("pge", Marked(self, &markers))]);
        serde_json::value::to_raw_value(&entries)
            .map(Some)
            .map_err(export)
    }
}

/// The marker of skeleton `k` in the JSON text: an array of its number after a line feed.
/// Compact JSON has no line feed anywhere else (one in a string is written `\n`), so the
/// markers are found by that byte, and a marker is still valid JSON.
fn marker(k: usize) -> String {
    format!("[\n{k}]")
}

/// A mesh's extras with the markers of its skeletons, in order.
struct Marked<'a, 'm>(&'a MeshExtras<'m>, &'a [Box<RawValue>]);

impl Serialize for Marked<'_, '_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.0.len()))?;
        let mut markers = self.1.iter();
        for (key, value) in &self.0.0 {
            match value {
                Extra::Skeleton(_) => match markers.next() {
                    Some(m) => map.serialize_entry(key, m)?,
                    None => map.serialize_entry(key, &JsonValue::Null)?,
                },
                Extra::Value(value) => map.serialize_entry(key, value)?,
                Extra::Lod(lod) => map.serialize_entry(key, &LodJson(lod))?,
            }
        }
        map.end()
    }
}

/// A JSON object of the given entries, in order.
struct Entries<const N: usize, T>([(&'static str, T); N]);

impl<const N: usize, T: Serialize> Serialize for Entries<N, T> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(N))?;
        for (key, value) in &self.0 {
            map.serialize_entry(key, value)?;
        }
        map.end()
    }
}

/// The glTF JSON text with the skeletons in place of their markers, formatted in pieces on
/// the rayon pool. A skeleton is `{parents, positions, radii, orders}` (docs/glb.md): a root's
/// parent is -1; floats are written as the `f64` they widen to (`null` when not finite), as
/// serde_json writes them, so the text is the same as one serialized in one pass.
pub(super) struct JsonText {
    /// The text with the markers.
    text: Vec<u8>,
    /// The skeletons' texts, in the order of their markers.
    skeletons: Vec<Text>,
    /// The text around the markers, and the skeletons, in order.
    parts: Vec<Part>,
    /// The length of the whole text.
    len: usize,
}

/// A part of a [`JsonText`].
enum Part {
    /// Bytes of the text around the markers.
    Text(Range<usize>),
    /// The text of the skeleton of that marker.
    Skeleton(usize),
}

/// A skeleton's text in a [`JsonText`].
enum Text {
    /// Formatted ahead of the export.
    Prepared(Arc<SkeletonText>),
    /// Formatted by the export.
    Formatted(Formatted),
}

impl Text {
    fn formatted(&self) -> &Formatted {
        match self {
            Text::Prepared(text) => &text.formatted,
            Text::Formatted(formatted) => formatted,
        }
    }
}

/// The arrays of a skeleton, in the order they are written.
#[derive(Clone, Copy)]
enum Array {
    Parents,
    Positions,
    Radii,
    Orders,
}

impl Array {
    const ALL: [Array; 4] = [
        Array::Parents,
        Array::Positions,
        Array::Radii,
        Array::Orders,
    ];

    /// What comes before the array's numbers.
    fn opening(self) -> &'static [u8] {
        match self {
            Array::Parents => br#"{"parents":["#,
            Array::Positions => br#"],"positions":["#,
            Array::Radii => br#"],"radii":["#,
            Array::Orders => br#"],"orders":["#,
        }
    }

    fn len(self, sk: &Skeleton) -> usize {
        match self {
            Array::Parents => sk.parents.len(),
            Array::Positions => 3 * sk.positions.len(),
            Array::Radii => sk.radii.len(),
            Array::Orders => sk.orders.len(),
        }
    }

    /// The numbers `range` of the array, each after a comma but the array's first.
    fn format(self, sk: &Skeleton, range: Range<usize>) -> std::io::Result<Vec<u8>> {
        let mut out = Vec::with_capacity(12 * range.len());
        let mut f = CompactFormatter;
        for k in range {
            if k > 0 {
                out.push(b',');
            }
            match self {
                Array::Parents => f.write_i64(&mut out, sk.parents[k].map_or(-1, i64::from))?,
                Array::Positions => float(&mut out, sk.positions[k / 3][k % 3])?,
                Array::Radii => float(&mut out, sk.radii[k])?,
                Array::Orders => f.write_u32(&mut out, sk.orders[k])?,
            }
        }
        Ok(out)
    }
}

/// A float as the `f64` it widens to, `null` when not finite (as serde_json writes it).
fn float(out: &mut Vec<u8>, v: f32) -> std::io::Result<()> {
    if v.is_finite() {
        CompactFormatter.write_f64(out, f64::from(v))
    } else {
        CompactFormatter.write_null(out)
    }
}

/// A skeleton's numbers formatted: the pieces of each array, in the order of [`Array::ALL`].
#[derive(Debug)]
struct Formatted([Vec<Vec<u8>>; 4]);

impl Formatted {
    /// The numbers of the skeleton's arrays, in pieces of [`PIECE_NUMBERS`], formatted on the
    /// rayon pool when `share` and they are [`FORMAT_IN_PARALLEL`] or more.
    fn new(sk: &Skeleton, share: bool) -> std::io::Result<Formatted> {
        let jobs: Vec<(Array, Range<usize>)> = Array::ALL
            .into_iter()
            .flat_map(|array| {
                let n = array.len(sk);
                (0..n)
                    .step_by(PIECE_NUMBERS)
                    .map(move |s| (array, s..(s + PIECE_NUMBERS).min(n)))
            })
            .collect();
        let format = |(array, range): (Array, Range<usize>)| array.format(sk, range);
        let pieces = if !share || Formatted::numbers(sk) < FORMAT_IN_PARALLEL {
            jobs.into_iter()
                .map(format)
                .collect::<std::io::Result<Vec<_>>>()?
        } else {
            jobs.into_par_iter()
                .map(format)
                .collect::<std::io::Result<Vec<_>>>()?
        };
        let mut pieces = pieces.into_iter();
        Ok(Formatted(Array::ALL.map(|array| {
            let n = array.len(sk).div_ceil(PIECE_NUMBERS);
            pieces.by_ref().take(n).collect()
        })))
    }

    /// How many numbers the skeleton's text has.
    fn numbers(sk: &Skeleton) -> usize {
        Array::ALL.into_iter().map(|array| array.len(sk)).sum()
    }

    /// The skeleton's text: `{"parents":[...],...}`.
    fn slices(&self) -> impl Iterator<Item = &[u8]> {
        Array::ALL
            .into_iter()
            .zip(&self.0)
            .flat_map(|(array, pieces)| {
                std::iter::once(array.opening()).chain(pieces.iter().map(Vec::as_slice))
            })
            .chain(std::iter::once(&b"]}"[..]))
    }
}

/// What the glb writer formats of a model, formatted once ahead of the export and reused
/// by every file that writes the same skeletons (the tiles of one run, which share their
/// forest's variants): each mesh's skeleton as its `extras.pge` text. A writer given one
/// uses a text for a skeleton of the same numbers, compared bit for bit (a thirtieth of the
/// time of formatting them), and formats any other; the file is the same either way.
#[derive(Clone, Debug, Default)]
pub struct Prepared {
    skeletons: Vec<Arc<SkeletonText>>,
}

impl Prepared {
    /// The texts of every skeleton of `model`'s meshes.
    pub fn new(model: &Model) -> Result<Prepared> {
        let mut prepared = Prepared::default();
        prepared.extend(model)?;
        Ok(prepared)
    }

    /// Adds the texts of the skeletons of `model`'s meshes not held yet (side by side on
    /// the rayon pool).
    pub fn extend(&mut self, model: &Model) -> Result<()> {
        let mut missing: Vec<&Arc<Skeleton>> = Vec::new();
        for sk in model.meshes.iter().filter_map(|m| m.skeleton.as_ref()) {
            let held = missing.iter().any(|m| Arc::ptr_eq(m, sk))
                || self.skeletons.iter().any(|t| t.made_from(sk));
            if !held {
                missing.push(sk);
            }
        }
        let texts = missing
            .into_par_iter()
            .map(|sk| SkeletonText::new(sk).map(Arc::new))
            .collect::<Result<Vec<_>>>()?;
        self.skeletons.extend(texts);
        Ok(())
    }

    /// How many skeleton texts are held.
    #[must_use]
    pub fn len(&self) -> usize {
        self.skeletons.len()
    }

    /// Whether no text is held (a writer given this formats every skeleton).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.skeletons.is_empty()
    }
}

/// A skeleton's text in a mesh's `extras.pge`, formatted ahead of the export ([`Prepared`]).
#[derive(Debug)]
pub(super) struct SkeletonText {
    /// The skeleton's numbers it was formatted from (its leaves are not written).
    from: Skeleton,
    formatted: Formatted,
}

impl SkeletonText {
    /// The text of `skeleton`, formatted on the calling thread.
    pub(super) fn new(skeleton: &Skeleton) -> Result<SkeletonText> {
        let formatted =
            Formatted::new(skeleton, false).map_err(|e| Error::Export(e.to_string()))?;
        let from = Skeleton {
            positions: skeleton.positions.clone(),
            parents: skeleton.parents.clone(),
            radii: skeleton.radii.clone(),
            orders: skeleton.orders.clone(),
            leaves: Vec::new(),
        };
        Ok(SkeletonText { from, formatted })
    }

    /// Whether this is the text of `skeleton`: the same numbers, bit for bit.
    pub(super) fn made_from(&self, skeleton: &Skeleton) -> bool {
        fn bits<T: bytemuck::Pod>(v: &[T]) -> &[u32] {
            bytemuck::cast_slice(v)
        }
        self.from.parents == skeleton.parents
            && self.from.orders == skeleton.orders
            && bits(&self.from.positions) == bits(&skeleton.positions)
            && bits(&self.from.radii) == bits(&skeleton.radii)
    }
}

impl JsonText {
    /// `text` with each skeleton marker replaced by the skeleton of that mesh of
    /// `skeletons` (an empty one if it has none): the text of `prepared` made from the same
    /// numbers where there is one, formatted now otherwise.
    pub(super) fn new(
        text: Vec<u8>,
        skeletons: &[Arc<Mesh>],
        prepared: &Prepared,
    ) -> Result<JsonText> {
        let bad = || Error::Export("a skeleton marker in the glTF JSON is damaged".into());
        // The markers, in order: skeleton k's is the k-th (the meshes are written in the
        // order their extras were), found by the next line feed that is part of it (one in
        // a raw extra read from a file is skipped).
        let mut markers = Vec::with_capacity(skeletons.len());
        let mut at = 0;
        while markers.len() < skeletons.len() {
            let k = markers.len();
            let want = marker(k);
            let start = (at + 1..text.len())
                .filter(|&p| text[p] == b'\n')
                .map(|p| p - 1)
                .find(|&p| text[p..].starts_with(want.as_bytes()))
                .ok_or_else(bad)?;
            markers.push(start..start + want.len());
            at = start + want.len();
        }
        let empty = Skeleton::default();
        let sks: Vec<&Skeleton> = skeletons
            .iter()
            .map(|mesh| mesh.skeleton.as_deref().unwrap_or(&empty))
            .collect();
        // Each skeleton's text: prepared, or formatted now (skeletons side by side when
        // they are many numbers in all; a big one's pieces side by side too).
        let found: Vec<Option<Arc<SkeletonText>>> = sks
            .iter()
            .map(|sk| prepared.skeletons.iter().find(|t| t.made_from(sk)).cloned())
            .collect();
        let missing: Vec<&Skeleton> = sks
            .iter()
            .zip(&found)
            .filter(|(_, f)| f.is_none())
            .map(|(sk, _)| *sk)
            .collect();
        let numbers: usize = missing.iter().map(|sk| Formatted::numbers(sk)).sum();
        let formatted = if numbers < FORMAT_IN_PARALLEL || missing.len() < 2 {
            missing
                .into_iter()
                .map(|sk| Formatted::new(sk, true))
                .collect::<std::io::Result<Vec<_>>>()
        } else {
            missing
                .into_par_iter()
                .map(|sk| Formatted::new(sk, true))
                .collect()
        };
        let mut formatted = formatted
            .map_err(|e| Error::Export(e.to_string()))?
            .into_iter();
        let mut texts = Vec::with_capacity(skeletons.len());
        for f in found {
            texts.push(match f {
                Some(text) => Text::Prepared(text),
                None => Text::Formatted(formatted.next().ok_or_else(bad)?),
            });
        }
        let mut parts = Vec::with_capacity(2 * markers.len() + 1);
        let mut from = 0;
        for (k, range) in markers.into_iter().enumerate() {
            parts.push(Part::Text(from..range.start));
            parts.push(Part::Skeleton(k));
            from = range.end;
        }
        parts.push(Part::Text(from..text.len()));
        let mut json = JsonText {
            text,
            skeletons: texts,
            parts,
            len: 0,
        };
        json.len = json.slices().map(<[u8]>::len).sum();
        Ok(json)
    }

    /// The text's bytes, part by part.
    pub(super) fn slices(&self) -> impl Iterator<Item = &[u8]> {
        self.parts.iter().flat_map(|p| {
            let (text, skeleton) = match p {
                Part::Text(range) => (Some(&self.text[range.clone()]), None),
                Part::Skeleton(k) => (None, self.skeletons.get(*k).map(Text::formatted)),
            };
            text.into_iter()
                .chain(skeleton.into_iter().flat_map(Formatted::slices))
        })
    }

    /// The length of the text in bytes.
    pub(super) fn len(&self) -> usize {
        self.len
    }

    /// Writes the text at the start of `dst` (at least [`JsonText::len`] bytes), its parts
    /// copied in parallel.
    pub(super) fn write(&self, dst: &mut [u8]) {
        let mut rest = dst;
        let mut copies = Vec::with_capacity(self.parts.len());
        for bytes in self.slices() {
            let (head, tail) = rest.split_at_mut(bytes.len());
            copies.push((head, bytes));
            rest = tail;
        }
        copies
            .into_par_iter()
            .with_min_len(8)
            .for_each(|(dst, src)| dst.copy_from_slice(src));
    }

    /// The whole text.
    pub(super) fn into_vec(self) -> Vec<u8> {
        if let [Part::Text(_)] = self.parts.as_slice() {
            return self.text;
        }
        let mut out = vec![0; self.len];
        self.write(&mut out);
        out
    }
}
