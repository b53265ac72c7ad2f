//! Universal Scene Description export: a text layer (`.usda`) with its textures beside it in
//! a folder, or both in one `.usdz` package.
//!
//! The layer holds one root `Xform` (the default prim, `Y` up, one metre a unit) with the
//! run's metadata as `customData`; a `Materials` scope of `UsdPreviewSurface` materials
//! reading the textures with `UsdUVTexture`; each placed mesh as a `Mesh` (lines as linear
//! `BasisCurves`) with its skeleton, levels of detail and extras as `customData`; each
//! forest species as a `PointInstancer` with one prototype per variant. Growth stages are
//! the variants of a variant set `stage` on the root.

mod mesh;
mod text;
mod usdz;

use std::sync::Arc;

use glam::Mat4;
use rayon::prelude::*;
use serde_json::{Value as JsonValue, json};

use super::ExportMeta;
use super::glb::GENERATOR;
use crate::geometry::{
    AlphaMode, InstanceGroup, Material, Mesh, MeshLod, Model, Primitive, Skeleton, Texture,
};
use crate::{Error, Result};
use mesh::mesh_text;
use text::{Names, Text, identifier, quote};

pub use usdz::usdz_bytes;

/// The name of the root prim, the layer's default prim.
pub const USD_ROOT: &str = "PGE";

/// A USD export: the layer's text and the textures it refers to, each with its path relative
/// to the layer (`FOLDER/N_NAME.png` or `.jpg`).
#[derive(Clone, Debug, Default)]
pub struct UsdFiles {
    /// The `.usda` text.
    pub layer: String,
    /// The textures: path relative to the layer, image.
    pub textures: Vec<(String, Arc<Texture>)>,
}

/// The USD layer of `model` with `meta`; textures are referred to in the folder `folder`
/// beside the layer (the layer's name without its extension).
pub fn usd_files(model: &Model, meta: &ExportMeta, folder: &str) -> Result<UsdFiles> {
    model.validate()?;
    let mut w = Writer::new(std::slice::from_ref(model), folder);
    w.header();
    w.root_open(model, meta, None);
    w.materials();
    w.body(model);
    w.text.close("}");
    Ok(w.finish())
}

/// The USD layer of several stages of one growth (`pge run --stages`): the root's variant
/// set `stage` has one variant per stage (named as given, made an identifier), the last one
/// selected; the materials are shared. The root's `customData` describes the last stage, with
/// `stages`: each stage's name, vertices, triangles, nodes and leaves.
pub fn usd_stages_files(
    stages: &[(String, Model)],
    meta: &ExportMeta,
    folder: &str,
) -> Result<UsdFiles> {
    let Some((_, last)) = stages.last() else {
        return Err(Error::Export("no stage to write".into()));
    };
    let models: Vec<Model> = stages.iter().map(|(_, m)| m.clone()).collect();
    let mut names = Names::default();
    let mut variants = Vec::with_capacity(stages.len());
    let mut summary = Vec::with_capacity(stages.len());
    for (name, model) in stages {
        model.validate()?;
        variants.push(names.unique(name));
        summary.push(json!({
            "name": name,
            "vertices": model.vertex_count(),
            "triangles": model.triangle_count(),
            "nodes": model.stats.nodes,
            "leaves": model.stats.leaves,
        }));
    }
    let mut w = Writer::new(&models, folder);
    w.header();
    let selected = variants.last().cloned();
    w.root_open(
        last,
        meta,
        Some((JsonValue::Array(summary), selected.unwrap_or_default())),
    );
    w.materials();
    w.text.put("variantSet \"stage\" = {");
    w.text.depth_in();
    for (variant, model) in variants.iter().zip(&models) {
        let mut line = String::new();
        quote(&mut line, variant);
        line.push_str(" {");
        w.text.put(&line);
        w.text.depth_in();
        w.body(model);
        w.text.close("}");
    }
    w.text.close("}");
    w.text.close("}");
    Ok(w.finish())
}

/// The layer being written: its text, the materials and textures of the models.
struct Writer<'m> {
    /// The text after the last piece.
    text: Text,
    /// The layer so far: text, and meshes formatted in parallel when the layer is finished.
    pieces: Vec<Piece<'m>>,
    folder: String,
    /// Distinct materials with their prim names.
    materials: Vec<(Arc<Material>, String)>,
    /// Distinct textures with their paths.
    textures: Vec<(Arc<Texture>, String)>,
}

