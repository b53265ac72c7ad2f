//! glTF 2.0 binary export (gltf-json), deterministic to the byte.

use std::sync::Arc;

use glam::{Mat4, Vec3};
use gltf_json as json;
use json::validation::Checked::Valid;
use json::validation::USize64;
use serde_json::{Map, Value as JsonValue, json};

use crate::geometry::{
    AlphaMode, InstanceGroup, Material, Mesh, Model, Primitive, Skeleton, Texture,
};
use crate::{Error, Result};

/// What the root `extras.pge` records besides the model's own extras.
#[derive(Clone, Debug, Default)]
pub struct ExportMeta {
    /// The run's seed.
    pub seed: u64,
    /// Declared parameters and their values, in order.
    pub params: Vec<(String, JsonValue)>,
}

/// How the placements of an [`InstanceGroup`] (a forest's trees) are written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Instancing {
    /// One node per group with `EXT_mesh_gpu_instancing` (TRANSLATION, ROTATION and SCALE
    /// accessors), declared in `extensionsUsed`.
    #[default]
    Gpu,
    /// One plain node per placement, for tools without the extension.
    Nodes,
}

/// The name of the glTF extension used by [`Instancing::Gpu`].
pub const GPU_INSTANCING: &str = "EXT_mesh_gpu_instancing";

/// The generator string written to `asset.generator` and `extras.pge.generator`.
pub const GENERATOR: &str = concat!("PGE ", env!("CARGO_PKG_VERSION"));

#[derive(Default)]
struct Builder {
    root: json::Root,
    bin: Vec<u8>,
    materials: Vec<(Arc<Material>, json::Index<json::Material>)>,
    textures: Vec<(Arc<Texture>, json::Index<json::Texture>)>,
    images: Vec<(Arc<Texture>, json::Index<json::Image>)>,
    sampler: Option<json::Index<json::texture::Sampler>>,
    /// How instance groups are written.
    instancing: Instancing,
    /// Nodes that need `EXT_mesh_gpu_instancing`, with their TRANSLATION/ROTATION/SCALE
    /// accessors.
    gpu_nodes: Vec<(usize, [usize; 3])>,
}

fn raw(value: &JsonValue) -> Result<json::Extras> {
    serde_json::value::to_raw_value(value)
        .map(Some)
        .map_err(|e| Error::Export(e.to_string()))
}

/// The index already written for `item` (the same `Arc` or an equal value), if any.
fn written<T: PartialEq, I: Copy>(list: &[(Arc<T>, I)], item: &Arc<T>) -> Option<I> {
    list.iter()
        .find(|(x, _)| Arc::ptr_eq(x, item) || **x == **item)
        .map(|(_, i)| *i)
}

