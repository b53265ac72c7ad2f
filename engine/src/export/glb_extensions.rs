//! The glTF extensions gltf-json has no fields for (without its extension features):
//! added to the root's JSON as a `serde_json::Value`, the meshes' extras (skeleton markers
//! and all) kept out of it and written back as they are.

use gltf_json as json;
use serde::ser::{Serialize, SerializeMap, SerializeSeq, Serializer};
use serde_json::value::RawValue;
use serde_json::{Value as JsonValue, json};

use crate::geometry::DiffuseTransmission;
use crate::{Error, Result};

use super::{GPU_INSTANCING, UNLIT};

/// The name of the glTF extension of materials that let light through (leaves): declared in
/// `extensionsUsed`, not required (a client without it draws the material as it would
/// without the extension).
pub const DIFFUSE_TRANSMISSION: &str = "KHR_materials_diffuse_transmission";

/// The root's JSON with `EXT_mesh_gpu_instancing` on the given nodes (index, [TRANSLATION,
/// ROTATION, SCALE] accessors), `KHR_materials_unlit` and
/// `KHR_materials_diffuse_transmission` on the given materials, and the extensions used
/// declared in `extensionsUsed` (gltf-json has no fields for them without its extension
/// features).
pub(super) fn with_extensions(
    root: &mut json::Root,
    nodes: &[(usize, [usize; 3])],
    unlit: &[usize],
    transmissive: &[(usize, DiffuseTransmission)],
) -> Result<Vec<u8>> {
    let export = |e: serde_json::Error| Error::Export(e.to_string());
    // The meshes' extras stay out of the `Value` (parsing a tree's skeleton back would cost
    // more than writing it), a number holding their place.
    let place = RawValue::from_string("0".into()).map_err(export)?;
    let extras: Vec<json::Extras> = root
        .meshes
        .iter_mut()
        .map(|m| {
            m.extras
                .as_mut()
                .map(|e| std::mem::replace(e, place.clone()))
        })
        .collect();
    let value = serde_json::to_value(&*root).map_err(export);
    for (mesh, e) in root.meshes.iter_mut().zip(&extras) {
        if e.is_some() {
            mesh.extras.clone_from(e);
        }
    }
    let mut value = value?;
    let mut material_extension = |index: usize, name: &str, ext: JsonValue| -> Result<()> {
        let material = value
            .get_mut("materials")
            .and_then(|m| m.get_mut(index))
            .and_then(JsonValue::as_object_mut)
            .ok_or_else(|| Error::Export(format!("a material with {name} is missing")))?;
        let extensions = material
            .entry("extensions")
            .or_insert_with(|| json!({}))
            .as_object_mut()
            .ok_or_else(|| Error::Export("a material's extensions are not an object".into()))?;
        extensions.insert(name.into(), ext);
        Ok(())
    };
    for &index in unlit {
        material_extension(index, UNLIT, json!({}))?;
    }
    for &(index, t) in transmissive {
        material_extension(
            index,
            DIFFUSE_TRANSMISSION,
            json!({
                "diffuseTransmissionFactor": t.factor,
                "diffuseTransmissionColorFactor": t.color,
            }),
        )?;
    }
    for &(index, [t, r, s]) in nodes {
        let node = value
            .get_mut("nodes")
            .and_then(|n| n.get_mut(index))
            .and_then(JsonValue::as_object_mut)
            .ok_or_else(|| Error::Export("an instancing node is missing".into()))?;
        node.insert(
            "extensions".into(),
            json!({ GPU_INSTANCING: { "attributes": {
                "TRANSLATION": t, "ROTATION": r, "SCALE": s } } }),
        );
    }
    let mut used = Vec::new();
    if !nodes.is_empty() {
        used.push(GPU_INSTANCING);
    }
    if !unlit.is_empty() {
        used.push(UNLIT);
    }
    if !transmissive.is_empty() {
        used.push(DIFFUSE_TRANSMISSION);
    }
    if let Some(root) = value.as_object_mut() {
        root.insert("extensionsUsed".into(), json!(used));
    }
    serde_json::to_vec(&WithMeshExtras(&value, &extras)).map_err(export)
}

/// The root's `Value` with each mesh's extras (`meshes[i].extras`) written from the raw
/// text in place of the number that held its place: the same text as a `Value` holding them
/// would give.
struct WithMeshExtras<'a>(&'a JsonValue, &'a [json::Extras]);

impl Serialize for WithMeshExtras<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let Some(root) = self.0.as_object() else {
            return self.0.serialize(s);
        };
        let mut map = s.serialize_map(Some(root.len()))?;
        for (key, value) in root {
            match value.as_array() {
                Some(meshes) if key == "meshes" => {
                    map.serialize_entry(key, &Meshes(meshes, self.1))?;
                }
                _ => map.serialize_entry(key, value)?,
            }
        }
        map.end()
    }
}

/// The meshes' `Value`s and their raw extras.
struct Meshes<'a>(&'a [JsonValue], &'a [json::Extras]);

impl Serialize for Meshes<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.0.len()))?;
        for (i, mesh) in self.0.iter().enumerate() {
            let extras = self.1.get(i).and_then(Option::as_deref);
            seq.serialize_element(&MeshValue(mesh, extras))?;
        }
        seq.end()
    }
}

/// A mesh's `Value` and its raw extras.
struct MeshValue<'a>(&'a JsonValue, Option<&'a RawValue>);

impl Serialize for MeshValue<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let (Some(mesh), Some(extras)) = (self.0.as_object(), self.1) else {
            return self.0.serialize(s);
        };
        let mut map = s.serialize_map(Some(mesh.len()))?;
        for (key, value) in mesh {
            if key == "extras" {
                map.serialize_entry(key, extras)?;
            } else {
                map.serialize_entry(key, value)?;
            }
        }
        map.end()
    }
}