/// A piece of the layer: text written in order, or a mesh prim to format.
enum Piece<'m> {
    Text(String),
    Mesh(MeshJob<'m>),
    Placements(Vec<&'m InstanceGroup>, Placements),
}

/// An array of a point instancer.
#[derive(Clone, Copy)]
enum Placements {
    /// `quath` rotations, real part first.
    Orientations,
    Positions,
    /// The uniform scale on each axis.
    Scales,
}

/// The text of a point instancer's array: `[(...), ...]`.
fn placements_text(groups: &[&InstanceGroup], array: Placements) -> String {
    let count: usize = groups.iter().map(|g| g.transforms.len()).sum();
    let mut t = Text::with_capacity(40 * count + 2);
    t.out.push('[');
    for (k, tr) in groups.iter().flat_map(|g| g.transforms.iter()).enumerate() {
        if k > 0 {
            t.out.push_str(", ");
        }
        match array {
            Placements::Orientations => {
                let [x, y, z, w] = tr.rotation;
                t.tuple(&[w, x, y, z]);
            }
            Placements::Positions => t.tuple(&tr.translation),
            Placements::Scales => t.tuple(&[tr.scale; 3]),
        }
    }
    t.out.push(']');
    t.out
}

/// A mesh prim to format: the mesh, its prim name, its transform, its material's path and the
/// indentation of its `def` line.
struct MeshJob<'m> {
    mesh: &'m Mesh,
    name: String,
    transform: Option<Mat4>,
    material: String,
    depth: usize,
}