impl Builder {
    fn view(
        &mut self,
        bytes: &[u8],
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64(bytes.len() as u64),
            byte_offset: Some(USize64(offset as u64)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: None,
        })
    }

    fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        component: json::accessor::ComponentType,
        type_: json::accessor::Type,
        bounds: Option<(JsonValue, JsonValue)>,
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::Accessor> {
        let view = self.view(bytes, target);
        let (min, max) = match bounds {
            Some((a, b)) => (Some(a), Some(b)),
            None => (None, None),
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: Some(USize64(0)),
            count: USize64(count as u64),
            component_type: Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: None,
            type_: Valid(type_),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    fn floats(&mut self, data: &[f32], per: usize, bounds: bool) -> json::Index<json::Accessor> {
        use json::accessor::Type;
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        let type_ = match per {
            2 => Type::Vec2,
            3 => Type::Vec3,
            _ => Type::Vec4,
        };
        let b = bounds.then(|| {
            let mut lo = vec![f32::INFINITY; per];
            let mut hi = vec![f32::NEG_INFINITY; per];
            for c in data.chunks_exact(per) {
                for k in 0..per {
                    lo[k] = lo[k].min(c[k]);
                    hi[k] = hi[k].max(c[k]);
                }
            }
            (json!(lo), json!(hi))
        });
        self.accessor(
            &bytes,
            data.len() / per,
            json::accessor::ComponentType::F32,
            type_,
            b,
            Some(json::buffer::Target::ArrayBuffer),
        )
    }

    /// A float accessor of per-instance data (no buffer view target: not a vertex attribute).
    fn instance_floats(&mut self, data: &[f32], per: usize) -> json::Index<json::Accessor> {
        use json::accessor::Type;
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        let type_ = if per == 3 { Type::Vec3 } else { Type::Vec4 };
        self.accessor(
            &bytes,
            data.len() / per,
            json::accessor::ComponentType::F32,
            type_,
            None,
            None,
        )
    }

    /// The embedded PNG image of `tex`, written once however many textures (and the
    /// environment) use it.
    fn image(&mut self, tex: &Arc<Texture>) -> json::Index<json::Image> {
        if let Some(i) = written(&self.images, tex) {
            return i;
        }
        let view = self.view(&tex.png, None);
        let index = self.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType("image/png".into())),
            name: Some(tex.name.clone()),
            uri: None,
            extensions: None,
            extras: None,
        });
        self.images.push((tex.clone(), index));
        index
    }

    fn texture(&mut self, tex: &Arc<Texture>) -> json::Index<json::Texture> {
        if let Some(i) = written(&self.textures, tex) {
            return i;
        }
        let image = self.image(tex);
        let sampler = *self.sampler.get_or_insert_with(|| {
            self.root.push(json::texture::Sampler {
                mag_filter: Some(Valid(json::texture::MagFilter::Linear)),
                min_filter: Some(Valid(json::texture::MinFilter::LinearMipmapLinear)),
                wrap_s: Valid(json::texture::WrappingMode::Repeat),
                wrap_t: Valid(json::texture::WrappingMode::Repeat),
                ..Default::default()
            })
        });
        let index = self.root.push(json::Texture {
            name: Some(tex.name.clone()),
            sampler: Some(sampler),
            source: image,
            extensions: None,
            extras: None,
        });
        self.textures.push((tex.clone(), index));
        index
    }

    fn material(&mut self, m: &Arc<Material>) -> json::Index<json::Material> {
        if let Some(i) = written(&self.materials, m) {
            return i;
        }
        let base_color_texture = m.texture.as_ref().map(|t| json::texture::Info {
            index: self.texture(t),
            tex_coord: 0,
            extensions: None,
            extras: None,
        });
        let (alpha_mode, alpha_cutoff) = match m.alpha {
            AlphaMode::Opaque => (json::material::AlphaMode::Opaque, None),
            AlphaMode::Mask(c) => (
                json::material::AlphaMode::Mask,
                Some(json::material::AlphaCutoff(c)),
            ),
            AlphaMode::Blend => (json::material::AlphaMode::Blend, None),
        };
        let index = self.root.push(json::Material {
            name: Some(m.name.clone()),
            alpha_mode: Valid(alpha_mode),
            alpha_cutoff,
            double_sided: m.double_sided,
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor(m.base_color),
                base_color_texture,
                metallic_factor: json::material::StrengthFactor(m.metallic),
                roughness_factor: json::material::StrengthFactor(m.roughness),
                ..Default::default()
            },
            ..Default::default()
        });
        self.materials.push((m.clone(), index));
        index
    }

    fn mesh(&mut self, mesh: &Mesh) -> Result<json::Index<json::Mesh>> {
        let (primitive, pge) = self.primitive(mesh)?;
        let extras = if pge.is_empty() {
            None
        } else {
            raw(&json!({ "pge": pge }))?
        };
        Ok(self.root.push(json::Mesh {
            extensions: None,
            extras,
            name: Some(mesh.name.clone()),
            primitives: vec![primitive],
            weights: None,
        }))
    }

    /// One glTF mesh for a group: a primitive per member mesh; the members' `extras.pge`
    /// merged (the first member's keys win).
    fn group_mesh(
        &mut self,
        group: &InstanceGroup,
        meshes: &[std::sync::Arc<Mesh>],
    ) -> Result<json::Index<json::Mesh>> {
        let mut primitives = Vec::with_capacity(group.meshes.len());
        let mut merged = Map::new();
        for &m in &group.meshes {
            let (primitive, pge) = self.primitive(&meshes[m])?;
            primitives.push(primitive);
            for (k, v) in pge {
                merged.entry(k).or_insert(v);
            }
        }
        let extras = if merged.is_empty() {
            None
        } else {
            raw(&json!({ "pge": merged }))?
        };
        Ok(self.root.push(json::Mesh {
            extensions: None,
            extras,
            name: Some(group.name.clone()),
            primitives,
            weights: None,
        }))
    }

    fn primitive(
        &mut self,
        mesh: &Mesh,
    ) -> Result<(json::mesh::Primitive, Map<String, JsonValue>)> {
        use json::accessor::{ComponentType, Type};
        use json::mesh::Semantic;
        mesh.validate()?;
        let mut attributes = std::collections::BTreeMap::new();
        let positions: Vec<f32> = mesh.positions.iter().flat_map(|p| p.to_array()).collect();
        attributes.insert(Valid(Semantic::Positions), self.floats(&positions, 3, true));
        if !mesh.normals.is_empty() {
            let n: Vec<f32> = mesh.normals.iter().flat_map(|p| p.to_array()).collect();
            attributes.insert(Valid(Semantic::Normals), self.floats(&n, 3, false));
        }
        if !mesh.uvs.is_empty() {
            let t: Vec<f32> = mesh.uvs.iter().flat_map(|p| p.to_array()).collect();
            attributes.insert(Valid(Semantic::TexCoords(0)), self.floats(&t, 2, false));
        }
        if !mesh.colors.is_empty() {
            let c: Vec<f32> = mesh.colors.iter().flat_map(|p| p.to_array()).collect();
            attributes.insert(Valid(Semantic::Colors(0)), self.floats(&c, 4, false));
        }
        let index_bytes: Vec<u8> = mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let indices = self.accessor(
            &index_bytes,
            mesh.indices.len(),
            ComponentType::U32,
            Type::Scalar,
            None,
            Some(json::buffer::Target::ElementArrayBuffer),
        );
        let material = self.material(&mesh.material);
        let mut pge = Map::new();
        if let Some(s) = &mesh.skeleton {
            pge.insert("skeleton".into(), skeleton_json(s));
        }
        for (k, v) in &mesh.extras {
            pge.insert(k.clone(), v.clone());
        }
        let mode = match mesh.primitive {
            Primitive::Triangles => json::mesh::Mode::Triangles,
            Primitive::Lines => json::mesh::Mode::Lines,
        };
        let primitive = json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: None,
            indices: Some(indices),
            material: Some(material),
            mode: Valid(mode),
            targets: None,
        };
        Ok((primitive, pge))
    }
}

