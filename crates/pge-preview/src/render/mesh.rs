//! One mesh on the GPU: its buffers, its material, and how it is drawn outside a forest.

use std::sync::Arc;

use eframe::egui_wgpu::wgpu;
use glam::{Mat4, Vec4};
use wgpu::util::DeviceExt;

use super::super::pipeline::material_uniform;
use super::super::scene::{Scene, SceneMesh};
use super::Toggles;
use super::overlay::triangle_edges;

/// Leaves instanced at least this many times (a forest's) are drawn for near trees only
/// while the camera moves.
const FAR_LEAVES_MIN: usize = 256;

/// The share of their depth range, from the nearest, where such leaves are drawn while the
/// camera moves.
const NEAR_FRACTION: f32 = 0.3;

/// The three mesh pipelines: back faces culled, double-sided, lines.
#[derive(Clone, Copy)]
pub(super) struct MeshPipelines<'a> {
    pub culled: &'a wgpu::RenderPipeline,
    pub double: &'a wgpu::RenderPipeline,
    pub lines: &'a wgpu::RenderPipeline,
}

pub(super) struct GpuMesh {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub index_count: u32,
    pub instances: wgpu::Buffer,
    pub instance_count: u32,
    pub material: wgpu::BindGroup,
    pub lines: bool,
    pub double_sided: bool,
    pub is_leaf: bool,
    /// Edge list for the wireframe, built when first needed.
    pub edges: Option<(wgpu::Buffer, u32)>,
    /// An eighth of the leaves or the largest eighth of a big bark mesh (vertices, indices,
    /// index count), for frames drawn while the camera moves.
    pub coarse: Option<(wgpu::Buffer, wgpu::Buffer, u32)>,
    /// For leaves instanced by many trees (not a forest's): the instances near the camera,
    /// rewritten for each moving frame, and how many there are; far trees' leaves are not
    /// drawn while the camera moves.
    pub near: Option<(wgpu::Buffer, u32)>,
    pub source: Arc<Scene>,
    pub index_in_scene: usize,
    /// Sequential quads over all of V, the vertices coloured by level and the LOD tables,
    /// for a leaf mesh with levels.
    pub lod: Option<(wgpu::Buffer, wgpu::Buffer, super::super::lod::LeafLod)>,
}

pub(super) fn buffer_init(
    device: &wgpu::Device,
    label: &str,
    bytes: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytes,
        usage,
    })
}

/// wgpu refuses empty buffers; an empty index list still gets one (unused) index.
pub(super) fn index_bytes(indices: &[u32]) -> &[u8] {
    if indices.is_empty() {
        bytemuck::cast_slice(&[0u32])
    } else {
        bytemuck::cast_slice(indices)
    }
}

