//! Foliage levels of detail in the glb: a mesh's `extras.pge.lod` (its LOD tables, written
//! from its [`MeshLod`] and read back by the importer), and the `extras.pge.lod` of the nodes
//! that place a forest's trees (the leaves each placement stands for and the level of detail
//! it is drawn at).

use gltf_json as json;
use serde::ser::{Serialize, SerializeMap, SerializeSeq, Serializer};
use serde_json::{Value as JsonValue, json};

use super::raw;
use crate::geometry::{
    GroupLod, InstanceGroup, LodLevel, LodSector, LodTable, MeshLod, PrimitiveLod,
};
use crate::{Error, Result};

/// The `extras.pge.lod = {leaves = [...], level = [...]}` of a group's instancing node: the
/// leaves and level of every placement, in the order of the instancing accessors (`None`
/// when the group has no leaf counts).
pub(super) fn group_leaves_extras(group: &InstanceGroup) -> Result<json::Extras> {
    let Some(leaves) = &group.leaves else {
        return Ok(None);
    };
    // Written straight as text (serde_json's number formatting, no `Value` tree): a forest's
    // nodes hold millions of these numbers.
    let levels: Vec<i64> = (0..leaves.counts.len()).map(|k| leaves.level(k)).collect();
    let mut text = Vec::with_capacity(48 + 10 * levels.len());
    text.extend_from_slice(br#"{"pge":{"lod":{"leaves":"#);
    let export = |e: serde_json::Error| Error::Export(e.to_string());
    serde_json::to_writer(&mut text, &leaves.counts).map_err(export)?;
    text.extend_from_slice(br#","level":"#);
    serde_json::to_writer(&mut text, &levels).map_err(export)?;
    text.extend_from_slice(b"}}}");
    let text = String::from_utf8(text).map_err(|e| Error::Export(e.to_string()))?;
    serde_json::value::RawValue::from_string(text)
        .map(Some)
        .map_err(export)
}

/// The `extras.pge.lod = {leaves, level}` of the node of placement `k` of a group written
/// one node per placement (`None` when the group has no leaf counts).
pub(super) fn placement_leaves_extras(group: &InstanceGroup, k: usize) -> Result<json::Extras> {
    let Some(leaves) = &group.leaves else {
        return Ok(None);
    };
    let count = leaves.counts.get(k).copied().unwrap_or(0);
    raw(&json!({ "pge": { "lod": { "leaves": count, "level": leaves.level(k) } } }))
}

/// A mesh's `extras.pge.lod`, serialized from its [`MeshLod`] in one pass: a leaf mesh's
/// `{leaves, roots, table: [[a, b, c], ...]}` (`sectors: [{offset, leaves, roots, table}]`
/// for several sectors), a group's `{leaves, roots, primitives: [{primitive, leaves, roots,
/// table | sectors}]}`.
pub(in crate::export) struct LodJson<'a>(pub(in crate::export) &'a MeshLod);

impl Serialize for LodJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(None)?;
        match self.0 {
            MeshLod::Leaves(table) => table_entries(&mut map, table)?,
            MeshLod::Group(group) => {
                map.serialize_entry("leaves", &self.0.leaves())?;
                map.serialize_entry("roots", &self.0.roots())?;
                map.serialize_entry("primitives", &Primitives(group.primitives()))?;
            }
        }
        map.end()
    }
}

/// The entries of a leaf table: `leaves`, `roots`, then `table` or `sectors`.
fn table_entries<M: SerializeMap>(
    map: &mut M,
    table: &LodTable,
) -> std::result::Result<(), M::Error> {
    map.serialize_entry("leaves", &table.leaves())?;
    map.serialize_entry("roots", &table.roots())?;
    match table.sectors() {
        [one] => map.serialize_entry("table", &Rows(one.levels())),
        sectors => map.serialize_entry("sectors", &Sectors(sectors)),
    }
}