/// The skeleton as `{parents, positions, radii, orders}` (API.md §7).
fn skeleton_json(s: &Skeleton) -> JsonValue {
    let parents: Vec<i64> = s.parents.iter().map(|p| p.map_or(-1, i64::from)).collect();
    let positions: Vec<f32> = s.positions.iter().flat_map(|p| p.to_array()).collect();
    json!({ "parents": parents, "positions": positions, "radii": s.radii, "orders": s.orders })
}

/// A node placing `mesh` by `m`: translation/rotation/scale when `m` decomposes exactly,
/// the matrix otherwise.
fn node(mesh: json::Index<json::Mesh>, m: &Mat4) -> json::Node {
    let mut node = json::Node {
        mesh: Some(mesh),
        ..Default::default()
    };
    if *m == Mat4::IDENTITY {
        return node;
    }
    let (s, r, t) = m.to_scale_rotation_translation();
    if Mat4::from_scale_rotation_translation(s, r, t).abs_diff_eq(*m, 1e-5) {
        if t != Vec3::ZERO {
            node.translation = Some(t.to_array());
        }
        if r != glam::Quat::IDENTITY {
            node.rotation = Some(json::scene::UnitQuaternion(r.normalize().to_array()));
        }
        if s != Vec3::ONE {
            node.scale = Some(s.to_array());
        }
    } else {
        node.matrix = Some(m.to_cols_array());
    }
    node
}

/// The `.glb` bytes of a model: one buffer, u32 indices, embedded PNG textures, one node per
/// instance, and the root `extras.pge` with generator, seed, params and stats (and, when the
/// model has an environment, `environment = {image = <image index>, mapping =
/// "equirectangular"}`). Groups of instances are written with [`Instancing::Gpu`].
pub fn glb_bytes(model: &Model, meta: &ExportMeta) -> Result<Vec<u8>> {
    glb_bytes_with(model, meta, Instancing::Gpu)
}