impl GpuMesh {
    /// Uploads mesh `index` of `scene`, drawn with `material` (its bind group).
    pub fn new(
        device: &wgpu::Device,
        scene: &Arc<Scene>,
        index: usize,
        material: wgpu::BindGroup,
    ) -> GpuMesh {
        let mesh = &scene.meshes[index];
        GpuMesh {
            vertices: buffer_init(
                device,
                "vertices",
                bytemuck::cast_slice(&mesh.vertices),
                wgpu::BufferUsages::VERTEX,
            ),
            indices: buffer_init(
                device,
                "indices",
                index_bytes(&mesh.indices),
                wgpu::BufferUsages::INDEX,
            ),
            index_count: mesh.indices.len() as u32,
            lod: mesh.lod.as_ref().map(|lod| {
                let quads = lod.quad_indices();
                let colored = lod.level_colors(&mesh.vertices);
                (
                    buffer_init(
                        device,
                        "lod quads",
                        index_bytes(&quads),
                        wgpu::BufferUsages::INDEX,
                    ),
                    buffer_init(
                        device,
                        "lod colours",
                        bytemuck::cast_slice(&colored),
                        wgpu::BufferUsages::VERTEX,
                    ),
                    lod.clone(),
                )
            }),
            instances: buffer_init(
                device,
                "instances",
                bytemuck::cast_slice(&mesh.instances),
                wgpu::BufferUsages::VERTEX,
            ),
            instance_count: mesh.instances.len() as u32,
            material,
            lines: mesh.lines,
            double_sided: mesh.double_sided,
            is_leaf: mesh.is_leaf,
            edges: None,
            coarse: mesh
                .coarse
                .as_ref()
                .filter(|(_, c)| !c.is_empty())
                .map(|(v, c)| {
                    (
                        buffer_init(
                            device,
                            "coarse leaves",
                            bytemuck::cast_slice(v),
                            wgpu::BufferUsages::VERTEX,
                        ),
                        buffer_init(
                            device,
                            "coarse leaves",
                            index_bytes(c),
                            wgpu::BufferUsages::INDEX,
                        ),
                        c.len() as u32,
                    )
                }),
            near: (mesh.is_leaf && !mesh.forest && mesh.instances.len() >= FAR_LEAVES_MIN).then(
                || {
                    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("near instances"),
                        size: std::mem::size_of_val(mesh.instances.as_slice()) as u64,
                        usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    });
                    (buffer, 0)
                },
            ),
            source: scene.clone(),
            index_in_scene: index,
        }
    }

    /// The scene mesh this was uploaded from.
    pub fn scene_mesh(&self) -> &SceneMesh {
        &self.source.meshes[self.index_in_scene]
    }

    /// Builds the wireframe's edge list, once.
    pub fn build_edges(&mut self, device: &wgpu::Device) {
        if self.edges.is_some() || self.lines {
            return;
        }
        let edges = triangle_edges(&self.scene_mesh().indices);
        let buffer = buffer_init(
            device,
            "edges",
            index_bytes(&edges),
            wgpu::BufferUsages::INDEX,
        );
        self.edges = Some((buffer, edges.len() as u32));
    }

    /// For a moving frame: the instances of many-times-instanced leaves (not a forest's)
    /// that are in view and in the nearest [`NEAR_FRACTION`] of their depth range.
    pub fn pick_near(&mut self, queue: &wgpu::Queue, view_proj: Mat4) {
        let Some((buffer, count)) = &mut self.near else {
            return;
        };
        let Some(all) = self.source.meshes.get(self.index_in_scene) else {
            return;
        };
        let clip: Vec<Vec4> = all
            .instances
            .iter()
            .map(|m| view_proj * Vec4::new(m[12], m[13], m[14], 1.0))
            .collect();
        let (lo, hi) = clip
            .iter()
            .filter(|c| c.w > 0.0)
            .fold((f32::INFINITY, 0.0f32), |(lo, hi), c| {
                (lo.min(c.w), hi.max(c.w))
            });
        let cut = lo + NEAR_FRACTION * (hi - lo);
        // A crown reaches beyond its trunk: keep trunks a little outside the frame.
        let near: Vec<[f32; 16]> = all
            .instances
            .iter()
            .zip(&clip)
            .filter(|(_, c)| {
                c.w > 0.0 && c.w <= cut && c.x.abs() <= 1.3 * c.w && c.y.abs() <= 1.3 * c.w
            })
            .map(|(m, _)| *m)
            .collect();
        if !near.is_empty() {
            queue.write_buffer(buffer, 0, bytemuck::cast_slice(&near));
        }
        *count = near.len() as u32;
    }

    /// Draws a mesh that no forest places: whole, coarse while `moving`, as its edges in
    /// wireframe, or at a level of detail; returns the triangles drawn (lines not counted).
    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipelines: MeshPipelines<'_>,
        toggles: Toggles,
        moving: bool,
    ) -> u64 {
        let mut vertices = &self.vertices;
        let (pipeline, indices, count) = if self.lines {
            (pipelines.lines, &self.indices, self.index_count)
        } else if toggles.wireframe {
            match &self.edges {
                Some((edges, n)) => (pipelines.lines, edges, *n),
                None => return 0,
            }
        } else {
            let pipeline = if self.double_sided {
                pipelines.double
            } else {
                pipelines.culled
            };
            match (&self.coarse, moving) {
                (Some((coarse_vertices, coarse, n)), true) => {
                    vertices = coarse_vertices;
                    (pipeline, coarse, *n)
                }
                _ => (pipeline, &self.indices, self.index_count),
            }
        };
        if count == 0 {
            return 0;
        }
        // A coarser level of detail, or leaves coloured by level: the two ranges of V per
        // sector over the sequential quads.
        if let Some((quads, colored, lod)) = &self.lod
            && (toggles.lod_percent < 100 || toggles.lod_colors)
            && !toggles.wireframe
            && std::ptr::eq(vertices, &self.vertices)
        {
            let vertices = if toggles.lod_colors {
                colored
            } else {
                vertices
            };
            pass.set_pipeline(pipeline);
            pass.set_bind_group(1, &self.material, &[]);
            pass.set_vertex_buffer(0, vertices.slice(..));
            pass.set_vertex_buffer(1, self.instances.slice(..));
            pass.set_index_buffer(quads.slice(..), wgpu::IndexFormat::Uint32);
            let mut triangles = 0;
            for range in lod.index_ranges(toggles.lod_percent) {
                triangles += u64::from(range.len() as u32 / 3) * u64::from(self.instance_count);
                pass.draw_indexed(range, 0, 0..self.instance_count);
            }
            return triangles;
        }
        pass.set_pipeline(pipeline);
        pass.set_bind_group(1, &self.material, &[]);
        pass.set_vertex_buffer(0, vertices.slice(..));
        let (instances, instance_count) = match &self.near {
            Some((near, n)) if moving && !toggles.wireframe => (near, *n),
            _ => (&self.instances, self.instance_count),
        };
        if instance_count == 0 {
            return 0;
        }
        pass.set_vertex_buffer(1, instances.slice(..));
        pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..count, 0, 0..instance_count);
        if self.lines || toggles.wireframe {
            0
        } else {
            u64::from(count / 3) * u64::from(instance_count)
        }
    }
}

/// The material bind group of `mesh`: its uniform, its texture view (`view`), `sampler` and
/// normal map view (`normal`).
pub(super) fn material_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    mesh: &SceneMesh,
    view: &wgpu::TextureView,
    sampler: &wgpu::Sampler,
    normal: &wgpu::TextureView,
) -> wgpu::BindGroup {
    let uniform = material_uniform(
        mesh.base_color,
        mesh.alpha_cutoff,
        mesh.double_sided,
        mesh.transmission,
    );
    bind_material(device, layout, "material", &uniform, view, sampler, normal)
}

/// A bind group of the material layout named `label`: the `uniform` (as
/// [`material_uniform`] makes it) in a new buffer, the texture `view`, `sampler` and the
/// normal map `normal`.
pub(super) fn bind_material(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    label: &str,
    uniform: &[f32],
    view: &wgpu::TextureView,
    sampler: &wgpu::Sampler,
    normal: &wgpu::TextureView,
) -> wgpu::BindGroup {
    let uniform = buffer_init(
        device,
        label,
        bytemuck::cast_slice(uniform),
        wgpu::BufferUsages::UNIFORM,
    );
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(view),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::Sampler(sampler),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: wgpu::BindingResource::TextureView(normal),
            },
        ],
    })
}
