use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::{ForestStats, GeometryError, Mesh, Texture, VariantCounts};

/// One placement of a mesh in the model (a glTF node).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Instance {
    /// Index into [`Model::meshes`].
    pub mesh: usize,
    /// Local-to-world transform.
    pub transform: Mat4,
}

/// One placement in an [`InstanceGroup`]: translation, rotation (a unit quaternion x, y, z,
/// w) and a uniform scale, 32 bytes, so a forest of millions of trees stays compact.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InstanceTransform {
    /// Where the instance stands.
    pub translation: [f32; 3],
    /// Its rotation as a unit quaternion `[x, y, z, w]`.
    pub rotation: [f32; 4],
    /// Its uniform scale.
    pub scale: f32,
}

impl InstanceTransform {
    /// The transform as a matrix.
    #[must_use]
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(
            Vec3::splat(self.scale),
            glam::Quat::from_array(self.rotation),
            Vec3::from_array(self.translation),
        )
    }
}

/// Many placements of one object made of several meshes (a tree's bark and leaves): exported
/// as one glTF mesh with a primitive per mesh and either one node with
/// `EXT_mesh_gpu_instancing` or one node per placement.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InstanceGroup {
    /// Name of the glTF mesh (a forest writes `SPECIES/VARIANT`).
    pub name: String,
    /// Indices into [`Model::meshes`]: the primitives of the object, in its own frame.
    pub meshes: Vec<usize>,
    /// The placements.
    pub transforms: Vec<InstanceTransform>,
    /// How many leaves each placement draws of the object's foliage levels of detail (a
    /// forest's leaf budget for a camera), written in the node extras; `None` when not
    /// budgeted.
    pub leaves: Option<PlacementLeaves>,
}

/// The leaves each placement of an [`InstanceGroup`] draws: counts aligned with
/// [`InstanceGroup::transforms`], exported as the node's `extras.pge.lod = {leaves, level}`
/// (arrays with `EXT_mesh_gpu_instancing`, one number per node otherwise).
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PlacementLeaves {
    /// The coarsest level's leaf count |R| of the object (a drawn placement's level is its
    /// count minus this).
    pub roots: u32,
    /// Leaves drawn by each placement, 0 for one not drawn.
    pub counts: Vec<u32>,
}

impl PlacementLeaves {
    /// The level of placement `k`: its count minus [`roots`](Self::roots), -1 when it is not
    /// drawn.
    #[must_use]
    pub fn level(&self, k: usize) -> i64 {
        match self.counts.get(k) {
            Some(&c) if c > 0 => i64::from(c) - i64::from(self.roots),
            _ => -1,
        }
    }
}

/// Counts and timings of a generation, reported by `pge run --stats`.
///
/// Vertex and triangle counts are not stored: they are derived from the model.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Stats {
    /// Skeleton nodes.
    pub nodes: u64,
    /// Leaves.
    pub leaves: u64,
    /// Length of the final L-system string.
    pub modules: u64,
    /// Seconds spent per phase, in the order the phases ran. Never exported to the glb
    /// (timings would make the output differ from run to run), nor to the binary form.
    #[serde(skip)]
    pub phases: Vec<(String, f64)>,
    /// Warnings for the user (`FILE:LINE: warning: ...`): the result is usable but may not be
    /// what was meant. `pge run` prints them; the preview shows them.
    pub warnings: Vec<String>,
}

impl Stats {
    /// Adds `seconds` to the phase called `name` (appending it if new).
    pub fn add_phase(&mut self, name: &str, seconds: f64) {
        match self.phases.iter_mut().find(|(n, _)| n == name) {
            Some((_, s)) => *s += seconds,
            None => self.phases.push((name.to_string(), seconds)),
        }
    }

    /// Adds the counts and phases of another generation to these.
    pub fn merge(&mut self, other: &Stats) {
        self.nodes += other.nodes;
        self.leaves += other.leaves;
        self.modules += other.modules;
        for (name, s) in &other.phases {
            self.add_phase(name, *s);
        }
        self.warnings.extend(other.warnings.iter().cloned());
    }
}

