//! Variants shared by the tiles of a world (`pge run --variants-out DIR`, `--variants DIR`):
//! the variant meshes, materials and textures written once, as a binary file and its glTF
//! description, and tiles whose instance groups refer to them.
//!
//! The description (`variants.json`) is a glTF 2.0 document of its own: `buffers[0]` is the
//! binary file (by a relative `uri`), then the buffer views, accessors, images, samplers,
//! textures, materials and meshes of the variants, one glTF mesh per variant, exactly as a
//! standalone tile writes them; `extras.pge.variants` says what they were grown from and
//! lists the variants (`groups`: name, mesh index and what one instance of it draws). A tile
//! that refers to them starts its glTF arrays with the description's (so their indices stay
//! as they are), its own buffer 0 holding the terrain patch and the instances (the GLB's
//! binary chunk) and buffer 1 the shared file, by a `uri` relative to the tile.

use serde_json::{Map, Value as JsonValue, json};

use super::{
    Builder, DIFFUSE_TRANSMISSION, ExportMeta, Instancing, JsonText, Prepared, json as gltf, raw,
    with_extensions,
};
use crate::geometry::{DiffuseTransmission, Model};
use crate::{Error, Result};

/// The format named in a description's `extras.pge.variants.format`.
pub const VARIANTS_FORMAT: &str = "pge-variants/1";

/// One variant of a shared variants description.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SharedGroup {
    /// The instance group's name (`SPECIES/VARIANT`).
    pub name: String,
    /// Its glTF mesh in the description.
    pub mesh: usize,
    /// Vertices one instance draws.
    pub vertices: u64,
    /// Triangles one instance draws.
    pub triangles: u64,
    /// Nodes (of the grown tree) one instance stands for.
    pub nodes: u64,
    /// Leaves one instance stands for.
    pub leaves: u64,
}

/// A shared variants description, read back (`variants.json`).
#[derive(Clone, Debug)]
pub struct SharedVariants {
    root: gltf::Root,
    groups: Vec<SharedGroup>,
    info: Map<String, JsonValue>,
    bin_bytes: u64,
    /// Materials with `KHR_materials_diffuse_transmission` (gltf-json reads no extension).
    transmissive: Vec<(usize, DiffuseTransmission)>,
}

impl SharedVariants {
    /// Reads a description written by [`variants_files`]; an [`Error::Export`] saying what is
    /// wrong with one that is not.
    pub fn parse(text: &[u8]) -> Result<SharedVariants> {
        let bad = |what: &str| Error::Export(format!("not a shared variants description ({what})"));
        let mut value: JsonValue = serde_json::from_slice(text).map_err(|e| bad(&e.to_string()))?;
        // The variants' own extras (their skeletons, most of the description) stay in the
        // description: a tile places the meshes, it does not describe them.
        if let Some(meshes) = value.get_mut("meshes").and_then(JsonValue::as_array_mut) {
            for mesh in meshes.iter_mut().filter_map(JsonValue::as_object_mut) {
                mesh.remove("extras");
            }
        }
        let transmissive = transmissive_materials(&value);
        let root: gltf::Root = serde_json::from_value(value).map_err(|e| bad(&e.to_string()))?;
        let extras: JsonValue = match &root.extras {
            Some(raw) => serde_json::from_str(raw.get()).map_err(|e| bad(&e.to_string()))?,
            None => return Err(bad("no extras.pge.variants")),
        };
        let Some(JsonValue::Object(info)) = extras.pointer("/pge/variants") else {
            return Err(bad("no extras.pge.variants"));
        };
        if info.get("format").and_then(JsonValue::as_str) != Some(VARIANTS_FORMAT) {
            return Err(bad(&format!("its format is not {VARIANTS_FORMAT}")));
        }
        let [buffer] = root.buffers.as_slice() else {
            return Err(bad("it must have one buffer"));
        };
        let bin_bytes = buffer.byte_length.0;
        if root.buffer_views.iter().any(|v| v.buffer.value() != 0) {
            return Err(bad("a buffer view of another buffer"));
        }
        // The importer's checks, as for any glTF PGE reads: indices in range (the gltf
        // crate's own validation would panic on some), every accessor inside its view with a
        // stride that holds its element, every view inside the binary file's recorded length.
        let document = crate::import::open(text)
            .map_err(|e| bad(&e.to_string()))?
            .document;
        let length = usize::try_from(bin_bytes).map_err(|_| bad("its buffer is too long"))?;
        crate::import::check_layout(&document, &[length]).map_err(|e| bad(&e.to_string()))?;
        let mut groups = Vec::new();
        for g in info
            .get("groups")
            .and_then(JsonValue::as_array)
            .ok_or_else(|| bad("no groups"))?
        {
            // What one instance draws and stands for: at most what a glTF count holds.
            let number = |k: &str| {
                g.get(k)
                    .and_then(JsonValue::as_u64)
                    .filter(|&n| n <= u64::from(u32::MAX))
                    .ok_or_else(|| bad(&format!("a group without {k} (a count below 2^32)")))
            };
            let mesh = number("mesh")?;
            if mesh >= root.meshes.len() as u64 {
                return Err(bad(&format!("a group's mesh {mesh} does not exist")));
            }
            groups.push(SharedGroup {
                name: g
                    .get("name")
                    .and_then(JsonValue::as_str)
                    .ok_or_else(|| bad("a group without a name"))?
                    .to_string(),
                mesh: mesh as usize,
                vertices: number("vertices")?,
                triangles: number("triangles")?,
                nodes: number("nodes")?,
                leaves: number("leaves")?,
            });
        }
        Ok(SharedVariants {
            transmissive,
            bin_bytes,
            root,
            groups,
            info: info.clone(),
        })
    }

