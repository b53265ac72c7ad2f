//! Meshes and their primitives: a model's meshes, and an instance group's members as the
//! primitives of one glTF mesh.

use std::sync::Arc;

use gltf_json as json;
use json::validation::Checked::Valid;

use super::*;
use crate::geometry::{InstanceGroup, Mesh, Primitive};
use crate::{Error, Result};

impl Builder {
    pub(super) fn mesh(&mut self, mesh: &Arc<Mesh>) -> Result<json::Index<json::Mesh>> {
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
    pub(super) fn group_mesh(
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

    pub(super) fn primitive<'m>(
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
        // Tangents (the mesh's own, or MikkTSpace's) where a normal map reads them.
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
