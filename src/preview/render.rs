//! The 3D viewport, drawn with wgpu into a texture that egui shows as an image.
//!
//! Drawing into our own texture (with its own depth buffer) keeps the model's frame apart
//! from egui's: the model is redrawn only when the camera, the model or a toggle changes, so
//! panel interaction stays fast even with a large tree on a software renderer.

use std::sync::Arc;

use eframe::egui;
use eframe::egui_wgpu::{self, wgpu};
use glam::{Mat4, Vec3, Vec4};
use wgpu::util::DeviceExt;

use super::forest::{self, Detail, Draw, ForestMesh, Source, View};
use super::pipeline::{BindLayouts, COLOR_FORMAT, DEPTH_FORMAT, Pipelines, material_uniform};
use super::scene::{Environment, Scene, SceneMesh, TextureData};
use super::texture::{Samplers, upload_texture};

/// Background without an environment, sRGB-encoded.
const CLEAR: wgpu::Color = wgpu::Color {
    r: 0.11,
    g: 0.12,
    b: 0.135,
    a: 1.0,
};

/// What to draw besides the meshes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Toggles {
    /// Triangle edges instead of filled triangles.
    pub wireframe: bool,
    /// The branch skeleton on top.
    pub skeleton: bool,
    /// Foliage meshes.
    pub leaves: bool,
    /// The ground grid.
    pub grid: bool,
    /// Percent of the leaves drawn of meshes with levels of detail (100: the finest level,
    /// the index buffer itself).
    pub lod_percent: u8,
    /// Leaves of meshes with levels of detail coloured by the level that created them.
    pub lod_colors: bool,
    /// A forest's leaf budget T: the most leaves its instances draw in a frame at rest (and
    /// as many triangles of bark); a moving frame draws a 32nd of it ([`forest::MOVING_SHARE`]).
    pub leaf_budget: u64,
}

impl Default for Toggles {
    fn default() -> Self {
        Toggles {
            wireframe: false,
            skeleton: false,
            leaves: true,
            grid: true,
            lod_percent: 100,
            lod_colors: false,
            leaf_budget: forest::DEFAULT_LEAF_BUDGET,
        }
    }
}

struct GpuMesh {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    instances: wgpu::Buffer,
    instance_count: u32,
    material: wgpu::BindGroup,
    lines: bool,
    double_sided: bool,
    is_leaf: bool,
    /// Edge list for the wireframe, built when first needed.
    edges: Option<(wgpu::Buffer, u32)>,
    /// An eighth of the leaves or the largest eighth of a big bark mesh (vertices, indices,
    /// index count), for frames drawn while the camera moves.
    coarse: Option<(wgpu::Buffer, wgpu::Buffer, u32)>,
    /// For leaves instanced by many trees (a forest's): the instances near the camera,
    /// rewritten for each moving frame, and how many there are; far trees' leaves are not
    /// drawn while the camera moves.
    near: Option<(wgpu::Buffer, u32)>,
    source: Arc<Scene>,
    index_in_scene: usize,
    /// Sequential quads over all of V, the vertices coloured by level and the LOD tables,
    /// for a leaf mesh with levels.
    lod: Option<(wgpu::Buffer, wgpu::Buffer, super::lod::LeafLod)>,
    /// For a mesh placed by a forest: what it can draw, the instances of this frame's plan
    /// (rewritten each frame, in band order) and the plan's draws.
    forest: Option<ForestGpu>,
}

struct ForestGpu {
    detail: Detail,
    /// A leaf mesh's vertices with grown leaves ([`forest::GROWN`]), for far instances.
    grown: Option<wgpu::Buffer>,
    instances: wgpu::Buffer,
    draws: Vec<Draw>,
}

struct Target {
    color: wgpu::Texture,
    depth: wgpu::TextureView,
    size: [u32; 2],
}

/// The renderer: pipelines, the uploaded model and the target texture.
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    globals: wgpu::Buffer,
    globals_group: wgpu::BindGroup,
    material_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    white: wgpu::TextureView,
    mesh_culled: wgpu::RenderPipeline,
    mesh_double: wgpu::RenderPipeline,
    mesh_lines: wgpu::RenderPipeline,
    sky: wgpu::RenderPipeline,
    sky_sampler: wgpu::Sampler,
    /// The environment's sky (its material bind group) and ambient factor, when the model
    /// has one.
    environment: Option<(wgpu::BindGroup, [f32; 3])>,
    overlay_depth: wgpu::RenderPipeline,
    overlay_top: wgpu::RenderPipeline,
    meshes: Vec<GpuMesh>,
    grid: Option<(wgpu::Buffer, u32)>,
    skeleton: Option<(wgpu::Buffer, u32)>,
    target: Option<Target>,
    texture_id: Option<egui::TextureId>,
    /// Triangles drawn by the last frame (lines not counted).
    triangles: u64,
    /// Leaves a forest's leaf meshes with levels drew in the last frame.
    forest_leaves: u64,
}