/// [`glb_bytes`], writing the model's [`InstanceGroup`]s as `instancing` says: one glTF mesh
/// per group (a primitive per member mesh), then one node per group with
/// `EXT_mesh_gpu_instancing`, or one node per placement.
pub fn glb_bytes_with(model: &Model, meta: &ExportMeta, instancing: Instancing) -> Result<Vec<u8>> {
    model.validate()?;
    let mut b = Builder::new();
    b.instancing = instancing;
    // A scene needs at least one node (and the gltf crate refuses one without), so an empty
    // model is written without a scene: a valid, empty glTF.
    if let Some(scene) = b.scene(model, "pge")? {
        b.root.scene = Some(scene);
    }
    b.finish(model, meta, None)
}

/// The `.glb` bytes of several stages of one growth (`pge run --stages`): one scene per
/// stage, named as given (`step 10`), each with its own meshes (materials and textures
/// shared); the default scene is the last stage. The root `extras.pge` describes the last
/// stage as [`glb_bytes`] does, and adds `stages = [{name, vertices, triangles, nodes,
/// leaves}, ...]`.
pub fn glb_stages_bytes(stages: &[(String, Model)], meta: &ExportMeta) -> Result<Vec<u8>> {
    let Some((_, last)) = stages.last() else {
        return Err(Error::Export("no stage to write".into()));
    };
    let mut b = Builder::new();
    let mut summary = Vec::with_capacity(stages.len());
    for (name, model) in stages {
        model.validate()?;
        if let Some(scene) = b.scene(model, name)? {
            b.root.scene = Some(scene);
        }
        summary.push(json!({
            "name": name,
            "vertices": model.vertex_count(),
            "triangles": model.triangle_count(),
            "nodes": model.stats.nodes,
            "leaves": model.stats.leaves,
        }));
    }
    b.finish(last, meta, Some(JsonValue::Array(summary)))
}

impl Builder {
    fn new() -> Builder {
        let mut b = Builder::default();
        b.root.asset = json::Asset {
            copyright: None,
            extensions: None,
            extras: None,
            generator: Some(GENERATOR.into()),
            min_version: None,
            version: "2.0".into(),
        };
        b
    }

    /// Writes the model's meshes, one node per instance and its instance groups (as
    /// `self.instancing` says), gathered in a scene named `name`; `None` (and nothing written
    /// but the meshes) when the model places nothing.
    fn scene(&mut self, model: &Model, name: &str) -> Result<Option<json::Index<json::Scene>>> {
        // Meshes only groups use are written inside their group's mesh, not on their own.
        let mut meshes = Vec::with_capacity(model.meshes.len());
        for (i, m) in model.meshes.iter().enumerate() {
            let standalone =
                model.groups.is_empty() || model.instances.iter().any(|inst| inst.mesh == i);
            meshes.push(if standalone {
                Some(self.mesh(m)?)
            } else {
                None
            });
        }
        let mut nodes = Vec::with_capacity(model.instances.len());
        for inst in &model.instances {
            let Some(mesh) = meshes[inst.mesh] else {
                return Err(Error::Export("an instance's mesh was not written".into()));
            };
            let n = node(mesh, &inst.transform);
            nodes.push(self.root.push(n));
        }
        for group in &model.groups {
            if group.transforms.is_empty() {
                continue;
            }
            let mesh = self.group_mesh(group, &model.meshes)?;
            match self.instancing {
                Instancing::Gpu => {
                    let mut t = Vec::with_capacity(group.transforms.len() * 3);
                    let mut r = Vec::with_capacity(group.transforms.len() * 4);
                    let mut s = Vec::with_capacity(group.transforms.len() * 3);
                    for x in &group.transforms {
                        t.extend_from_slice(&x.translation);
                        r.extend_from_slice(&x.rotation);
                        s.extend_from_slice(&[x.scale; 3]);
                    }
                    let accessors = [
                        self.instance_floats(&t, 3),
                        self.instance_floats(&r, 4),
                        self.instance_floats(&s, 3),
                    ];
                    let index = self.root.push(json::Node {
                        mesh: Some(mesh),
                        name: Some(group.name.clone()),
                        ..Default::default()
                    });
                    self.gpu_nodes
                        .push((index.value(), accessors.map(|a| a.value())));
                    nodes.push(index);
                }
                Instancing::Nodes => {
                    for x in &group.transforms {
                        let mut n = json::Node {
                            mesh: Some(mesh),
                            ..Default::default()
                        };
                        if x.translation != [0.0; 3] {
                            n.translation = Some(x.translation);
                        }
                        if x.rotation != [0.0, 0.0, 0.0, 1.0] {
                            n.rotation = Some(json::scene::UnitQuaternion(x.rotation));
                        }
                        if x.scale != 1.0 {
                            n.scale = Some([x.scale; 3]);
                        }
                        nodes.push(self.root.push(n));
                    }
                }
            }
        }
        if nodes.is_empty() {
            return Ok(None);
        }
        Ok(Some(self.root.push(json::Scene {
            extensions: None,
            extras: None,
            name: Some(name.into()),
            nodes,
        })))
    }

