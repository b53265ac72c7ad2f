//! glTF 2.0 binary export (gltf-json), deterministic to the byte.

use std::sync::Arc;

use glam::{Mat4, Vec3};
use gltf_json as json;
use json::validation::Checked::Valid;
use json::validation::USize64;
use serde_json::{Value as JsonValue, json};

use crate::geometry::{
    AlphaMode, DiffuseTransmission, InstanceGroup, Material, Mesh, Model, Primitive, Texture,
};
use crate::{Error, Result};

pub use super::glb_container::{GLB_LIMIT, GlbFile, glb_container};
use super::glb_extras::{Extra, JsonText, MeshExtras, Prepared};
use super::glb_layout::{Attribute, Data, Layout, vec3_bounds};
pub use super::glb_sky::UNLIT;
use super::glb_sky::{SKY_MIN_RADIUS, SKY_RINGS, SKY_SEGMENTS, sky_sphere};

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
    /// The binary chunk's views, placed as the JSON refers to them, written at the end.
    layout: Layout,
    materials: Vec<(Arc<Material>, json::Index<json::Material>)>,
    textures: Vec<(Arc<Texture>, json::Index<json::Texture>)>,
    images: Vec<(Arc<Texture>, json::Index<json::Image>)>,
    sampler: Option<json::Index<json::texture::Sampler>>,
    /// How instance groups are written.
    instancing: Instancing,
    /// Nodes that need `EXT_mesh_gpu_instancing`, with their TRANSLATION/ROTATION/SCALE
    /// accessors.
    gpu_nodes: Vec<(usize, [usize; 3])>,
    /// The sky dome's mesh, once written (models with an environment).
    sky: Option<json::Index<json::Mesh>>,
    /// Materials that need `KHR_materials_unlit` (the sky's).
    unlit: Vec<usize>,
    /// Materials with `KHR_materials_diffuse_transmission` (leaves), and what they let
    /// through.
    transmissive: Vec<(usize, DiffuseTransmission)>,
    /// The shared variants a tile's instance groups refer to (`glb_bytes_shared`).
    shared: Option<shared::Shared>,
    /// The meshes whose skeletons the JSON text marks, formatted when it is written (see
    /// [`JsonText`]).
    skeletons: Vec<Arc<Mesh>>,
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
    /// A buffer view of `data` at the next 4-byte boundary of the buffer, placed now and
    /// written when the file is (see [`Layout`]).
    fn view(
        &mut self,
        data: Data,
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        let (offset, len) = self.layout.place(data);
        self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64(len as u64),
            byte_offset: Some(USize64(offset as u64)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: None,
        })
    }

    /// An accessor of the `count` elements of `data`, in a view of its own.
    fn accessor(
        &mut self,
        data: Data,
        count: usize,
        component: json::accessor::ComponentType,
        type_: json::accessor::Type,
        bounds: Option<(JsonValue, JsonValue)>,
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::Accessor> {
        let view = self.view(data, target);
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

    /// A VEC3 float vertex attribute of `mesh` (positions or normals), with its `min`/`max`
    /// when `bounds`.
    fn vec3s(
        &mut self,
        mesh: &Arc<Mesh>,
        attribute: Attribute,
        bounds: bool,
    ) -> json::Index<json::Accessor> {
        let data = match attribute {
            Attribute::Normals => &mesh.normals,
            _ => &mesh.positions,
        };
        let b = bounds.then(|| {
            let (lo, hi) = vec3_bounds(data);
            (json!(lo.to_vec()), json!(hi.to_vec()))
        });
        self.accessor(
            Data::Mesh(mesh.clone(), attribute),
            data.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec3,
            b,
            Some(json::buffer::Target::ArrayBuffer),
        )
    }

    /// A VEC2 float vertex attribute (texture coordinates).
    fn vec2s(&mut self, mesh: &Arc<Mesh>) -> json::Index<json::Accessor> {
        self.accessor(
            Data::Mesh(mesh.clone(), Attribute::Uvs),
            mesh.uvs.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec2,
            None,
            Some(json::buffer::Target::ArrayBuffer),
        )
    }

    /// A `COLOR_0` accessor: linear RGBA as normalized unsigned bytes (4 bytes a vertex
    /// instead of 16), rounded to the nearest of the 256 steps.
    fn colors(&mut self, mesh: &Arc<Mesh>) -> json::Index<json::Accessor> {
        let index = self.accessor(
            Data::Mesh(mesh.clone(), Attribute::Colors),
            mesh.colors.len(),
            json::accessor::ComponentType::U8,
            json::accessor::Type::Vec4,
            None,
            Some(json::buffer::Target::ArrayBuffer),
        );
        if let Some(accessor) = self.root.accessors.get_mut(index.value()) {
            accessor.normalized = true;
        }
        index
    }

    /// A float accessor of per-instance data (no buffer view target: not a vertex attribute).
    fn instance_floats(&mut self, data: Vec<f32>, per: usize) -> json::Index<json::Accessor> {
        use json::accessor::Type;
        let type_ = if per == 3 { Type::Vec3 } else { Type::Vec4 };
        let count = data.len() / per;
        self.accessor(
            Data::Floats(data),
            count,
            json::accessor::ComponentType::F32,
            type_,
            None,
            None,
        )
    }

    /// The embedded image of `tex` (PNG or JPEG), written once however many textures (and the
    /// environment) use it.
    fn image(&mut self, tex: &Arc<Texture>) -> json::Index<json::Image> {
        if let Some(i) = written(&self.images, tex) {
            return i;
        }
        let view = self.view(Data::Image(tex.clone()), None);
        let index = self.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType(tex.mime_type().into())),
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
        let normal_texture = m
            .normal_texture
            .as_ref()
            .map(|t| json::material::NormalTexture {
                index: self.texture(t),
                scale: 1.0,
                tex_coord: 0,
                extensions: None,
                extras: None,
            });
        let metallic_roughness_texture =
            m.metallic_roughness_texture
                .as_ref()
                .map(|t| json::texture::Info {
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
                metallic_roughness_texture,
                ..Default::default()
            },
            normal_texture,
            ..Default::default()
        });
        if let Some(t) = m.transmission {
            self.transmissive.push((index.value(), t));
        }
        self.materials.push((m.clone(), index));
        index
    }

    fn mesh(&mut self, mesh: &Arc<Mesh>) -> Result<json::Index<json::Mesh>> {
        let (primitive, pge) = self.primitive(mesh)?;
        let extras = if pge.0.is_empty() {
            None
        } else {
            pge.extras(&mut self.skeletons)?
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
        let mut merged = MeshExtras::default();
        for &m in &group.meshes {
            let mesh = meshes
                .get(m)
                .ok_or_else(|| Error::Export("a group's mesh does not exist".into()))?;
            let (primitive, pge) = self.primitive(mesh)?;
            primitives.push(primitive);
            for (k, v) in pge.0 {
                if !merged.0.iter().any(|(key, _)| *key == k) {
                    merged.0.push((k, v));
                }
            }
        }
        let extras = if merged.0.is_empty() {
            None
        } else {
            merged.extras(&mut self.skeletons)?
        };
        Ok(self.root.push(json::Mesh {
            extensions: None,
            extras,
            name: Some(group.name.clone()),
            primitives,
            weights: None,
        }))
    }

    fn primitive<'m>(
        &mut self,
        mesh: &'m Arc<Mesh>,
    ) -> Result<(json::mesh::Primitive, MeshExtras<'m>)> {
        use json::accessor::{ComponentType, Type};
        use json::mesh::Semantic;
        // Reads every attribute by its own length: nothing here fails on an invalid mesh
        // (`write_glb_with` checks the model while it builds and writes).
        let mut attributes = std::collections::BTreeMap::new();
        attributes.insert(
            Valid(Semantic::Positions),
            self.vec3s(mesh, Attribute::Positions, true),
        );
        if !mesh.normals.is_empty() {
            attributes.insert(
                Valid(Semantic::Normals),
                self.vec3s(mesh, Attribute::Normals, false),
            );
        }
        // Texture coordinates only where a texture reads them.
        let m = &mesh.material;
        let textured = [&m.texture, &m.normal_texture, &m.metallic_roughness_texture];
        if !mesh.uvs.is_empty() && textured.iter().any(|t| t.is_some()) {
            attributes.insert(Valid(Semantic::TexCoords(0)), self.vec2s(mesh));
        }
        if !mesh.colors.is_empty() {
            attributes.insert(Valid(Semantic::Colors(0)), self.colors(mesh));
        }
        // MikkTSpace tangents where a normal map reads them.
        if let Some(t) = mesh.tangents() {
            let data = Data::Floats(t.iter().flat_map(|t| t.to_array()).collect());
            let vertex = Some(json::buffer::Target::ArrayBuffer);
            let index = self.accessor(data, t.len(), ComponentType::F32, Type::Vec4, None, vertex);
            attributes.insert(Valid(Semantic::Tangents), index);
        }
        let indices = self.accessor(
            Data::Mesh(mesh.clone(), Attribute::Indices),
            mesh.indices.len(),
            ComponentType::U32,
            Type::Scalar,
            None,
            Some(json::buffer::Target::ElementArrayBuffer),
        );
        let material = self.material(&mesh.material);
        // The skeleton first, the mesh's own extras after it (one named `skeleton` replaces
        // it in place), as a map of them would keep them.
        let mut pge = MeshExtras::default();
        if mesh.skeleton.is_some() {
            pge.0.push(("skeleton", Extra::Skeleton(mesh)));
        }
        for (k, v) in &mesh.extras {
            match pge.0.iter_mut().find(|(key, _)| key == k) {
                Some(entry) => entry.1 = Extra::Value(v),
                None => pge.0.push((k, Extra::Value(v))),
            }
        }
        // The levels of detail last (in the place of an own extra of that name).
        if let Some(lod) = &mesh.lod {
            match pge.0.iter_mut().find(|(key, _)| *key == "lod") {
                Some(entry) => entry.1 = Extra::Lod(lod),
                None => pge.0.push(("lod", Extra::Lod(lod))),
            }
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
/// instance, one scene (an empty model's holds one empty node), and on the root and the
/// scene `extras.pge` with generator, seed, params and stats (and, when the model has an
/// environment, `environment = {image = <image index>, mapping = "equirectangular"}`).
/// Groups of instances are written with [`Instancing::Gpu`].
pub fn glb_bytes(model: &Model, meta: &ExportMeta) -> Result<Vec<u8>> {
    glb_bytes_with(model, meta, Instancing::Gpu)
}

/// [`glb_bytes`], writing the model's [`InstanceGroup`]s as `instancing` says: one glTF mesh
/// per group (a primitive per member mesh), then one node per group with
/// `EXT_mesh_gpu_instancing`, or one node per placement.
pub fn glb_bytes_with(model: &Model, meta: &ExportMeta, instancing: Instancing) -> Result<Vec<u8>> {
    glb_file_with(model, meta, instancing)?.to_vec()
}

/// The file [`glb_bytes_with`] gives, not yet assembled: [`GlbFile::write_to`] writes it to a
/// file from the model's own memory, with no buffer of the file's size.
pub fn glb_file_with(model: &Model, meta: &ExportMeta, instancing: Instancing) -> Result<GlbFile> {
    let prepared = Prepared::default();
    write_glb_with(
        model,
        &prepared,
        meta,
        instancing,
        || Ok(()),
        |(), file| Ok(file),
    )
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
        b.root.scene = Some(b.scene(model, name)?);
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
    /// `self.instancing` says), gathered in a scene named `name`. A model that places nothing
    /// gets a scene holding one empty node named `empty`: clients expect a scene (three.js's
    /// `gltf.scene`), and a glTF scene lists at least one node.
    fn scene(&mut self, model: &Model, name: &str) -> Result<json::Index<json::Scene>> {
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
            let Some(&Some(mesh)) = meshes.get(inst.mesh) else {
                return Err(Error::Export("an instance's mesh was not written".into()));
            };
            let n = node(mesh, &inst.transform);
            nodes.push(self.root.push(n));
        }
        for group in &model.groups {
            if group.transforms.is_empty() {
                continue;
            }
            let mesh = match self.shared_mesh(group)? {
                Some(mesh) => mesh,
                None => self.group_mesh(group, &model.meshes)?,
            };
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
                        self.instance_floats(t, 3),
                        self.instance_floats(r, 4),
                        self.instance_floats(s, 3),
                    ];
                    let index = self.root.push(json::Node {
                        mesh: Some(mesh),
                        name: Some(group.name.clone()),
                        extras: group_leaves_extras(group)?,
                        ..Default::default()
                    });
                    self.gpu_nodes
                        .push((index.value(), accessors.map(|a| a.value())));
                    nodes.push(index);
                }
                Instancing::Nodes => {
                    for (k, x) in group.transforms.iter().enumerate() {
                        let mut n = json::Node {
                            mesh: Some(mesh),
                            extras: placement_leaves_extras(group, k)?,
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
            nodes.push(self.root.push(json::Node {
                name: Some("empty".into()),
                ..Default::default()
            }));
        }
        if let Some(env) = &model.environment {
            let dome = self.sky_dome(env)?;
            // Around the model, ten times as far as its farthest corner (50 m at least).
            let (lo, hi) = model.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
            let radius = (10.0 * (hi - lo).length() / 2.0).max(SKY_MIN_RADIUS);
            let centre = (lo + hi) / 2.0;
            let mut n = node(
                dome,
                &Mat4::from_scale_rotation_translation(
                    Vec3::splat(radius),
                    glam::Quat::IDENTITY,
                    centre,
                ),
            );
            n.name = Some("sky".into());
            nodes.push(self.root.push(n));
        }
        Ok(self.root.push(json::Scene {
            extensions: None,
            extras: None,
            name: Some(name.into()),
            nodes,
        }))
    }

    /// The sky dome's mesh (written once): a unit sphere seen from inside, its texture the
    /// environment image mapped as the preview reads it (row 0 straight up, the middle
    /// column along -Z, a quarter to its right +X), with an unlit material.
    fn sky_dome(&mut self, env: &Arc<Texture>) -> Result<json::Index<json::Mesh>> {
        if let Some(mesh) = self.sky {
            return Ok(mesh);
        }
        let mut mesh = sky_sphere(SKY_SEGMENTS, SKY_RINGS);
        mesh.material = Arc::new(Material {
            name: "sky".into(),
            base_color: [1.0; 4],
            texture: Some(env.clone()),
            metallic: 0.0,
            roughness: 1.0,
            ..Material::default()
        });
        let mesh = Arc::new(mesh);
        let index = self.mesh(&mesh)?;
        if let Some(material) = written(&self.materials, &mesh.material) {
            self.unlit.push(material.value());
        }
        self.sky = Some(index);
        Ok(index)
    }

    /// The file's bytes ([`Builder::file`] in one buffer).
    fn finish(
        self,
        model: &Model,
        meta: &ExportMeta,
        stages: Option<JsonValue>,
    ) -> Result<Vec<u8>> {
        self.file(model, &Prepared::default(), meta, stages)?
            .to_vec()
    }

    /// The root extras (describing `model`), the buffer and the GLB container, the
    /// skeletons' texts taken from `prepared` where it has them.
    fn file(
        self,
        model: &Model,
        prepared: &Prepared,
        meta: &ExportMeta,
        stages: Option<JsonValue>,
    ) -> Result<GlbFile> {
        let mut b = self;
        // What the instances of shared variants draw (a tile that refers to them).
        let [sv, st, sn, sl] = b.shared_counts(model);
        let environment = model.environment.as_ref().map(|env| b.image(env).value());
        // Blender keeps a scene's extras but drops the root's, three.js shows a scene's as
        // `userData`: every scene carries the run's extras too.
        let extras = RootExtras {
            meta,
            stats: [
                model.vertex_count() as u64 + sv,
                model.triangle_count() as u64 + st,
                model.stats.nodes + sn,
                model.stats.leaves + sl,
                model.stats.modules,
            ],
            environment,
            forest: model.forest.as_ref(),
            extras: &model.extras,
            stages: stages.as_ref(),
        }
        .extras()?;
        for scene in &mut b.root.scenes {
            scene.extras.clone_from(&extras);
        }
        b.root.extras = extras;
        let mut bin_len = b.layout.padded_len();
        if bin_len == 0 && b.shared.is_some() {
            // Buffer 0 must exist before the shared one (buffer 1).
            bin_len = 4;
        }
        if bin_len > 0 {
            b.root.push(json::Buffer {
                byte_length: USize64(bin_len as u64),
                name: None,
                uri: None,
                extensions: None,
                extras: None,
            });
        }
        b.push_shared_buffer();
        let no_extensions =
            b.gpu_nodes.is_empty() && b.unlit.is_empty() && b.transmissive.is_empty();
        let text = if no_extensions {
            b.root.to_vec().map_err(|e| Error::Export(e.to_string()))?
        } else {
            with_extensions(&mut b.root, &b.gpu_nodes, &b.unlit, &b.transmissive)?
        };
        let json = JsonText::new(text, &b.skeletons, prepared)?;
        GlbFile::new(json, b.layout, bin_len, GLB_LIMIT)
    }
}

#[path = "glb_extensions.rs"]
mod extensions;
#[path = "glb_lod_extras.rs"]
pub(super) mod lod_extras;
#[path = "glb_root_extras.rs"]
mod root_extras;
#[path = "glb_write.rs"]
mod write;
pub use extensions::DIFFUSE_TRANSMISSION;
use extensions::with_extensions;
pub use lod_extras::lod_from_json;
use lod_extras::{group_leaves_extras, placement_leaves_extras};
use root_extras::RootExtras;
pub use write::write_glb_with;

#[path = "glb_shared.rs"]
pub(super) mod shared;

#[cfg(test)]
#[path = "glb_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "glb_environment_tests.rs"]
mod environment_tests;

#[cfg(test)]
#[path = "glb_stage_tests.rs"]
mod empty_tests;

#[cfg(test)]
#[path = "glb_lod_tests.rs"]
mod lod_tests;
