//! A forest mesh on the GPU: its instances in the order of the plan drawn, and that plan's
//! instanced draws ([`super::super::forest`]; plans come from [`super::super::planner`]).

use eframe::egui_wgpu::wgpu;

use super::super::forest::{self, Detail, Draw, Source};
use super::super::scene::SceneMesh;
use super::Toggles;
use super::mesh::{GpuMesh, MeshPipelines, buffer_init};

/// What a forest mesh adds to its [`GpuMesh`].
pub(super) struct ForestGpu {
    /// What it can draw.
    pub detail: Detail,
    /// A leaf mesh's vertices with grown leaves ([`forest::GROWN`]), for far instances.
    grown: Option<wgpu::Buffer>,
    /// The matrices of the instances drawn, in the plan's order.
    instances: wgpu::Buffer,
    /// Instances the buffer can hold.
    capacity: usize,
    /// The draws of the plan drawn.
    draws: Vec<Draw>,
}

impl ForestGpu {
    /// The forest side of `mesh`: its detail, grown leaves, an instance buffer for all its
    /// instances, and no draws until a plan arrives.
    pub fn new(device: &wgpu::Device, mesh: &SceneMesh) -> ForestGpu {
        ForestGpu {
            grown: mesh.lod.as_ref().map(|lod| {
                buffer_init(
                    device,
                    "grown leaves",
                    bytemuck::cast_slice(&lod.grown(&mesh.vertices, forest::GROWN)),
                    wgpu::BufferUsages::VERTEX,
                )
            }),
            detail: match &mesh.lod {
                Some(lod) => Detail::leaves(lod),
                None => Detail::Rigid {
                    full: mesh.indices.len() as u32,
                    coarse: mesh
                        .coarse
                        .as_ref()
                        .map(|(_, c)| c.len() as u32)
                        .filter(|&c| c > 0),
                },
            },
            instances: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("forest instances"),
                size: std::mem::size_of_val(mesh.instances.as_slice()).max(64) as u64,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            capacity: mesh.instances.len(),
            draws: Vec::new(),
        }
    }

    /// Takes a plan's draws: `matrices` are its instances in order, of which the positions
    /// `changed` differ from what the buffer holds (only those are written). A plan with
    /// more instances than the mesh has (of another scene, which the planner never hands
    /// out: [`super::super::planner::Planner::reset`]) is refused: nothing is drawn.
    pub fn take_plan(
        &mut self,
        queue: &wgpu::Queue,
        matrices: &[[f32; 16]],
        changed: std::ops::Range<usize>,
        draws: Vec<Draw>,
    ) {
        if matrices.len() > self.capacity {
            self.draws.clear();
            return;
        }
        if let Some(part) = matrices.get(changed.clone())
            && !part.is_empty()
        {
            let offset = (changed.start * std::mem::size_of::<[f32; 16]>()) as u64;
            queue.write_buffer(&self.instances, offset, bytemuck::cast_slice(part));
        }
        self.draws = draws;
    }

    /// Issues the draws of the plan taken last and returns the triangles drawn. In
    /// wireframe, only the instances drawn whole show their edges.
    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        mesh: &GpuMesh,
        pipelines: MeshPipelines<'_>,
        toggles: Toggles,
    ) -> u64 {
        let pipeline = if mesh.double_sided {
            pipelines.double
        } else {
            pipelines.culled
        };
        pass.set_bind_group(1, &mesh.material, &[]);
        pass.set_vertex_buffer(1, self.instances.slice(..));
        let mut triangles = 0;
        for d in &self.draws {
            let (pipeline, vertices, indices, range) = match d.source {
                Source::Full if toggles.wireframe => match &mesh.edges {
                    Some((edges, n)) => (pipelines.lines, &mesh.vertices, edges, 0..*n),
                    None => continue,
                },
                _ if toggles.wireframe => continue,
                Source::Full => (pipeline, &mesh.vertices, &mesh.indices, d.indices.clone()),
                Source::Coarse => match &mesh.coarse {
                    Some((v, i, _)) => (pipeline, v, i, d.indices.clone()),
                    None => continue,
                },
                Source::Quads | Source::Grown => match (&mesh.lod, &self.grown) {
                    (Some((quads, colored, _)), grown) => {
                        let v = match (toggles.lod_colors, d.source, grown) {
                            (true, _, _) => colored,
                            (false, Source::Grown, Some(grown)) => grown,
                            _ => &mesh.vertices,
                        };
                        (pipeline, v, quads, d.indices.clone())
                    }
                    _ => continue,
                },
            };
            pass.set_pipeline(pipeline);
            pass.set_vertex_buffer(0, vertices.slice(..));
            pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
            if !toggles.wireframe {
                triangles += d.triangles();
            }
            pass.draw_indexed(range, 0, d.instances.clone());
        }
        triangles
    }
}