    /// The root extras (describing `model`), the buffer and the GLB container.
    fn finish(
        self,
        model: &Model,
        meta: &ExportMeta,
        stages: Option<JsonValue>,
    ) -> Result<Vec<u8>> {
        let mut b = self;
        let params: Map<String, JsonValue> = meta.params.iter().cloned().collect();
        let mut pge = Map::new();
        pge.insert("generator".into(), GENERATOR.into());
        pge.insert("seed".into(), meta.seed.into());
        pge.insert("params".into(), JsonValue::Object(params));
        pge.insert(
            "stats".into(),
            json!({
                "vertices": model.vertex_count(),
                "triangles": model.triangle_count(),
                "nodes": model.stats.nodes,
                "leaves": model.stats.leaves,
                "modules": model.stats.modules,
            }),
        );
        if let Some(env) = &model.environment {
            let image = b.image(env).value();
            pge.insert(
                "environment".into(),
                json!({ "image": image, "mapping": "equirectangular" }),
            );
        }
        for (k, v) in &model.extras {
            pge.entry(k.clone()).or_insert_with(|| v.clone());
        }
        if let Some(stages) = stages {
            pge.insert("stages".into(), stages);
        }
        b.root.extras = raw(&json!({ "pge": pge }))?;
        while !b.bin.len().is_multiple_of(4) {
            b.bin.push(0);
        }
        if !b.bin.is_empty() {
            b.root.push(json::Buffer {
                byte_length: USize64(b.bin.len() as u64),
                name: None,
                uri: None,
                extensions: None,
                extras: None,
            });
        }
        let mut text = if b.gpu_nodes.is_empty() {
            b.root.to_vec().map_err(|e| Error::Export(e.to_string()))?
        } else {
            with_gpu_instancing(&b.root, &b.gpu_nodes)?
        };
        while !text.len().is_multiple_of(4) {
            text.push(b' ');
        }
        glb_container(&text, &b.bin, GLB_LIMIT)
    }
}

/// The largest GLB file: its header stores lengths as 32-bit numbers.
pub const GLB_LIMIT: u64 = u32::MAX as u64;