/// `[[a, b, c], ...]`.
struct Rows<'a>(&'a [LodLevel]);

impl Serialize for Rows<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_seq(self.0.iter().map(|l| [l.a, l.b, l.c]))
    }
}

/// `[{offset, leaves, roots, table}, ...]`.
struct Sectors<'a>(&'a [LodSector]);

impl Serialize for Sectors<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.0.len()))?;
        for sector in self.0 {
            seq.serialize_element(&Sector(sector))?;
        }
        seq.end()
    }
}

struct Sector<'a>(&'a LodSector);

impl Serialize for Sector<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(4))?;
        map.serialize_entry("offset", &self.0.offset())?;
        map.serialize_entry("leaves", &self.0.leaves())?;
        map.serialize_entry("roots", &self.0.roots())?;
        map.serialize_entry("table", &Rows(self.0.levels()))?;
        map.end()
    }
}

/// `[{primitive, leaves, roots, table | sectors}, ...]`.
struct Primitives<'a>(&'a [PrimitiveLod]);

impl Serialize for Primitives<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.0.len()))?;
        for p in self.0 {
            seq.serialize_element(&Primitive(p))?;
        }
        seq.end()
    }
}

struct Primitive<'a>(&'a PrimitiveLod);

impl Serialize for Primitive<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(None)?;
        map.serialize_entry("primitive", &self.0.primitive)?;
        table_entries(&mut map, &self.0.table)?;
        map.end()
    }
}

/// A mesh's `extras.pge.lod` read back (the glTF importer's): the [`MeshLod`] the writer
/// wrote it from, or `None` when it is not one (not PGE's, inconsistent, or with anything
/// the writer would not write back the same).
#[must_use]
pub fn lod_from_json(value: &JsonValue) -> Option<MeshLod> {
    let lod = match value.get("primitives") {
        Some(list) => {
            let primitives = list
                .as_array()?
                .iter()
                .map(|p| {
                    Some(PrimitiveLod {
                        primitive: number(p, "primitive")?,
                        table: table(p)?,
                    })
                })
                .collect::<Option<Vec<_>>>()?;
            MeshLod::Group(GroupLod::new(primitives).ok()?)
        }
        None => MeshLod::Leaves(table(value)?),
    };
    // Only what is written back to the same JSON.
    let again = serde_json::to_value(LodJson(&lod)).ok()?;
    (again == *value).then_some(lod)
}

fn number(value: &JsonValue, key: &str) -> Option<u32> {
    u32::try_from(value.get(key)?.as_u64()?).ok()
}

