//! The glTF extensions gltf-json has no fields for (without its extension features): written
//! into the root's JSON text as it is serialized, at the end of the objects that use them,
//! with every float written as the `f64` it widens to.

use gltf_json as json;
use serde::Serialize;
use serde_json::ser::{CompactFormatter, Formatter};
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
/// features). The text is the one a `serde_json::Value` of the root with the extensions
/// inserted would give (files with extensions have always been written so): each
/// `extensions` object last in its material or node (in place of an empty one gltf-json
/// wrote), `extensionsUsed` last in the root,
/// floats as the `f64` they widen to.
pub(super) fn with_extensions(
    root: &mut json::Root,
    nodes: &[(usize, [usize; 3])],
    unlit: &[usize],
    transmissive: &[(usize, DiffuseTransmission)],
) -> Result<Vec<u8>> {
    let export = |e: serde_json::Error| Error::Export(e.to_string());
    let mut materials = vec![Extensions::default(); root.materials.len()];
    let mut material_extension = |index: usize, name: &'static str, ext: JsonValue| {
        materials
            .get_mut(index)
            .map(|e| e.insert(name, ext))
            .ok_or_else(|| Error::Export(format!("a material with {name} is missing")))
    };
    for &index in unlit {
        material_extension(index, UNLIT, json!({}))?;
    }
    for &(index, t) in transmissive {
        let ext = json!({
            "diffuseTransmissionFactor": t.factor,
            "diffuseTransmissionColorFactor": t.color,
        });
        material_extension(index, DIFFUSE_TRANSMISSION, ext)?;
    }
    let mut instanced = vec![Extensions::default(); root.nodes.len()];
    for &(index, [t, r, s]) in nodes {
        let ext = json!({ "attributes": { "TRANSLATION": t, "ROTATION": r, "SCALE": s } });
        let node = instanced
            .get_mut(index)
            .ok_or_else(|| Error::Export("an instancing node is missing".into()))?;
        // The node's extensions are this one alone.
        *node = Extensions::default();
        node.insert(GPU_INSTANCING, ext);
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
    // The root's fields up to the images as gltf-json writes them, the last seven (materials
    // to textures, in gltf-json's order) one by one after them, then `extensionsUsed`.
    let tail = Tail::take(root);
    let head = text(&*root);
    tail.put_back(root);
    let mut out = head.map_err(export)?;
    if out.pop() != Some(b'}') {
        return Err(Error::Export("the glTF root is not a JSON object".into()));
    }
    let none: &[Extensions] = &[];
    array(&mut out, "materials", &root.materials, &materials).map_err(export)?;
    array(&mut out, "meshes", &root.meshes, none).map_err(export)?;
    array(&mut out, "nodes", &root.nodes, &instanced).map_err(export)?;
    array(&mut out, "samplers", &root.samplers, none).map_err(export)?;
    array(&mut out, "scenes", &root.scenes, none).map_err(export)?;
    array(&mut out, "skins", &root.skins, none).map_err(export)?;
    array(&mut out, "textures", &root.textures, none).map_err(export)?;
    out.extend_from_slice(br#","extensionsUsed":"#);
    write(&mut out, &used).map_err(export)?;
    out.push(b'}');
    Ok(out)
}

/// The root's last seven arrays, taken out while the fields before them are written.
struct Tail {
    materials: Vec<json::Material>,
    meshes: Vec<json::Mesh>,
    nodes: Vec<json::Node>,
    samplers: Vec<json::texture::Sampler>,
    scenes: Vec<json::Scene>,
    skins: Vec<json::Skin>,
    textures: Vec<json::Texture>,
}

impl Tail {
    fn take(root: &mut json::Root) -> Tail {
        use std::mem::take;
        Tail {
            materials: take(&mut root.materials),
            meshes: take(&mut root.meshes),
            nodes: take(&mut root.nodes),
            samplers: take(&mut root.samplers),
            scenes: take(&mut root.scenes),
            skins: take(&mut root.skins),
            textures: take(&mut root.textures),
        }
    }

    fn put_back(self, root: &mut json::Root) {
        root.materials = self.materials;
        root.meshes = self.meshes;
        root.nodes = self.nodes;
        root.samplers = self.samplers;
        root.scenes = self.scenes;
        root.skins = self.skins;
        root.textures = self.textures;
    }
}

/// An object's extensions: names and their values, in the order first inserted.
#[derive(Clone, Default)]
struct Extensions(Vec<(&'static str, JsonValue)>);

impl Extensions {
    /// Adds `name`, or replaces its value where it stands.
    fn insert(&mut self, name: &'static str, ext: JsonValue) {
        match self.0.iter_mut().find(|(n, _)| *n == name) {
            Some(entry) => entry.1 = ext,
            None => self.0.push((name, ext)),
        }
    }
}

/// `,"key":[...]` for a non-empty array, each item with its extensions (if any).
fn array<T: Serialize>(
    out: &mut Vec<u8>,
    key: &str,
    items: &[T],
    extensions: &[Extensions],
) -> serde_json::Result<()> {
    if items.is_empty() {
        return Ok(());
    }
    out.push(b',');
    write(out, key)?;
    out.extend_from_slice(b":[");
    for (i, item) in items.iter().enumerate() {
        if i > 0 {
            out.push(b',');
        }
        let Some(Extensions(ext)) = extensions.get(i).filter(|e| !e.0.is_empty()) else {
            write(out, item)?;
            continue;
        };
        // An item with extensions goes through a `Value` of its own, as the whole root once
        // did: they take the place of an `extensions` object gltf-json wrote (an empty one, as
        // its extension features are off: a variant read back from a glb has one), or go last.
        let mut value = serde_json::to_value(item)?;
        let entries = value
            .as_object_mut()
            .map(|object| object.entry("extensions").or_insert_with(|| json!({})))
            .and_then(JsonValue::as_object_mut)
            .ok_or_else(|| serde::ser::Error::custom("an object's extensions are not an object"))?;
        for (name, ext) in ext {
            entries.insert((*name).into(), ext.clone());
        }
        write(out, &value)?;
    }
    out.push(b']');
    Ok(())
}

/// `value` as compact JSON, floats widened to `f64` ([`Widened`]).
fn text<T: Serialize + ?Sized>(value: &T) -> serde_json::Result<Vec<u8>> {
    let mut out = Vec::new();
    write(&mut out, value)?;
    Ok(out)
}

/// Writes `value` at the end of `out` as [`text`] does.
fn write<T: Serialize + ?Sized>(out: &mut Vec<u8>, value: &T) -> serde_json::Result<()> {
    value.serialize(&mut serde_json::Serializer::with_formatter(out, Widened))
}

/// Compact JSON with each `f32` written as the `f64` it widens to (`0.1f32` as
/// `0.10000000149011612`), as a `serde_json::Value` holds it.
struct Widened;

impl Formatter for Widened {
    fn write_f32<W: ?Sized + std::io::Write>(
        &mut self,
        writer: &mut W,
        value: f32,
    ) -> std::io::Result<()> {
        CompactFormatter.write_f64(writer, f64::from(value))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use json::validation::Checked::Valid;
    use serde_json::value::RawValue;

    /// The text of the root with the extensions inserted in its `serde_json::Value`.
    fn through_a_value(
        root: &json::Root,
        nodes: &[(usize, [usize; 3])],
        unlit: &[usize],
        transmissive: &[(usize, DiffuseTransmission)],
    ) -> Vec<u8> {
        let mut value = serde_json::to_value(root).expect("value");
        let mut add = |index: usize, name: &str, ext: JsonValue| {
            let material = value["materials"][index].as_object_mut().expect("object");
            let extensions = material.entry("extensions").or_insert_with(|| json!({}));
            extensions[name] = ext;
        };
        for &index in unlit {
            add(index, UNLIT, json!({}));
        }
        for &(index, t) in transmissive {
            add(
                index,
                DIFFUSE_TRANSMISSION,
                json!({ "diffuseTransmissionFactor": t.factor,
                    "diffuseTransmissionColorFactor": t.color }),
            );
        }
        for &(index, [t, r, s]) in nodes {
            value["nodes"][index]["extensions"] = json!({ GPU_INSTANCING: { "attributes": {
                "TRANSLATION": t, "ROTATION": r, "SCALE": s } } });
        }
        let mut used = Vec::new();
        for (on, name) in [
            (!nodes.is_empty(), GPU_INSTANCING),
            (!unlit.is_empty(), UNLIT),
            (!transmissive.is_empty(), DIFFUSE_TRANSMISSION),
        ] {
            if on {
                used.push(name);
            }
        }
        value["extensionsUsed"] = json!(used);
        serde_json::to_vec(&value).expect("text")
    }

    #[test]
    fn extensions_are_written_as_a_value_tree_would_write_them() {
        let raw = |s: &str| Some(RawValue::from_string(s.into()).expect("raw"));
        let mut root = json::Root::default();
        root.asset.generator = Some("a \"test\" é".into());
        root.extras = raw(r#"{"pge":{"seed":3,"params":{"w":5.5,"s":0.1}}}"#);
        let material = |name: &str, c: f32| json::Material {
            name: Some(name.into()),
            alpha_mode: Valid(json::material::AlphaMode::Mask),
            alpha_cutoff: Some(json::material::AlphaCutoff(0.3)),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor([c, 0.2, 1e-7, 1.0]),
                ..Default::default()
            },
            ..Default::default()
        };
        root.materials = vec![material("bark", 0.1), material("leaves", -0.0)];
        root.meshes = vec![json::Mesh {
            extensions: None,
            extras: raw(r#"{"pge":{"skeleton":{"radii":[0.1,null]}}}"#),
            name: Some("bark".into()),
            primitives: Vec::new(),
            weights: None,
        }];
        root.nodes = vec![
            json::Node {
                mesh: Some(json::Index::new(0)),
                translation: Some([0.1, f32::NAN, 3.0]),
                ..Default::default()
            },
            json::Node::default(),
        ];
        root.scenes = vec![json::Scene {
            extensions: None,
            extras: raw(r#"{"pge":{"a":[1,2.5]}}"#),
            name: Some("pge".into()),
            nodes: vec![json::Index::new(0), json::Index::new(1)],
        }];
        let t = DiffuseTransmission {
            factor: 0.25,
            color: [0.1, 0.7, 1.0],
        };
        let check = |root: &mut json::Root,
                     nodes: &[(usize, [usize; 3])],
                     unlit: &[usize],
                     transmissive: &[(usize, DiffuseTransmission)]| {
            let want = through_a_value(root, nodes, unlit, transmissive);
            let got = with_extensions(root, nodes, unlit, transmissive).expect("text");
            assert_eq!(
                String::from_utf8(got).expect("utf-8"),
                String::from_utf8(want).expect("utf-8")
            );
        };
        let every_case = |root: &mut json::Root| {
            check(
                root,
                &[(1, [1, 2, 3]), (0, [4, 5, 6])],
                &[1],
                &[(0, t), (1, t)],
            );
            check(root, &[], &[], &[(1, t)]);
            check(root, &[(1, [1, 2, 3])], &[0, 0], &[]);
        };
        every_case(&mut root);
        // Read back from a glb (a forest's shared variants), a material and a node carry an
        // empty `extensions` object of gltf-json's own: the extensions go in its place.
        root.materials[1].extensions = Some(Default::default());
        root.nodes[0].extensions = Some(Default::default());
        root.materials[1].extras = raw(r#"{"pge":1}"#);
        every_case(&mut root);
        // A material or node that is not there is an error, not a panic.
        assert!(with_extensions(&mut root, &[], &[2], &[]).is_err());
        assert!(with_extensions(&mut root, &[(2, [0; 3])], &[], &[]).is_err());
    }
}