/// The GLB container around a glTF JSON text (padded to 4 bytes) and a binary chunk (empty:
/// none): an [`Error::Export`] naming the limit when the file would pass `limit` bytes
/// ([`GLB_LIMIT`] when exporting; a smaller one in tests), never a truncated length.
pub fn glb_container(text: &[u8], bin: &[u8], limit: u64) -> Result<Vec<u8>> {
    let total = 12
        + 8
        + text.len() as u64
        + if bin.is_empty() {
            0
        } else {
            8 + bin.len() as u64
        };
    let limit = limit.min(GLB_LIMIT);
    if total > limit {
        return Err(Error::Export(format!(
            "the model needs a glb of {total} bytes, past the limit of {limit} bytes (a glb \
             holds at most 4 GiB): lower the detail or split the model"
        )));
    }
    let len32 =
        |n: u64| u32::try_from(n).map_err(|_| Error::Export(format!("a glb length of {n} bytes")));
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&len32(total)?.to_le_bytes());
    out.extend_from_slice(&len32(text.len() as u64)?.to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(text);
    if !bin.is_empty() {
        out.extend_from_slice(&len32(bin.len() as u64)?.to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(bin);
    }
    Ok(out)
}

/// The root's JSON with `EXT_mesh_gpu_instancing` on the given nodes (index, [TRANSLATION,
/// ROTATION, SCALE] accessors) and the extension declared in `extensionsUsed` (gltf-json
/// has no field for it without its `extensions` feature).
fn with_gpu_instancing(root: &json::Root, nodes: &[(usize, [usize; 3])]) -> Result<Vec<u8>> {
    let export = |e: serde_json::Error| Error::Export(e.to_string());
    let mut value = serde_json::to_value(root).map_err(export)?;
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
    if let Some(root) = value.as_object_mut() {
        root.insert("extensionsUsed".into(), json!([GPU_INSTANCING]));
    }
    serde_json::to_vec(&value).map_err(export)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Material, Mesh};
    use glam::{Quat, Vec2};

    pub(super) fn textured_model() -> Model {
        let mut mesh =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
        mesh.uvs = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
        let tex = Texture::from_rgba("leaf", 2, 2, &[255; 16]).expect("png");
        mesh.material = Arc::new(Material {
            texture: Some(Arc::new(tex)),
            alpha: AlphaMode::Mask(0.5),
            double_sided: true,
            ..Material::default()
        });
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.1, 0);
        s.push(Vec3::Y, Some(r), 0.05, 0);
        mesh.skeleton = Some(Arc::new(s));
        let mesh = Arc::new(mesh);
        let mut model = Model::new();
        model.add_mesh(mesh.clone(), Mat4::IDENTITY);
        model.add_mesh(
            mesh,
            Mat4::from_rotation_translation(Quat::from_rotation_y(1.0), Vec3::X),
        );
        model
    }

    #[test]
    fn glb_parses_back_with_the_gltf_crate() {
        let model = textured_model();
        let bytes = glb_bytes(
            &model,
            &ExportMeta {
                seed: 7,
                params: vec![("h".into(), json!(2))],
            },
        )
        .expect("exports");
        let gltf = gltf::Gltf::from_slice(&bytes).expect("parses");
        assert_eq!(gltf.meshes().count(), 1);
        assert_eq!(gltf.nodes().count(), 2);
        assert_eq!(gltf.images().count(), 1);
        let prim = gltf
            .meshes()
            .next()
            .and_then(|m| m.primitives().next())
            .expect("primitive");
        assert_eq!(
            prim.indices().map(|a| a.data_type()),
            Some(gltf::accessor::DataType::U32)
        );
        assert_eq!(
            prim.material().alpha_mode(),
            gltf::material::AlphaMode::Mask
        );
        let extras: JsonValue = serde_json::from_str(
            gltf.document
                .as_json()
                .extras
                .as_ref()
                .expect("extras")
                .get(),
        )
        .expect("json");
        assert_eq!(extras["pge"]["seed"], 7);
        assert_eq!(extras["pge"]["params"]["h"], 2);
        assert_eq!(extras["pge"]["stats"]["triangles"], 2);
        let mesh_extras: JsonValue = serde_json::from_str(
            gltf.meshes()
                .next()
                .expect("mesh")
                .extras()
                .as_ref()
                .expect("extras")
                .get(),
        )
        .expect("json");
        assert_eq!(mesh_extras["pge"]["skeleton"]["parents"], json!([-1, 0]));
    }

    #[test]
    fn export_is_byte_identical() {
        let a = glb_bytes(&textured_model(), &ExportMeta::default()).expect("exports");
        let b = glb_bytes(&textured_model(), &ExportMeta::default()).expect("exports");
        assert_eq!(a, b);
        assert_eq!(a.len() % 4, 0);
    }
}

#[cfg(test)]
mod environment_tests {
    use super::*;
    use glam::Vec2;