/// The result of a generation: shared meshes, the instances that place them, and extras.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Model {
    /// Meshes, each exported once however many instances use it.
    #[serde(with = "super::binary::shared_vec")]
    pub meshes: Vec<Arc<Mesh>>,
    /// Placements of the meshes; every one becomes a glTF node.
    pub instances: Vec<Instance>,
    /// Instanced objects (forests): many placements of the same meshes, stored compactly.
    pub groups: Vec<InstanceGroup>,
    /// The forest the model is (a forest's generator records it), written as the root
    /// `extras.pge.forest`.
    pub forest: Option<ForestStats>,
    /// What one instance of each group stands for, aligned with [`Model::groups`], in a
    /// forest's shared variants (`pge run --variants-out`); empty otherwise.
    pub variant_counts: Vec<VariantCounts>,
    /// Application data written under the root `extras.pge` next to the generator's own.
    #[serde(with = "super::binary::json_text")]
    pub extras: serde_json::Map<String, serde_json::Value>,
    /// Counts and timings.
    pub stats: Stats,
    /// An equirectangular sky image (row 0 straight up, the middle row the horizon), exported
    /// as an image referenced by the root `extras.pge.environment` and drawn by the preview
    /// as the background.
    #[serde(with = "super::binary::shared_option")]
    pub environment: Option<Arc<Texture>>,
    /// Meshes of `meshes` known to have no unusable triangle (their generator showed it, e.g.
    /// with [`Mesh::usable_by_construction`]), which [`Model::remove_unusable_triangles`]
    /// does not search. Each is a second reference to its mesh, so a listed mesh cannot
    /// change: `Arc::make_mut` copies a shared mesh, and the copy is searched.
    #[serde(skip)]
    pub clean: Vec<Arc<Mesh>>,
}

impl Model {
    /// An empty model.
    #[must_use]
    pub fn new() -> Model {
        Model::default()
    }

    /// A model with one mesh at the origin.
    #[must_use]
    pub fn from_mesh(mesh: impl Into<Arc<Mesh>>) -> Model {
        let mut model = Model::new();
        model.add_mesh(mesh, Mat4::IDENTITY);
        model
    }

    /// Adds a mesh placed by `transform`; a mesh already in the model (same `Arc`) is shared.
    pub fn add_mesh(&mut self, mesh: impl Into<Arc<Mesh>>, transform: Mat4) {
        let mesh = mesh.into();
        let index = self.mesh_index(mesh);
        self.instances.push(Instance {
            mesh: index,
            transform,
        });
    }

    /// Adds every instance of `other`, placed by `transform`, sharing meshes by `Arc`.
    /// Stats are merged; extras of `other` are copied where this model has no such key; its
    /// forest, variant counts and environment are taken when this model has none.
    pub fn add_model(&mut self, other: &Model, transform: Mat4) {
        let map: Vec<usize> = other
            .meshes
            .iter()
            .map(|m| self.mesh_index(m.clone()))
            .collect();
        for inst in &other.instances {
            self.instances.push(Instance {
                mesh: map[inst.mesh],
                transform: transform * inst.transform,
            });
        }
        for group in &other.groups {
            let transforms = group
                .transforms
                .iter()
                .map(|t| {
                    let (s, r, p) = (transform * t.matrix()).to_scale_rotation_translation();
                    InstanceTransform {
                        translation: p.to_array(),
                        rotation: r.to_array(),
                        scale: s.max_element(),
                    }
                })
                .collect();
            self.groups.push(InstanceGroup {
                name: group.name.clone(),
                meshes: group.meshes.iter().map(|&m| map[m]).collect(),
                transforms,
                leaves: group.leaves.clone(),
            });
        }
        for mesh in &other.clean {
            if !self.clean.iter().any(|m| Arc::ptr_eq(m, mesh)) {
                self.clean.push(mesh.clone());
            }
        }
        self.stats.merge(&other.stats);
        for (k, v) in &other.extras {
            self.extras.entry(k.clone()).or_insert_with(|| v.clone());
        }
        if self.forest.is_none() {
            self.forest.clone_from(&other.forest);
        }
        if self.variant_counts.is_empty() {
            self.variant_counts.clone_from(&other.variant_counts);
        }
        if self.environment.is_none() {
            self.environment.clone_from(&other.environment);
        }
    }

    fn mesh_index(&mut self, mesh: Arc<Mesh>) -> usize {
        match self.meshes.iter().position(|m| Arc::ptr_eq(m, &mesh)) {
            Some(i) => i,
            None => {
                self.meshes.push(mesh);
                self.meshes.len() - 1
            }
        }
    }