/// The buffer of the shader's `Globals` and its bind group (group 0).
fn globals_binding(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
) -> (wgpu::Buffer, wgpu::BindGroup) {
    let globals = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("globals"),
        size: GLOBALS_BYTES,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let globals_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("globals"),
        layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: globals.as_entire_binding(),
        }],
    });
    (globals, globals_group)
}

fn buffer_init(
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

impl Renderer {
    /// Creates the pipelines on egui's device.
    #[must_use]
    pub fn new(state: &egui_wgpu::RenderState) -> Renderer {
        let device = state.device.clone();
        let queue = state.queue.clone();
        let layouts = BindLayouts::new(&device);
        let (globals, globals_group) = globals_binding(&device, &layouts.globals);
        let Pipelines {
            mesh_culled,
            mesh_double,
            mesh_lines,
            sky,
            overlay_depth,
            overlay_top,
        } = Pipelines::new(&device, &queue, &layouts);
        let samplers = Samplers::new(&device, &queue);
        Renderer {
            device,
            queue,
            globals,
            globals_group,
            material_layout: layouts.material,
            sampler: samplers.material,
            white: samplers.white,
            mesh_culled,
            mesh_double,
            mesh_lines,
            sky,
            sky_sampler: samplers.sky,
            environment: None,
            overlay_depth,
            overlay_top,
            meshes: Vec::new(),
            grid: None,
            skeleton: None,
            target: None,
            texture_id: None,
            triangles: 0,
            forest_leaves: 0,
        }
    }

    /// Replaces the model on the GPU.
    pub fn upload(&mut self, scene: &Arc<Scene>) {
        self.environment = scene
            .environment
            .as_ref()
            .map(|env| (self.sky_group(env), ambient_tint(env.average)));
        let device = &self.device;
        let mut textures: Vec<(*const TextureData, wgpu::TextureView)> = Vec::new();
        self.meshes.clear();
        for (index, mesh) in scene.meshes.iter().enumerate() {
            let view = match &mesh.texture {
                Some(t) => match textures.iter().find(|(p, _)| *p == Arc::as_ptr(t)) {
                    Some((_, v)) => v.clone(),
                    None => {
                        let v = upload_texture(device, &self.queue, t);
                        textures.push((Arc::as_ptr(t), v.clone()));
                        v
                    }
                },
                None => self.white.clone(),
            };
            let uniform = material_uniform(
                mesh.base_color,
                mesh.alpha_cutoff,
                mesh.double_sided,
                mesh.transmission,
            );
            let uniform = buffer_init(
                device,
                "material",
                bytemuck::cast_slice(&uniform),
                wgpu::BufferUsages::UNIFORM,
            );
            let material = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("material"),
                layout: &self.material_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: uniform.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::Sampler(&self.sampler),
                    },
                ],
            });
            self.meshes.push(GpuMesh {
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
                forest: mesh.forest.then(|| ForestGpu {
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
                    draws: Vec::new(),
                }),
                near: (mesh.is_leaf && !mesh.forest && mesh.instances.len() >= FAR_LEAVES_MIN)
                    .then(|| {
                        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                            label: Some("near instances"),
                            size: std::mem::size_of_val(mesh.instances.as_slice()) as u64,
                            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                            mapped_at_creation: false,
                        });
                        (buffer, 0)
                    }),
                source: scene.clone(),
                index_in_scene: index,
            });
        }
        let lines = |label: &str, data: Vec<f32>| {
            (!data.is_empty()).then(|| {
                let count = (data.len() / 7) as u32;
                (
                    buffer_init(
                        device,
                        label,
                        bytemuck::cast_slice(&data),
                        wgpu::BufferUsages::VERTEX,
                    ),
                    count,
                )
            })
        };
        self.grid = lines("grid", grid_lines(scene.bounds));
        let skeleton: Vec<f32> = scene
            .skeleton
            .iter()
            .flat_map(|p| [p[0], p[1], p[2], 1.0, 0.55, 0.1, 0.9])
            .collect();
        self.skeleton = lines("skeleton", skeleton);
    }

    /// For a moving frame: the instances of many-times-instanced leaves (a forest's) that
    /// are in view and in the nearest [`NEAR_FRACTION`] of their depth range.
    fn pick_near(&mut self, view_proj: Mat4) {
        for mesh in &mut self.meshes {
            let Some((buffer, count)) = &mut mesh.near else {
                continue;
            };
            let Some(all) = mesh.source.meshes.get(mesh.index_in_scene) else {
                continue;
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
                self.queue
                    .write_buffer(buffer, 0, bytemuck::cast_slice(&near));
            }
            *count = near.len() as u32;
        }
    }

    /// Plans the forest meshes' draws for `view` within `leaf_budget`
    /// ([`forest::plan`]) and writes each one's instances in band order.
    fn plan_forest(&mut self, view: &View, leaf_budget: u64) {
        let (meshes, sources): (Vec<ForestMesh>, Vec<usize>) = self
            .meshes
            .iter()
            .enumerate()
            .filter_map(|(k, m)| {
                let f = m.forest.as_ref()?;
                let scene = m.source.meshes.get(m.index_in_scene)?;
                Some((
                    ForestMesh {
                        instances: &scene.instances,
                        centre: scene.sphere.0,
                        radius: scene.sphere.1,
                        detail: &f.detail,
                    },
                    k,
                ))
            })
            .unzip();
        if meshes.is_empty() {
            return;
        }
        let plan = forest::plan(&meshes, view, leaf_budget);
        self.forest_leaves = plan.leaves;
        let matrices: Vec<Vec<[f32; 16]>> = meshes
            .iter()
            .zip(&plan.meshes)
            .map(|(m, p)| p.order.iter().map(|&i| m.instances[i as usize]).collect())
            .collect();
        drop(meshes);
        for ((k, p), matrices) in sources.into_iter().zip(plan.meshes).zip(matrices) {
            let mesh = &mut self.meshes[k];
            if let Some(f) = &mut mesh.forest {
                if !matrices.is_empty() {
                    self.queue
                        .write_buffer(&f.instances, 0, bytemuck::cast_slice(&matrices));
                }
                f.draws = p.draws;
            }
        }
    }

    /// Triangles drawn by the last frame, over every mesh and instance (lines not counted).
    #[must_use]
    pub fn triangles(&self) -> u64 {
        self.triangles
    }

    /// Leaves drawn by a forest's leaf meshes with levels in the last frame.
    #[must_use]
    pub fn forest_leaves(&self) -> u64 {
        self.forest_leaves
    }

    /// Draws the model seen by `view_proj` from `eye` into a `size` pixel texture and returns
    /// the egui texture showing it. A forest's instances are drawn within its leaf budget
    /// ([`forest::plan`]). While the camera is `moving`, an eighth of the leaves and of a big
    /// bark mesh are drawn (software renderers cannot turn a 100 000-leaf tree smoothly
    /// otherwise), and a forest a 32nd of its budget.
    pub fn render(
        &mut self,
        egui_renderer: &mut egui_wgpu::Renderer,
        view_proj: Mat4,
        eye: Vec3,
        size: [u32; 2],
        toggles: Toggles,
        moving: bool,
    ) -> egui::TextureId {
        let size = [size[0].max(1), size[1].max(1)];
        if self.target.as_ref().is_none_or(|t| t.size != size) {
            self.target = Some(self.make_target(size));
            let color_view = self
                .target
                .as_ref()
                .map(|t| t.color.create_view(&Default::default()));
            if let Some(view) = color_view {
                match self.texture_id {
                    Some(id) => egui_renderer.update_egui_texture_from_wgpu_texture(
                        &self.device,
                        &view,
                        wgpu::FilterMode::Linear,
                        id,
                    ),
                    None => {
                        self.texture_id = Some(egui_renderer.register_native_texture(
                            &self.device,
                            &view,
                            wgpu::FilterMode::Linear,
                        ));
                    }
                }
            }
        }
        if toggles.wireframe {
            self.build_edges();
        }
        if moving {
            self.pick_near(view_proj);
        }
        let budget = if moving {
            toggles.leaf_budget / forest::MOVING_SHARE
        } else {
            toggles.leaf_budget
        };
        self.plan_forest(&View { eye, view_proj }, budget);
        let mut triangles = 0u64;
        let sun = Vec3::new(0.45, 0.8, 0.35).normalize();
        let ambient = self.environment.as_ref().map_or([1.0; 3], |(_, a)| *a);
        let mut globals = view_proj.to_cols_array().to_vec();
        globals.extend_from_slice(&[sun.x, sun.y, sun.z, 0.0]);
        globals.extend_from_slice(&view_proj.inverse().to_cols_array());
        globals.extend_from_slice(&[ambient[0], ambient[1], ambient[2], 1.0]);
        self.queue
            .write_buffer(&self.globals, 0, bytemuck::cast_slice(&globals));
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("pge preview"),
            });
        if let Some(target) = &self.target {
            let color = target.color.create_view(&Default::default());
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("viewport"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &color,
                    resolve_target: None,
                    depth_slice: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(CLEAR),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &target.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
            });
            pass.set_bind_group(0, &self.globals_group, &[]);
            if let Some((sky, _)) = &self.environment {
                pass.set_pipeline(&self.sky);
                pass.set_bind_group(1, sky, &[]);
                pass.draw(0..3, 0..1);
            }
            // Opaque first, then foliage.
            for leaves_pass in [false, true] {
                for mesh in self.meshes.iter().filter(|m| m.is_leaf == leaves_pass) {
                    if mesh.is_leaf && !toggles.leaves {
                        continue;
                    }
                    if let Some(f) = &mesh.forest
                        && !mesh.lines
                    {
                        let pipelines = (&self.mesh_culled, &self.mesh_double, &self.mesh_lines);
                        triangles += draw_forest(&mut pass, mesh, f, pipelines, toggles);
                        continue;
                    }
                    let mut vertices = &mesh.vertices;
                    let (pipeline, indices, count) = if mesh.lines {
                        (&self.mesh_lines, &mesh.indices, mesh.index_count)
                    } else if toggles.wireframe {
                        match &mesh.edges {
                            Some((edges, n)) => (&self.mesh_lines, edges, *n),
                            None => continue,
                        }
                    } else {
                        let pipeline = if mesh.double_sided {
                            &self.mesh_double
                        } else {
                            &self.mesh_culled
                        };
                        match (&mesh.coarse, moving) {
                            (Some((coarse_vertices, coarse, n)), true) => {
                                vertices = coarse_vertices;
                                (pipeline, coarse, *n)
                            }
                            _ => (pipeline, &mesh.indices, mesh.index_count),
                        }
                    };
                    if count == 0 {
                        continue;
                    }
                    // A coarser level of detail, or leaves coloured by level: the two ranges
                    // of V per sector over the sequential quads.
                    if let Some((quads, colored, lod)) = &mesh.lod
                        && (toggles.lod_percent < 100 || toggles.lod_colors)
                        && !toggles.wireframe
                        && std::ptr::eq(vertices, &mesh.vertices)
                    {
                        let vertices = if toggles.lod_colors {
                            colored
                        } else {
                            vertices
                        };
                        pass.set_pipeline(pipeline);
                        pass.set_bind_group(1, &mesh.material, &[]);
                        pass.set_vertex_buffer(0, vertices.slice(..));
                        pass.set_vertex_buffer(1, mesh.instances.slice(..));
                        pass.set_index_buffer(quads.slice(..), wgpu::IndexFormat::Uint32);
                        for range in lod.index_ranges(toggles.lod_percent) {
                            triangles +=
                                u64::from(range.len() as u32 / 3) * u64::from(mesh.instance_count);
                            pass.draw_indexed(range, 0, 0..mesh.instance_count);
                        }
                        continue;
                    }
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(1, &mesh.material, &[]);
                    pass.set_vertex_buffer(0, vertices.slice(..));
                    let (instances, instance_count) = match &mesh.near {
                        Some((near, n)) if moving && !toggles.wireframe => (near, *n),
                        _ => (&mesh.instances, mesh.instance_count),
                    };
                    if instance_count == 0 {
                        continue;
                    }
                    pass.set_vertex_buffer(1, instances.slice(..));
                    pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                    if !mesh.lines && !toggles.wireframe {
                        triangles += u64::from(count / 3) * u64::from(instance_count);
                    }
                    pass.draw_indexed(0..count, 0, 0..instance_count);
                }
            }
            if toggles.grid
                && let Some((grid, n)) = &self.grid
            {
                pass.set_pipeline(&self.overlay_depth);
                pass.set_vertex_buffer(0, grid.slice(..));
                pass.draw(0..*n, 0..1);
            }
            if toggles.skeleton
                && let Some((lines, n)) = &self.skeleton
            {
                pass.set_pipeline(&self.overlay_top);
                pass.set_vertex_buffer(0, lines.slice(..));
                pass.draw(0..*n, 0..1);
            }
        }
        self.queue.submit([encoder.finish()]);
        self.triangles = triangles;
        self.texture_id.unwrap_or_default()
    }

    /// The sky's bind group: the material layout with the sky image and a sampler that wraps
    /// around the horizon and clamps at the poles.
    fn sky_group(&self, env: &Environment) -> wgpu::BindGroup {
        let view = upload_texture(&self.device, &self.queue, &env.texture);
        let uniform = buffer_init(
            &self.device,
            "sky",
            bytemuck::cast_slice(&material_uniform([1.0; 4], None, false, None)),
            wgpu::BufferUsages::UNIFORM,
        );
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sky"),
            layout: &self.material_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&self.sky_sampler),
                },
            ],
        })
    }

    fn make_target(&self, size: [u32; 2]) -> Target {
        let extent = wgpu::Extent3d {
            width: size[0],
            height: size[1],
            depth_or_array_layers: 1,
        };
        let texture = |label, format, usage| {
            self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: extent,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let color = texture(
            "viewport colour",
            COLOR_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let depth = texture(
            "viewport depth",
            DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        )
        .create_view(&Default::default());
        Target { color, depth, size }
    }

    fn build_edges(&mut self) {
        for mesh in &mut self.meshes {
            if mesh.edges.is_some() || mesh.lines {
                continue;
            }
            let source: &SceneMesh = &mesh.source.meshes[mesh.index_in_scene];
            let edges = triangle_edges(&source.indices);
            let buffer = buffer_init(
                &self.device,
                "edges",
                index_bytes(&edges),
                wgpu::BufferUsages::INDEX,
            );
            mesh.edges = Some((buffer, edges.len() as u32));
        }
    }
}

/// Issues the draws of a forest mesh's plan (the instances were written by
/// [`Renderer::plan_forest`]) and returns the triangles drawn. In wireframe, only the
/// instances drawn whole show their edges.
fn draw_forest(
    pass: &mut wgpu::RenderPass<'_>,
    mesh: &GpuMesh,
    f: &ForestGpu,
    (culled, double, lines): (
        &wgpu::RenderPipeline,
        &wgpu::RenderPipeline,
        &wgpu::RenderPipeline,
    ),
    toggles: Toggles,
) -> u64 {
    let pipeline = if mesh.double_sided { double } else { culled };
    pass.set_bind_group(1, &mesh.material, &[]);
    pass.set_vertex_buffer(1, f.instances.slice(..));
    let mut triangles = 0;
    for d in &f.draws {
        let (pipeline, vertices, indices, range) = match d.source {
            Source::Full if toggles.wireframe => match &mesh.edges {
                Some((edges, n)) => (lines, &mesh.vertices, edges, 0..*n),
                None => continue,
            },
            _ if toggles.wireframe => continue,
            Source::Full => (pipeline, &mesh.vertices, &mesh.indices, d.indices.clone()),
            Source::Coarse => match &mesh.coarse {
                Some((v, i, _)) => (pipeline, v, i, d.indices.clone()),
                None => continue,
            },
            Source::Quads | Source::Grown => match (&mesh.lod, &f.grown) {
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

/// Leaves instanced at least this many times (a forest's) are drawn for near trees only
/// while the camera moves.
const FAR_LEAVES_MIN: usize = 256;

/// The share of their depth range, from the nearest, where such leaves are drawn while the
/// camera moves.
const NEAR_FRACTION: f32 = 0.3;

/// Bytes of the shader's `Globals`: view_proj, sun, inv_view_proj, ambient.
const GLOBALS_BYTES: u64 = (16 + 4 + 16 + 4) * 4;

/// The ambient light's factor under a sky of linear average colour `average`: half neutral,
/// half the sky's hue at unchanged brightness (so a blue sky cools the shadows, a sunset
/// warms them, and a dark sky does not black them out).
#[must_use]
pub fn ambient_tint(average: [f32; 3]) -> [f32; 3] {
    let luma = 0.2126 * average[0] + 0.7152 * average[1] + 0.0722 * average[2];
    average.map(|c| 0.5 + 0.5 * (c / luma.max(0.05)).min(2.5))
}

/// wgpu refuses empty buffers; an empty index list still gets one (unused) index.
fn index_bytes(indices: &[u32]) -> &[u8] {
    if indices.is_empty() {
        bytemuck::cast_slice(&[0u32])
    } else {
        bytemuck::cast_slice(indices)
    }
}

/// The three edges of every triangle as line pairs (shared edges are drawn twice, which
/// costs less than finding them).
#[must_use]
pub fn triangle_edges(indices: &[u32]) -> Vec<u32> {
    indices
        .chunks_exact(3)
        .flat_map(|t| [t[0], t[1], t[1], t[2], t[2], t[0]])
        .collect()
}

/// A ground grid on y = 0 around the model's footprint: lines as `[x, y, z, r, g, b, a]`,
/// spaced by a power of ten that gives 2 to 20 cells from the centre to the edge, every
/// tenth line brighter;
/// the X axis red and the Z axis blue.
#[must_use]
pub fn grid_lines(bounds: Option<(Vec3, Vec3)>) -> Vec<f32> {
    let (lo, hi) = bounds.unwrap_or((Vec3::splat(-1.0), Vec3::splat(1.0)));
    let half = ((hi - lo).length() * 0.75).max(1.0);
    let spacing = 10f32.powf((half / 2.0).log10().floor());
    let centre = (lo + hi) * 0.5;
    let n = (half / spacing).ceil() as i64;
    let (cx, cz) = (
        (centre.x / spacing).round() as i64,
        (centre.z / spacing).round() as i64,
    );
    let mut out = Vec::new();
    let mut line = |a: [f32; 3], b: [f32; 3], c: [f32; 4]| {
        out.extend_from_slice(&[a[0], a[1], a[2], c[0], c[1], c[2], c[3]]);
        out.extend_from_slice(&[b[0], b[1], b[2], c[0], c[1], c[2], c[3]]);
    };
    let (x0, x1) = ((cx - n) as f32 * spacing, (cx + n) as f32 * spacing);
    let (z0, z1) = ((cz - n) as f32 * spacing, (cz + n) as f32 * spacing);
    for i in -n..=n {
        let (x, z) = ((cx + i) as f32 * spacing, (cz + i) as f32 * spacing);
        let colour = |k: i64, axis: [f32; 4]| {
            if k == 0 {
                axis
            } else if k % 10 == 0 {
                [0.5, 0.5, 0.5, 0.6]
            } else {
                [0.3, 0.3, 0.3, 0.45]
            }
        };
        line(
            [x, 0.0, z0],
            [x, 0.0, z1],
            colour(cx + i, [0.2, 0.3, 0.9, 0.9]),
        );
        line(
            [x0, 0.0, z],
            [x1, 0.0, z],
            colour(cz + i, [0.9, 0.2, 0.2, 0.9]),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ambient_tint_follows_the_skys_hue() {
        let grey = ambient_tint([0.3, 0.3, 0.3]);
        assert!(grey.iter().all(|c| (c - 1.0).abs() < 1e-5), "{grey:?}");
        let blue = ambient_tint([0.1, 0.2, 0.6]);
        assert!(blue[2] > 1.2 && blue[0] < 0.9, "{blue:?}");
        let black = ambient_tint([0.0; 3]);
        assert_eq!(black, [0.5; 3]);
    }

    #[test]
    fn edges_of_two_triangles() {
        assert_eq!(
            triangle_edges(&[0, 1, 2, 2, 1, 3]),
            vec![0, 1, 1, 2, 2, 0, 2, 1, 1, 3, 3, 2]
        );
    }

    #[test]
    fn the_grid_scales_with_the_model_and_marks_the_axes() {
        let small = grid_lines(Some((Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 3.0, 1.0))));
        let big = grid_lines(Some((
            Vec3::new(-100.0, 0.0, -100.0),
            Vec3::new(100.0, 30.0, 100.0),
        )));
        let lines = |g: &[f32]| g.len() / 14;
        assert!((10..=110).contains(&lines(&small)), "{}", lines(&small));
        assert!((10..=110).contains(&lines(&big)), "{}", lines(&big));
        assert!(small.chunks(7).all(|v| v[1] == 0.0), "on the ground");
        // The Z axis line (x = 0) is blue.
        let z_axis = small
            .chunks(14)
            .find(|l| l[0] == 0.0 && l[7] == 0.0)
            .expect("axis line");
        assert_eq!(&z_axis[3..7], &[0.2, 0.3, 0.9, 0.9]);
    }
}