impl<'m> Writer<'m> {
    fn new(models: &'m [Model], folder: &str) -> Writer<'m> {
        let mut w = Writer {
            text: Text::with_capacity(4096),
            pieces: Vec::new(),
            folder: folder.to_string(),
            materials: Vec::new(),
            textures: Vec::new(),
        };
        let mut names = Names::default();
        for model in models {
            for mesh in &model.meshes {
                w.material(&mesh.material, &mut names);
            }
        }
        w
    }

    /// Registers a material (and its textures) once.
    fn material(&mut self, m: &Arc<Material>, names: &mut Names) {
        if self
            .materials
            .iter()
            .any(|(k, _)| Arc::ptr_eq(k, m) || **k == **m)
        {
            return;
        }
        self.materials.push((m.clone(), names.unique(&m.name)));
        for t in [&m.texture, &m.normal_texture, &m.metallic_roughness_texture]
            .into_iter()
            .flatten()
        {
            if !self
                .textures
                .iter()
                .any(|(k, _)| Arc::ptr_eq(k, t) || **k == **t)
            {
                let path = format!(
                    "{}/{}_{}.{}",
                    self.folder,
                    self.textures.len(),
                    identifier(&t.name),
                    t.extension()
                );
                self.textures.push((t.clone(), path));
            }
        }
    }

    fn material_name(&self, m: &Arc<Material>) -> &str {
        self.materials
            .iter()
            .find(|(k, _)| Arc::ptr_eq(k, m) || **k == **m)
            .map_or("", |(_, n)| n.as_str())
    }

    fn texture_path(&self, t: &Arc<Texture>) -> &str {
        self.textures
            .iter()
            .find(|(k, _)| Arc::ptr_eq(k, t) || **k == **t)
            .map_or("", |(_, p)| p.as_str())
    }

    /// The layer: the pieces in order, the meshes formatted on the rayon pool.
    fn finish(mut self) -> UsdFiles {
        self.text.out.push('\n');
        self.pieces
            .push(Piece::Text(std::mem::take(&mut self.text.out)));
        let texts: Vec<std::borrow::Cow<str>> = self
            .pieces
            .par_iter()
            .map(|piece| match piece {
                Piece::Text(text) => std::borrow::Cow::Borrowed(text.as_str()),
                Piece::Mesh(job) => std::borrow::Cow::Owned(mesh_text(job)),
                Piece::Placements(groups, array) => {
                    std::borrow::Cow::Owned(placements_text(groups, *array))
                }
            })
            .collect();
        let mut layer = String::with_capacity(texts.iter().map(|t| t.len()).sum());
        for text in &texts {
            layer.push_str(text);
        }
        UsdFiles {
            layer,
            textures: self.textures.into_iter().map(|(t, p)| (p, t)).collect(),
        }
    }

    fn header(&mut self) {
        self.text.out.push_str("#usda 1.0\n(");
        self.text.depth_in();
        self.text.put(&format!("defaultPrim = \"{USD_ROOT}\""));
        let mut doc = String::from("doc = ");
        quote(&mut doc, GENERATOR);
        self.text.put(&doc);
        self.text.put("metersPerUnit = 1");
        self.text.put("upAxis = \"Y\"");
        self.text.close(")");
        self.text.out.push('\n');
    }

    /// `def Xform "PGE" (customData = {pge = {...}} [variants]) {`.
    fn root_open(&mut self, model: &Model, meta: &ExportMeta, stages: Option<(JsonValue, String)>) {
        self.text.open(&format!("def Xform \"{USD_ROOT}\""), "(");
        self.text.put("customData = {");
        self.text.depth_in();
        self.text.put("dictionary pge = {");
        self.text.depth_in();
        self.run_metadata(model, meta, stages.as_ref().map(|(s, _)| s));
        self.text.close("}");
        self.text.close("}");
        if let Some((_, selected)) = &stages {
            self.text.put("variants = {");
            self.text.depth_in();
            self.text.put("string stage = ");
            self.text.string(selected);
            self.text.close("}");
            self.text.put("prepend variantSets = \"stage\"");
        }
        self.text.close(")");
        self.text.open("", "{");
    }

    /// The run's metadata: generator, seed, params, stats, the forest, the model's extras.
    fn run_metadata(&mut self, model: &Model, meta: &ExportMeta, stages: Option<&JsonValue>) {
        let t = &mut self.text;
        t.json_entry("generator", &json!(GENERATOR));
        t.json_entry("seed", &json!(meta.seed));
        let mut params = serde_json::Map::new();
        for (name, value) in &meta.params {
            params.insert(name.clone(), value.clone());
        }
        // Declared order, as the glb keeps it: a duplicate name where it first appears.
        t.line().push_str("dictionary \"params\" = {");
        t.depth_in();
        let mut seen = Vec::new();
        for (name, _) in &meta.params {
            if seen.contains(&name) {
                continue;
            }
            seen.push(name);
            t.json_entry(name, &params[name]);
        }
        t.close("}");
        t.json_entry(
            "stats",
            &json!({
                "vertices": model.vertex_count(),
                "triangles": model.triangle_count(),
                "nodes": model.stats.nodes,
                "leaves": model.stats.leaves,
                "modules": model.stats.modules,
            }),
        );
        if let Some(forest) = &model.forest
            && let Ok(v) = serde_json::to_value(forest)
        {
            t.json_entry("forest", &v);
        }
        for (key, value) in &model.extras {
            if matches!(
                key.as_str(),
                "generator" | "seed" | "params" | "stats" | "forest" | "stages"
            ) {
                continue;
            }
            t.json_entry(key, value);
        }
        if let Some(s) = stages {
            t.json_entry("stages", s);
        }
    }

    /// The `Materials` scope.
    fn materials(&mut self) {
        self.text.open("def Scope \"Materials\"", "{");
        for k in 0..self.materials.len() {
            let (m, name) = self.materials[k].clone();
            self.write_material(&m, &name);
        }
        self.text.close("}");
    }

    fn write_material(&mut self, m: &Material, name: &str) {
        let path = format!("</{USD_ROOT}/Materials/{name}");
        let t = &mut self.text;
        t.open(&format!("def Material \"{name}\""), "{");
        t.put(&format!(
            "token outputs:surface.connect = {path}/Surface.outputs:surface>"
        ));
        t.open("def Shader \"Surface\"", "{");
        t.put("uniform token info:id = \"UsdPreviewSurface\"");
        let [r, g, b, a] = m.base_color;
        if m.texture.is_some() {
            t.put(&format!(
                "color3f inputs:diffuseColor.connect = {path}/Color.outputs:rgb>"
            ));
        } else {
            t.line().push_str("color3f inputs:diffuseColor = ");
            t.tuple(&[r, g, b]);
        }
        if m.metallic_roughness_texture.is_some() {
            t.put(&format!(
                "float inputs:metallic.connect = {path}/MetallicRoughness.outputs:b>"
            ));
            t.put(&format!(
                "float inputs:roughness.connect = {path}/MetallicRoughness.outputs:g>"
            ));
        } else {
            t.line().push_str("float inputs:metallic = ");
            t.float(m.metallic);
            t.line().push_str("float inputs:roughness = ");
            t.float(m.roughness);
        }
        if m.normal_texture.is_some() {
            t.put(&format!(
                "normal3f inputs:normal.connect = {path}/Normal.outputs:rgb>"
            ));
        }
        match (m.alpha, m.texture.is_some()) {
            (AlphaMode::Opaque, _) => {}
            (_, true) => t.put(&format!(
                "float inputs:opacity.connect = {path}/Color.outputs:a>"
            )),
            (_, false) => {
                t.line().push_str("float inputs:opacity = ");
                t.float(a);
            }
        }
        if let AlphaMode::Mask(cutoff) = m.alpha {
            t.line().push_str("float inputs:opacityThreshold = ");
            t.float(cutoff);
        }
        t.put("int inputs:useSpecularWorkflow = 0");
        t.put("token outputs:surface");
        t.close("}");
        let textured = m.texture.is_some()
            || m.normal_texture.is_some()
            || m.metallic_roughness_texture.is_some();
        if textured {
            t.open("def Shader \"ST\"", "{");
            t.put("uniform token info:id = \"UsdPrimvarReader_float2\"");
            t.put("string inputs:varname = \"st\"");
            t.put("float2 outputs:result");
            t.close("}");
        }
        let readers = [
            (&m.texture, "Color", "sRGB", [r, g, b, a], [0.0; 4]),
            (
                &m.normal_texture,
                "Normal",
                "raw",
                [2.0, 2.0, 2.0, 1.0],
                [-1.0, -1.0, -1.0, 0.0],
            ),
            (
                &m.metallic_roughness_texture,
                "MetallicRoughness",
                "raw",
                [1.0, m.roughness, m.metallic, 1.0],
                [0.0; 4],
            ),
        ];
        for (texture, reader, space, scale, bias) in readers {
            let Some(texture) = texture else { continue };
            let file = self.texture_path(texture).to_string();
            let t = &mut self.text;
            t.open(&format!("def Shader \"{reader}\""), "{");
            t.put("uniform token info:id = \"UsdUVTexture\"");
            let l = t.line();
            l.push_str("asset inputs:file = @./");
            l.push_str(&file);
            l.push('@');
            t.put(&format!(
                "float2 inputs:st.connect = {path}/ST.outputs:result>"
            ));
            t.put(&format!("token inputs:sourceColorSpace = \"{space}\""));
            t.line().push_str("float4 inputs:scale = ");
            t.tuple(&scale);
            if bias != [0.0; 4] {
                t.line().push_str("float4 inputs:bias = ");
                t.tuple(&bias);
            }
            t.put("token inputs:wrapS = \"repeat\"");
            t.put("token inputs:wrapT = \"repeat\"");
            match reader {
                "Color" => {
                    t.put("float3 outputs:rgb");
                    if !matches!(m.alpha, AlphaMode::Opaque) {
                        t.put("float outputs:a");
                    }
                }
                "Normal" => t.put("float3 outputs:rgb"),
                _ => {
                    t.put("float outputs:b");
                    t.put("float outputs:g");
                }
            }
            t.close("}");
        }
        self.text.close("}");
    }

    /// A model's placed meshes and its forest, as children of the current prim.
    fn body(&mut self, model: &'m Model) {
        let mut names = Names::default();
        for inst in &model.instances {
            let mesh = &model.meshes[inst.mesh];
            let name = names.unique(&mesh.name);
            self.mesh(mesh, &name, Some(&inst.transform));
        }
        // One point instancer per species (`SPECIES/VARIANT`), a prototype per variant.
        let mut species: Vec<(&str, Vec<&InstanceGroup>)> = Vec::new();
        // A group that places nothing is not written (as in the glb).
        for group in model.groups.iter().filter(|g| !g.transforms.is_empty()) {
            let name = group.name.split('/').next().unwrap_or("");
            match species.iter_mut().find(|(s, _)| *s == name) {
                Some((_, groups)) => groups.push(group),
                None => species.push((name, vec![group])),
            }
        }
        for (name, groups) in species {
            let name = names.unique(if name.is_empty() { "instances" } else { name });
            self.instancer(model, &name, &groups);
        }
    }

    /// A `PointInstancer` named `name` (a child of the root or a stage) of `groups`.
    fn instancer(&mut self, model: &'m Model, name: &str, groups: &[&'m InstanceGroup]) {
        // One prototype per variant: groups of the same meshes (a merged world's tiles place
        // the same shared variants) share one, named after the first.
        let mut protos = Names::default();
        let mut prototypes: Vec<(&InstanceGroup, String)> = Vec::new();
        let mut proto_of = Vec::with_capacity(groups.len());
        for g in groups {
            match prototypes.iter().position(|(p, _)| p.meshes == g.meshes) {
                Some(k) => proto_of.push(k),
                None => {
                    proto_of.push(prototypes.len());
                    prototypes.push((g, protos.unique(&g.name)));
                }
            }
        }
        let count: usize = groups.iter().map(|g| g.transforms.len()).sum();
        let t = &mut self.text;
        t.open(&format!("def PointInstancer \"{name}\""), "(");
        t.put("customData = {");
        t.depth_in();
        t.json_entry("instances", &json!(count));
        if groups.iter().all(|g| g.leaves.is_some()) {
            // The leaves each instance draws, and each prototype's coarsest level.
            t.put("dictionary \"lod\" = {");
            t.depth_in();
            t.line().push_str("int64[] \"leaves\" = [");
            let mut first = true;
            for g in groups {
                for c in g.leaves.iter().flat_map(|l| l.counts.iter()) {
                    if !first {
                        t.out.push_str(", ");
                    }
                    first = false;
                    t.int(*c);
                }
            }
            t.out.push(']');
            t.line().push_str("int64[] \"roots\" = ");
            t.array(&prototypes, |t, (g, _)| {
                t.int(g.leaves.as_ref().map_or(0, |l| l.roots));
            });
            t.close("}");
        }
        t.close("}");
        t.close(")");
        t.open("", "{");
        t.line().push_str("quath[] orientations = ");
        self.placements(groups, Placements::Orientations);
        let t = &mut self.text;
        t.line().push_str("point3f[] positions = ");
        self.placements(groups, Placements::Positions);
        let t = &mut self.text;
        t.line().push_str("int[] protoIndices = [");
        let mut first = true;
        for (&p, g) in proto_of.iter().zip(groups) {
            for _ in &g.transforms {
                if !first {
                    t.out.push_str(", ");
                }
                first = false;
                t.int(p);
            }
        }
        t.out.push(']');
        let l = t.line();
        l.push_str("rel prototypes = [");
        for (k, (_, p)) in prototypes.iter().enumerate() {
            if k > 0 {
                l.push_str(", ");
            }
            l.push_str(&format!("</{USD_ROOT}/{name}/Prototypes/{p}>"));
        }
        l.push(']');
        t.line().push_str("float3[] scales = ");
        self.placements(groups, Placements::Scales);
        let t = &mut self.text;
        t.open("def Scope \"Prototypes\"", "{");
        for (g, p) in &prototypes {
            self.text.open(&format!("def Xform \"{p}\""), "(");
            self.text.line().push_str("customData = {");
            self.text.depth_in();
            self.text.json_entry("name", &json!(g.name));
            self.text.close("}");
            self.text.close(")");
            self.text.open("", "{");
            let mut names = Names::default();
            for &m in &g.meshes {
                let mesh = &model.meshes[m];
                let name = names.unique(&mesh.name);
                self.mesh(mesh, &name, None);
            }
            self.text.close("}");
        }
        self.text.close("}");
        self.text.close("}");
    }

    /// An array of the placements of `groups`, formatted when the layer is finished.
    fn placements(&mut self, groups: &[&'m InstanceGroup], array: Placements) {
        self.pieces
            .push(Piece::Text(std::mem::take(&mut self.text.out)));
        self.pieces.push(Piece::Placements(groups.to_vec(), array));
    }

    /// One mesh as a `Mesh` (triangles) or `BasisCurves` (lines) prim named `name`, formatted
    /// when the layer is finished ([`mesh_text`]).
    fn mesh(&mut self, mesh: &'m Mesh, name: &str, transform: Option<&Mat4>) {
        let material = format!(
            "/{USD_ROOT}/Materials/{}",
            self.material_name(&mesh.material)
        );
        self.pieces
            .push(Piece::Text(std::mem::take(&mut self.text.out)));
        self.pieces.push(Piece::Mesh(MeshJob {
            mesh,
            name: name.to_string(),
            transform: transform.copied(),
            material,
            depth: self.text.depth(),
        }));
    }
}

#[cfg(test)]
mod tests;