    /// Adds a warning (`SCRIPT: warning: the model is empty: ...`) to the stats when the
    /// model draws no vertex: the file written for it holds an empty scene, which is rarely
    /// what the script meant.
    pub fn warn_if_empty(&mut self, script: &std::path::Path) {
        if self.vertex_count() == 0 {
            self.stats.warnings.push(format!(
                "{}: warning: the model is empty: the script generated nothing to draw",
                script.display()
            ));
        }
    }

    /// Removes degenerate and repeated triangles from every mesh
    /// ([`Mesh::remove_unusable_triangles`]); a mesh with none is left as it is (still
    /// shared), one with some is replaced by a cleaned copy. Returns how many were removed.
    pub fn remove_unusable_triangles(&mut self) -> usize {
        let mut removed = 0;
        for mesh in &mut self.meshes {
            if self.clean.iter().any(|clean| Arc::ptr_eq(clean, mesh)) {
                continue;
            }
            let dropped = mesh.unusable_triangles();
            if !dropped.is_empty() {
                Arc::make_mut(mesh).remove_triangles(&dropped);
                removed += dropped.len();
            }
        }
        removed
    }

    /// The bytes its meshes hold ([`Mesh::heap_bytes`]), a mesh listed twice counted once;
    /// textures and skeletons apart.
    #[must_use]
    pub fn mesh_bytes(&self) -> usize {
        let mut seen = std::collections::HashSet::new();
        (self.meshes.iter())
            .filter(|m| seen.insert(Arc::as_ptr(m)))
            .map(|m| m.heap_bytes())
            .sum()
    }