    #[test]
    fn the_environment_is_an_embedded_image_named_by_the_root_extras() {
        let mut rgba = Vec::new();
        for _ in 0..2 {
            rgba.extend_from_slice(&[40, 90, 220, 255, 40, 90, 220, 255]);
        }
        for _ in 0..2 {
            rgba.extend_from_slice(&[90, 70, 40, 255, 90, 70, 40, 255]);
        }
        let sky = Arc::new(Texture::from_rgba("sky", 4, 2, &rgba).expect("png"));
        let mut mesh =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
        mesh.uvs = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
        let mut model = Model::from_mesh(mesh);
        model.environment = Some(sky.clone());
        let bytes = glb_bytes(&model, &ExportMeta::default()).expect("exports");
        let gltf = gltf::Gltf::from_slice(&bytes).expect("parses");
        let extras: JsonValue = serde_json::from_str(
            gltf.document
                .as_json()
                .extras
                .as_ref()
                .expect("extras")
                .get(),
        )
        .expect("json");
        let env = &extras["pge"]["environment"];
        assert_eq!(env["mapping"], "equirectangular");
        let index = env["image"].as_u64().expect("an image index") as usize;
        let image = gltf.images().nth(index).expect("the image exists");
        let gltf::image::Source::View { view, mime_type } = image.source() else {
            panic!("embedded, not a uri");
        };
        assert_eq!(mime_type, "image/png");
        let blob = gltf.blob.as_ref().expect("binary chunk");
        let png = &blob[view.offset()..view.offset() + view.length()];
        assert_eq!(png, sky.png.as_slice());
        let decoded = image::load_from_memory(png).expect("png").to_rgba8();
        assert_eq!(decoded.dimensions(), (4, 2));
        assert_eq!(decoded.as_raw(), &rgba);

        // The same picture as a material texture is stored once.
        let mut textured = Model::new();
        let mut mesh =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
        mesh.uvs = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
        mesh.material = Arc::new(Material {
            texture: Some(Arc::new((*sky).clone())),
            ..Material::default()
        });
        textured.add_mesh(mesh, Mat4::IDENTITY);
        textured.environment = Some(sky);
        let bytes = glb_bytes(&textured, &ExportMeta::default()).expect("exports");
        let gltf = gltf::Gltf::from_slice(&bytes).expect("parses");
        assert_eq!(gltf.images().count(), 1);
        assert_eq!(gltf.textures().count(), 1);
    }

    #[test]
    fn without_an_environment_nothing_is_written() {
        let bytes = glb_bytes(&Model::new(), &ExportMeta::default()).expect("exports");
        let text = String::from_utf8_lossy(&bytes);
        assert!(!text.contains("environment"));
    }
}

#[cfg(test)]
mod empty_tests {
    use super::*;

    #[test]
    fn stages_are_named_scenes_sharing_their_textures() {
        let one = super::tests::textured_model();
        let mut two = super::tests::textured_model();
        two.add_model(
            &super::tests::textured_model(),
            Mat4::from_translation(Vec3::X),
        );
        let stages = vec![("step 1".to_string(), one), ("step 2".to_string(), two)];
        let bytes = glb_stages_bytes(&stages, &ExportMeta::default()).expect("glb");
        let (doc, _, _) = gltf::import_slice(&bytes).expect("parses");
        let names: Vec<_> = doc.scenes().map(|s| s.name().map(str::to_string)).collect();
        assert_eq!(names, [Some("step 1".into()), Some("step 2".into())]);
        assert_eq!(doc.default_scene().map(|s| s.index()), Some(1));
        let nodes: Vec<usize> = doc.scenes().map(|s| s.nodes().count()).collect();
        assert_eq!(nodes[1], 2 * nodes[0]);
        assert_eq!(doc.images().count(), 1, "one texture for every stage");
        let extras = doc
            .as_json()
            .extras
            .as_ref()
            .expect("extras")
            .get()
            .to_string();
        assert!(
            extras.contains("\"stages\":[{\"name\":\"step 1\""),
            "{extras}"
        );
        assert!(glb_stages_bytes(&[], &ExportMeta::default()).is_err());
    }

    #[test]
    fn an_empty_model_is_a_valid_glb() {
        let bytes = glb_bytes(&Model::new(), &ExportMeta::default()).expect("exports");
        let gltf = gltf::Gltf::from_slice(&bytes).expect("parses");
        assert_eq!(gltf.nodes().count(), 0);
    }
}