    /// `extras.pge.variants`: the format, what the variants were grown from (as the caller of
    /// [`variants_files`] recorded it) and the groups.
    #[must_use]
    pub fn info(&self) -> &Map<String, JsonValue> {
        &self.info
    }

    /// The variants, in the order they were written.
    #[must_use]
    pub fn groups(&self) -> &[SharedGroup] {
        &self.groups
    }

    /// The length of the binary file the description refers to.
    #[must_use]
    pub fn bin_bytes(&self) -> u64 {
        self.bin_bytes
    }

    /// The variant named `name`.
    #[must_use]
    pub fn group(&self, name: &str) -> Option<&SharedGroup> {
        self.groups.iter().find(|g| g.name == name)
    }
}

/// The materials of a glTF JSON document that carry `KHR_materials_diffuse_transmission`,
/// with their factor and colour.
fn transmissive_materials(value: &JsonValue) -> Vec<(usize, DiffuseTransmission)> {
    let Some(materials) = value.get("materials").and_then(JsonValue::as_array) else {
        return Vec::new();
    };
    let number = |v: Option<&JsonValue>, default: f64| {
        v.and_then(JsonValue::as_f64).unwrap_or(default) as f32
    };
    materials
        .iter()
        .enumerate()
        .filter_map(|(k, m)| {
            let t = m.get("extensions")?.get(DIFFUSE_TRANSMISSION)?;
            let color = t
                .get("diffuseTransmissionColorFactor")
                .and_then(JsonValue::as_array);
            let channel = |i: usize| number(color.and_then(|c| c.get(i)), 1.0);
            Some((
                k,
                DiffuseTransmission {
                    factor: number(t.get("diffuseTransmissionFactor"), 0.0),
                    color: [channel(0), channel(1), channel(2)],
                },
            ))
        })
        .collect()
}