    /// Vertices drawn, counting every instance (of groups too).
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.drawn(Mesh::vertex_count)
    }

    /// Triangles drawn, counting every instance (of groups too).
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.drawn(Mesh::triangle_count)
    }

    /// The sum of `per_mesh` over every placement of a mesh, instances and groups alike.
    fn drawn(&self, per_mesh: impl Fn(&Mesh) -> usize) -> usize {
        let grouped: usize = self
            .groups
            .iter()
            .map(|g| {
                g.transforms.len()
                    * g.meshes
                        .iter()
                        .map(|&m| per_mesh(&self.meshes[m]))
                        .sum::<usize>()
            })
            .sum();
        self.instances
            .iter()
            .map(|i| per_mesh(&self.meshes[i.mesh]))
            .sum::<usize>()
            + grouped
    }

    /// Placements: plain instances plus every placement of every group.
    #[must_use]
    pub fn instance_count(&self) -> usize {
        self.instances.len()
            + self
                .groups
                .iter()
                .map(|g| g.transforms.len())
                .sum::<usize>()
    }

    /// Checks every mesh and that instances point at existing meshes with finite transforms.
    pub fn validate(&self) -> Result<(), GeometryError> {
        for mesh in &self.meshes {
            mesh.validate()?;
        }
        for (at, inst) in self.instances.iter().enumerate() {
            if inst.mesh >= self.meshes.len() {
                return Err(GeometryError::IndexOutOfRange {
                    index: inst.mesh as u32,
                    at,
                    vertices: self.meshes.len(),
                });
            }
            if !inst.transform.is_finite() {
                return Err(GeometryError::NotFinite {
                    attribute: "instance transform",
                    at,
                });
            }
        }
        for group in &self.groups {
            if let Some(&m) = group.meshes.iter().find(|&&m| m >= self.meshes.len()) {
                return Err(GeometryError::IndexOutOfRange {
                    index: m as u32,
                    at: 0,
                    vertices: self.meshes.len(),
                });
            }
            for (at, t) in group.transforms.iter().enumerate() {
                let finite = t.translation.iter().all(|v| v.is_finite())
                    && t.rotation.iter().all(|v| v.is_finite())
                    && t.scale.is_finite();
                if !finite {
                    return Err(GeometryError::NotFinite {
                        attribute: "group instance transform",
                        at,
                    });
                }
            }
            if let Some(leaves) = &group.leaves
                && leaves.counts.len() != group.transforms.len()
            {
                return Err(GeometryError::AttributeLength {
                    attribute: "group leaf counts",
                    got: leaves.counts.len(),
                    vertices: group.transforms.len(),
                });
            }
        }
        Ok(())
    }

    /// World-space bounds `(min, max)` over all instances, or `None` when empty. Each mesh's
    /// own bounds are found once, not once per instance (a forest places a mesh 10,000 times).
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let own: Vec<Option<(Vec3, Vec3)>> = self.meshes.iter().map(|m| m.bounds()).collect();
        let mut out: Option<(Vec3, Vec3)> = None;
        let grouped = self.groups.iter().flat_map(|g| {
            g.transforms.iter().flat_map(move |t| {
                let m = t.matrix();
                g.meshes.iter().map(move |&mesh| (mesh, m))
            })
        });
        let plain = self.instances.iter().map(|i| (i.mesh, i.transform));
        for (mesh, transform) in plain.chain(grouped) {
            let Some(Some((lo, hi))) = own.get(mesh) else {
                continue;
            };
            for corner in 0..8 {
                let c = Vec3::new(
                    if corner & 1 == 0 { lo.x } else { hi.x },
                    if corner & 2 == 0 { lo.y } else { hi.y },
                    if corner & 4 == 0 { lo.z } else { hi.z },
                );
                let p = transform.transform_point3(c);
                out = Some(match out {
                    None => (p, p),
                    Some((a, b)) => (a.min(p), b.max(p)),
                });
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle() -> Arc<Mesh> {
        Arc::new(
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("ok"),
        )
    }

    #[test]
    fn mesh_bytes_count_a_shared_mesh_once() {
        let tri = triangle();
        let mut m = Model::new();
        m.meshes.push(tri.clone());
        assert_eq!(m.mesh_bytes(), tri.heap_bytes());
        m.meshes.push(tri.clone());
        assert_eq!(m.mesh_bytes(), tri.heap_bytes());
        m.meshes.push(triangle());
        assert_eq!(m.mesh_bytes(), 2 * tri.heap_bytes());
    }

    #[test]
    fn instancing_shares_meshes_and_composes_transforms() {
        let tri = triangle();
        let mut inner = Model::new();
        inner.add_mesh(tri.clone(), Mat4::from_translation(Vec3::X));
        inner.stats.leaves = 3;
        let mut outer = Model::new();
        outer.add_model(&inner, Mat4::from_translation(Vec3::Y));
        outer.add_model(&inner, Mat4::from_translation(Vec3::Z));
        assert_eq!(outer.meshes.len(), 1);
        assert_eq!(outer.instances.len(), 2);
        assert_eq!(outer.triangle_count(), 2);
        assert_eq!(outer.stats.leaves, 6);
        let t = outer.instances[0].transform.transform_point3(Vec3::ZERO);
        assert_eq!(t, Vec3::new(1.0, 1.0, 0.0));
        let (lo, hi) = outer.bounds().expect("not empty");
        assert_eq!(lo, Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(hi, Vec3::new(2.0, 2.0, 1.0));
        outer.validate().expect("valid");
    }

    #[test]
    fn meshes_listed_clean_are_not_searched_until_changed() {
        // The triangle twice: the second is a repeat.
        let mut twice = (*triangle()).clone();
        twice.indices.extend([1, 2, 0]);
        let twice = Arc::new(twice);
        let mut inner = Model::from_mesh(twice.clone());
        inner.clean.push(twice.clone());
        let mut outer = Model::new();
        outer.add_model(&inner, Mat4::IDENTITY);
        outer.add_model(&inner, Mat4::IDENTITY);
        assert_eq!(outer.clean.len(), 1);
        assert_eq!(outer.remove_unusable_triangles(), 0);
        assert!(Arc::ptr_eq(&outer.meshes[0], &twice));
        // A change makes a copy, which is searched.
        Arc::make_mut(&mut outer.meshes[0]).name = "changed".into();
        assert_eq!(outer.remove_unusable_triangles(), 1);
        assert_eq!(outer.meshes[0].indices, [0, 1, 2]);
        assert_eq!(twice.indices.len(), 6);
    }

    #[test]
    fn add_model_keeps_the_receivers_environment_else_takes_the_others() {
        let sky = |name: &str| {
            Arc::new(
                Texture::from_rgba(name, 2, 1, &[0, 0, 255, 255, 0, 0, 128, 255]).expect("png"),
            )
        };
        let mut inner = Model::from_mesh(triangle());
        inner.environment = Some(sky("inner"));
        let mut outer = Model::new();
        outer.add_model(&inner, Mat4::IDENTITY);
        assert_eq!(
            outer.environment.as_ref().map(|t| t.name.as_str()),
            Some("inner")
        );
        let mut own = Model::new();
        own.environment = Some(sky("own"));
        own.add_model(&inner, Mat4::IDENTITY);
        assert_eq!(
            own.environment.as_ref().map(|t| t.name.as_str()),
            Some("own")
        );
    }
}
