//! The `extras.pge.lod` of the nodes that place a forest's trees: the leaves each placement
//! stands for and the level of detail it is drawn at.

use gltf_json as json;
use serde_json::json;

use super::raw;
use crate::geometry::InstanceGroup;
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
