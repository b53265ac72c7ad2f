//! glTF 2.0 binary export (gltf-json), deterministic to the byte.
//!
//! One [`Builder`] writes every file: a single model, the stages of a growth, a tile that
//! refers to shared variants and the shared variants themselves ([`shared`]), each by the
//! same steps: buffer views and accessors ([`buffers`], placed in a [`Layout`]), materials,
//! textures and images ([`materials`]), meshes ([`meshes`]), nodes and scenes ([`nodes`]),
//! extras ([`extras`], [`lod_extras`], [`root_extras`]) and extensions ([`extensions`]),
//! then the container ([`container`]), written in one pass ([`write`]).

use std::sync::Arc;

use gltf_json as json;
use json::validation::USize64;
use serde_json::{Value as JsonValue, json};

use crate::geometry::{DiffuseTransmission, Material, Mesh, Model, Texture};
use crate::{Error, Result};

mod buffers;
mod container;
mod extensions;
mod extras;
mod layout;
pub(super) mod lod_extras;
mod materials;
mod meshes;
mod nodes;
mod root_extras;
pub(super) mod shared;
mod sky;
mod write;

pub use container::{GLB_LIMIT, GlbFile, glb_container};
pub use extensions::DIFFUSE_TRANSMISSION;
use extensions::with_extensions;
pub use extras::Prepared;
use extras::{Extra, JsonText, MeshExtras};
use layout::{Attribute, Data, Layout, vec3_bounds};
pub use lod_extras::lod_from_json;
use lod_extras::{group_leaves_extras, placement_leaves_extras};
use root_extras::RootExtras;
pub use sky::UNLIT;
use sky::{SKY_MIN_RADIUS, SKY_RINGS, SKY_SEGMENTS, sky_sphere};
pub use write::{write_glb_checked, write_glb_with};

#[cfg(test)]
mod tests;

#[cfg(test)]
mod environment_tests;

#[cfg(test)]
mod stage_tests;

#[cfg(test)]
mod lod_tests;

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
    /// The deadline the build keeps to, checked per mesh and every [`CHECK_EVERY`] nodes.
    limit: super::ExportLimit,
}

/// Placements written between two checks of the deadline.
const CHECK_EVERY: usize = 1 << 16;

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