/// The shared variants of a world as its description (`variants.json`, naming the binary
/// file `bin_uri`) and binary file: one glTF mesh per instance group of `variants` (written
/// as a standalone tile writes a group's mesh; the groups' placements are not written), and
/// `extras.pge.variants` = `info` with `format` and `groups` added. `counts[g]` is what one
/// instance of group `g` stands for, `[nodes, leaves]` (the stats a tile adds up).
pub fn variants_files(
    variants: &Model,
    counts: &[[u64; 2]],
    mut info: Map<String, JsonValue>,
    bin_uri: &str,
) -> Result<(Vec<u8>, Vec<u8>)> {
    variants.validate()?;
    let mut b = Builder::new();
    let mut groups = Vec::with_capacity(variants.groups.len());
    for (g, group) in variants.groups.iter().enumerate() {
        let mesh = b.group_mesh(group, &variants.meshes)?;
        let drawn = |per: fn(&crate::geometry::Mesh) -> usize| -> u64 {
            group
                .meshes
                .iter()
                .map(|&m| per(&variants.meshes[m]) as u64)
                .sum()
        };
        let [nodes, leaves] = counts.get(g).copied().unwrap_or_default();
        groups.push(json!({
            "name": group.name,
            "mesh": mesh.value(),
            "vertices": drawn(crate::geometry::Mesh::vertex_count),
            "triangles": drawn(crate::geometry::Mesh::triangle_count),
            "nodes": nodes,
            "leaves": leaves,
        }));
    }
    info.insert("format".into(), VARIANTS_FORMAT.into());
    info.insert("groups".into(), JsonValue::Array(groups));
    b.root.extras = raw(&json!({ "pge": { "variants": info } }))?;
    let bin_len = b.layout.padded_len().max(4);
    b.root.push(gltf::Buffer {
        byte_length: gltf::validation::USize64(bin_len as u64),
        name: None,
        uri: Some(bin_uri.to_string()),
        extensions: None,
        extras: None,
    });
    let text = if b.unlit.is_empty() && b.transmissive.is_empty() {
        b.root.to_vec().map_err(|e| Error::Export(e.to_string()))?
    } else {
        with_extensions(&mut b.root, &[], &b.unlit, &b.transmissive)?
    };
    let text = JsonText::new(text, &b.skeletons, &Prepared::default())?.into_vec();
    let mut bin = vec![0; bin_len];
    b.layout.write(&mut bin);
    Ok((text, bin))
}

/// [`glb_bytes_with`](super::glb_bytes_with) of a tile whose instance groups without meshes
/// of their own are `shared`'s variants of the same name: the description's glTF arrays come
/// first (its meshes without their `extras`, which stay in the description), the tile's terrain, its own meshes and the instances follow in the GLB's binary
/// chunk (buffer 0), and buffer 1 is the shared binary file at `uri` (relative to the tile).
/// The root's `extras.pge.stats` count the shared variants' instances too, as the standalone
/// tile's do. An instance group that has no meshes and no variant of its name in `shared` is
/// an [`Error::Export`].
pub fn glb_bytes_shared(
    model: &Model,
    meta: &ExportMeta,
    instancing: Instancing,
    shared: &SharedVariants,
    uri: &str,
) -> Result<Vec<u8>> {
    model.validate()?;
    let mut b = Builder::new();
    b.instancing = instancing;
    let from = &shared.root;
    b.root.buffer_views = from.buffer_views.clone();
    for view in &mut b.root.buffer_views {
        view.buffer = gltf::Index::new(1);
    }
    b.root.accessors = from.accessors.clone();
    b.root.images = from.images.clone();
    b.root.samplers = from.samplers.clone();
    b.root.textures = from.textures.clone();
    b.root.materials = from.materials.clone();
    b.root.meshes = from.meshes.clone();
    b.transmissive.clone_from(&shared.transmissive);
    b.shared = Some(Shared {
        groups: shared.groups.clone(),
        uri: uri.to_string(),
        bytes: shared.bin_bytes,
    });
    b.root.scene = Some(b.scene(model, "pge")?);
    b.finish(model, meta, None)
}

/// What a tile's [`Builder`] keeps of the shared variants.
#[derive(Clone, Debug, Default)]
pub(super) struct Shared {
    groups: Vec<SharedGroup>,
    uri: String,
    bytes: u64,
}

impl Builder {
    /// The shared mesh of `group` when the tile refers to shared variants and the group has
    /// no meshes of its own; an error when it has none and no variant of its name is shared.
    pub(super) fn shared_mesh(
        &self,
        group: &crate::geometry::InstanceGroup,
    ) -> Result<Option<gltf::Index<gltf::Mesh>>> {
        let Some(shared) = &self.shared else {
            return Ok(None);
        };
        if !group.meshes.is_empty() {
            return Ok(None);
        }
        match shared.groups.iter().find(|g| g.name == group.name) {
            Some(g) => Ok(Some(gltf::Index::new(g.mesh as u32))),
            None => Err(Error::Export(format!(
                "the shared variants have no variant {} (write them again with --variants-out)",
                group.name
            ))),
        }
    }

