//! Nodes and scenes: one node per instance, one per instance group (or per placement),
//! the sky dome around the model, gathered in a named scene.

use std::sync::Arc;

use glam::{Mat4, Vec3};
use gltf_json as json;

use super::*;
use crate::geometry::{Material, Model, Texture};
use crate::{Error, Result};

/// A node placing `mesh` by `m`: translation/rotation/scale when `m` decomposes exactly,
/// the matrix otherwise.
pub(super) fn node(mesh: json::Index<json::Mesh>, m: &Mat4) -> json::Node {
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

impl Builder {
    /// Writes the model's meshes, one node per instance and its instance groups (as
    /// `self.instancing` says), gathered in a scene named `name`. A model that places nothing
    /// gets a scene holding one empty node named `empty`: clients expect a scene (three.js's
    /// `gltf.scene`), and a glTF scene lists at least one node.
    pub(super) fn scene(&mut self, model: &Model, name: &str) -> Result<json::Index<json::Scene>> {
        // Meshes only groups use are written inside their group's mesh, not on their own.
        let mut meshes = Vec::with_capacity(model.meshes.len());
        for (i, m) in model.meshes.iter().enumerate() {
            self.limit.check()?;
            let standalone =
                model.groups.is_empty() || model.instances.iter().any(|inst| inst.mesh == i);
            meshes.push(if standalone {
                Some(self.mesh(m)?)
            } else {
                None
            });
        }
        let mut nodes = Vec::with_capacity(model.instances.len());
        for (k, inst) in model.instances.iter().enumerate() {
            if k % CHECK_EVERY == 0 {
                self.limit.check()?;
            }
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
            self.limit.check()?;
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
                        if k % CHECK_EVERY == 0 {
                            self.limit.check()?;
                        }
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
    pub(super) fn sky_dome(&mut self, env: &Arc<Texture>) -> Result<json::Index<json::Mesh>> {
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
}
