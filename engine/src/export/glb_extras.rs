//! A mesh's `extras.pge` (its skeleton and own extras), serialized in one pass from borrowed
//! views of the model.

use gltf_json as json;
use serde::ser::{Serialize, SerializeMap, Serializer};
use serde_json::Value as JsonValue;

use crate::geometry::Skeleton;
use crate::{Error, Result};

/// One value of a mesh's `extras.pge`: its skeleton, written straight from the model, or one
/// of the mesh's own extras.
#[derive(Clone, Copy)]
pub(super) enum Extra<'m> {
    Skeleton(&'m Skeleton),
    Value(&'m JsonValue),
}

/// A mesh's `extras.pge` in order, borrowed from the model and serialized in one pass.
#[derive(Default)]
pub(super) struct MeshExtras<'m>(pub(super) Vec<(&'m str, Extra<'m>)>);

impl MeshExtras<'_> {
    /// `{"pge": {...}}` as the mesh's extras, serialized in one pass (no `Value` tree).
    pub(super) fn extras(&self) -> Result<json::Extras> {
        serde_json::value::to_raw_value(&Entries([("pge", self)]))
            .map(Some)
            .map_err(|e| Error::Export(e.to_string()))
    }
}

impl Serialize for MeshExtras<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (key, value) in &self.0 {
            match value {
                Extra::Skeleton(skeleton) => map.serialize_entry(key, &SkeletonJson(skeleton))?,
                Extra::Value(value) => map.serialize_entry(key, value)?,
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

/// The skeleton as `{parents, positions, radii, orders}` (API.md §7), serialized straight
/// from its arrays: a root's parent is -1; floats are written as the `f64` they widen to
/// (`null` when not finite), as a `serde_json::Value` of them would be.
pub(super) struct SkeletonJson<'m>(&'m Skeleton);

/// The items of an iterator, serialized as one JSON array.
struct Items<F>(F);

impl<I: Iterator<Item: Serialize>, F: Fn() -> I> Serialize for Items<F> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_seq((self.0)())
    }
}

impl Serialize for SkeletonJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let sk = self.0;
        let mut map = s.serialize_map(Some(4))?;
        map.serialize_entry(
            "parents",
            &Items(|| sk.parents.iter().map(|p| p.map_or(-1, i64::from))),
        )?;
        map.serialize_entry(
            "positions",
            &Items(|| {
                sk.positions
                    .iter()
                    .flat_map(|p| p.to_array())
                    .map(f64::from)
            }),
        )?;
        map.serialize_entry("radii", &Items(|| sk.radii.iter().map(|&r| f64::from(r))))?;
        map.serialize_entry("orders", &sk.orders)?;
        map.end()
    }
}