    /// What the shared variants' instances of `model` draw and stand for: vertices,
    /// triangles, nodes, leaves.
    pub(super) fn shared_counts(&self, model: &Model) -> [u64; 4] {
        let mut sum = [0u64; 4];
        let Some(shared) = &self.shared else {
            return sum;
        };
        for group in model.groups.iter().filter(|g| g.meshes.is_empty()) {
            if let Some(g) = shared.groups.iter().find(|g| g.name == group.name) {
                let n = group.transforms.len() as u64;
                for (s, per) in sum
                    .iter_mut()
                    .zip([g.vertices, g.triangles, g.nodes, g.leaves])
                {
                    *s = s.saturating_add(n.saturating_mul(per));
                }
            }
        }
        sum
    }

    /// Buffer 1, the shared binary file, after the tile's own (when the tile refers to one).
    pub(super) fn push_shared_buffer(&mut self) {
        if let Some(shared) = &self.shared {
            let buffer = gltf::Buffer {
                byte_length: gltf::validation::USize64(shared.bytes),
                name: None,
                uri: Some(shared.uri.clone()),
                extensions: None,
                extras: None,
            };
            self.root.push(buffer);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{InstanceGroup, InstanceTransform, Mesh};
    use glam::{Mat4, Vec3};

    fn triangle(name: &str) -> Mesh {
        let mut m =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("mesh");
        m.name = name.into();
        m.extras
            .insert("note".into(), json!("kept in the description"));
        m
    }

    #[test]
    fn a_tile_refers_to_the_shared_meshes_and_counts_their_instances() {
        let mut variants = Model::new();
        variants.meshes.push(std::sync::Arc::new(triangle("oak/0")));
        variants.groups.push(InstanceGroup {
            name: "oak/0".into(),
            meshes: vec![0],
            transforms: Vec::new(),
            leaves: None,
        });
        let (text, bin) =
            variants_files(&variants, &[[5, 2]], Map::new(), "variants.bin").expect("files");
        let description: JsonValue = serde_json::from_slice(&text).expect("json");
        assert_eq!(description["buffers"][0]["uri"], "variants.bin");
        assert_eq!(description["buffers"][0]["byteLength"], bin.len());
        assert_eq!(
            description["meshes"][0]["extras"]["pge"]["note"],
            "kept in the description"
        );
        let shared = SharedVariants::parse(&text).expect("parsed");
        assert_eq!(
            shared.group("oak/0").map(|g| (g.mesh, g.nodes)),
            Some((0, 5))
        );

        let mut tile = Model::new();
        tile.add_mesh(triangle("terrain"), Mat4::IDENTITY);
        let at = |x: f32| InstanceTransform {
            translation: [x, 0.0, 0.0],
            rotation: [0.0, 0.0, 0.0, 1.0],
            scale: 1.0,
        };
        tile.groups.push(InstanceGroup {
            name: "oak/0".into(),
            meshes: Vec::new(),
            transforms: vec![at(1.0), at(2.0)],
            leaves: None,
        });
        let glb = glb_bytes_shared(
            &tile,
            &ExportMeta::default(),
            Instancing::Gpu,
            &shared,
            "../v",
        )
        .expect("tile");
        let file = ::gltf::binary::Glb::from_slice(&glb).expect("glb");
        let json: JsonValue = serde_json::from_slice(&file.json).expect("json");
        assert_eq!(json["buffers"][1]["uri"], "../v");
        assert_eq!(json["bufferViews"][0]["buffer"], 1);
        assert_eq!(json["meshes"][0]["name"], "oak/0");
        assert!(
            json["meshes"][0].get("extras").is_none(),
            "{}",
            json["meshes"][0]
        );
        assert_eq!(json["extras"]["pge"]["stats"]["nodes"], 10);
        assert_eq!(json["extras"]["pge"]["stats"]["vertices"], 3 + 2 * 3);

        tile.groups[0].name = "elm/0".into();
        let err = glb_bytes_shared(&tile, &ExportMeta::default(), Instancing::Gpu, &shared, "v")
            .expect_err("no such variant");
        assert!(err.to_string().contains("elm/0"), "{err}");
        assert!(SharedVariants::parse(b"{}").is_err());
    }
}