/// A leaf table: `{leaves, roots, table}` or `{leaves, roots, sectors}` (the sums are
/// checked by the caller's comparison with the text written back).
fn table(value: &JsonValue) -> Option<LodTable> {
    let sector = |v: &JsonValue, offset: u32| -> Option<LodSector> {
        let levels = v
            .get("table")?
            .as_array()?
            .iter()
            .map(|row| {
                let row = row.as_array()?;
                let get = |k: usize| u32::try_from(row.get(k)?.as_u64()?).ok();
                (row.len() == 3).then_some(())?;
                Some(LodLevel {
                    a: get(0)?,
                    b: get(1)?,
                    c: get(2)?,
                })
            })
            .collect::<Option<Vec<_>>>()?;
        LodSector::new(offset, number(v, "leaves")?, number(v, "roots")?, levels).ok()
    };
    let sectors = match value.get("sectors") {
        Some(list) => list
            .as_array()?
            .iter()
            .map(|s| sector(s, number(s, "offset")?))
            .collect::<Option<Vec<_>>>()?,
        None => vec![sector(value, 0)?],
    };
    LodTable::new(sectors).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(a: u32, b: u32, c: u32) -> LodLevel {
        LodLevel { a, b, c }
    }

    /// Three leaves collapsed to one, V starting at `offset`.
    fn three(offset: u32) -> LodSector {
        let rows = vec![level(0, 4, 1), level(1, 3, 1), level(3, 5, 0)];
        LodSector::new(offset, 3, 1, rows).expect("valid")
    }

    fn text(lod: &MeshLod) -> String {
        serde_json::to_string(&LodJson(lod)).expect("json")
    }

    #[test]
    fn tables_are_written_as_their_maps_were_and_read_back() {
        let one = MeshLod::Leaves(LodTable::new(vec![three(0)]).expect("valid"));
        let one_map = json!({"leaves": 3, "roots": 1, "table": [[0, 4, 1], [1, 3, 1], [3, 5, 0]]});
        assert_eq!(text(&one), one_map.to_string());
        let two = LodTable::new(vec![three(0), three(5)]).expect("valid");
        let rows = json!([[0, 4, 1], [1, 3, 1], [3, 5, 0]]);
        let two_map = json!({"leaves": 6, "roots": 2, "sectors": [
            {"offset": 0, "leaves": 3, "roots": 1, "table": rows},
            {"offset": 5, "leaves": 3, "roots": 1, "table": rows},
        ]});
        assert_eq!(text(&MeshLod::Leaves(two.clone())), two_map.to_string());
        let group = MeshLod::Group(
            GroupLod::new(vec![
                PrimitiveLod {
                    primitive: 1,
                    table: LodTable::new(vec![three(0)]).expect("valid"),
                },
                PrimitiveLod {
                    primitive: 2,
                    table: two,
                },
            ])
            .expect("valid"),
        );
        let mut first = json!({"primitive": 1});
        let mut second = json!({"primitive": 2});
        for (entry, map) in [(&mut first, &one_map), (&mut second, &two_map)] {
            let entry = entry.as_object_mut().expect("object");
            for (k, v) in map.as_object().expect("object") {
                entry.insert(k.clone(), v.clone());
            }
        }
        let group_map = json!({"leaves": 9, "roots": 3, "primitives": [first, second]});
        assert_eq!(text(&group), group_map.to_string());
        for (lod, map) in [(&one, &one_map), (&group, &group_map)] {
            assert_eq!(lod_from_json(map).as_ref(), Some(lod));
        }
        assert!(matches!(lod_from_json(&two_map), Some(MeshLod::Leaves(_))));
    }

    #[test]
    fn what_is_not_written_back_the_same_is_not_read() {
        let good = json!({"leaves": 3, "roots": 1, "table": [[0, 4, 1], [1, 3, 1], [3, 5, 0]]});
        assert!(lod_from_json(&good).is_some());
        let mut bad = Vec::new();
        // Wrong totals, a row too many numbers, a broken row, an extra key, not an object,
        // one sector listed as sectors (written as a table), an offset past the first V.
        for (pointer, value) in [
            ("/leaves", json!(4)),
            ("/roots", json!(-1)),
            ("/table/0", json!([0, 4, 1, 0])),
            ("/table/1", json!([1, 3, 2])),
            ("/table/2", json!("x")),
        ] {
            let mut v = good.clone();
            *v.pointer_mut(pointer).expect("there") = value;
            bad.push(v);
        }
        let mut extra = good.clone();
        extra["mine"] = json!(1);
        bad.push(extra);
        bad.push(json!([1, 2]));
        bad.push(json!({}));
        let rows = good["table"].clone();
        bad.push(json!({"leaves": 3, "roots": 1, "sectors": [
            {"offset": 0, "leaves": 3, "roots": 1, "table": rows}]}));
        bad.push(json!({"leaves": 6, "roots": 2, "sectors": [
            {"offset": 0, "leaves": 3, "roots": 1, "table": rows},
            {"offset": 6, "leaves": 3, "roots": 1, "table": rows}]}));
        bad.push(json!({"leaves": 3, "roots": 1, "primitives": []}));
        bad.push(json!({"leaves": 3, "roots": 1, "primitives": [good]}));
        for v in &bad {
            assert_eq!(lod_from_json(v), None, "{v}");
        }
    }
}
