//! The 3D viewport, drawn with wgpu into a texture that egui shows as an image.
//!
//! Drawing into our own texture (with its own depth buffer) keeps the model's frame apart
//! from egui's: the model is redrawn only when the camera, the model or a toggle changes, so
//! panel interaction stays fast even with a large tree on a software renderer.

use std::sync::Arc;

use eframe::egui;
use eframe::egui_wgpu::{self, wgpu};
use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

use super::scene::{Environment, Scene, SceneMesh, TextureData, VERTEX_FLOATS};

/// The viewport texture holds sRGB-encoded values in a plain format: egui samples every
/// texture as gamma-encoded colour. The shaders encode.
const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Model textures are sRGB images, decoded to linear when sampled for lighting.
const IMAGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
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
}

impl Default for Toggles {
    fn default() -> Self {
        Toggles {
            wireframe: false,
            skeleton: false,
            leaves: true,
            grid: true,
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
    source: Arc<Scene>,
    index_in_scene: usize,
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
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("pge preview"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shader.wgsl").into()),
        });
        let globals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("globals"),
            size: GLOBALS_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let uniform_entry = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let globals_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("globals"),
            entries: &[uniform_entry(0)],
        });
        let globals_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout: &globals_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals.as_entire_binding(),
            }],
        });
        let material_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("material"),
            entries: &[
                uniform_entry(0),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mesh"),
            bind_group_layouts: &[&globals_layout, &material_layout],
            push_constant_ranges: &[],
        });
        let line_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lines"),
            bind_group_layouts: &[&globals_layout],
            push_constant_ranges: &[],
        });
        let front_face = probe_front_face(&device, &queue, &shader);
        let f32x = |n: u64| n * 4;
        let vertex_attributes = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4
        ];
        let instance_attributes = wgpu::vertex_attr_array![
            4 => Float32x4, 5 => Float32x4, 6 => Float32x4, 7 => Float32x4
        ];
        let mesh_buffers = [
            wgpu::VertexBufferLayout {
                array_stride: f32x(VERTEX_FLOATS as u64),
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &vertex_attributes,
            },
            wgpu::VertexBufferLayout {
                array_stride: f32x(16),
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &instance_attributes,
            },
        ];
        let line_attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4];
        let line_buffers = [wgpu::VertexBufferLayout {
            array_stride: f32x(7),
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &line_attributes,
        }];
        let pipeline = |label: &str,
                        layout: &wgpu::PipelineLayout,
                        buffers: &[wgpu::VertexBufferLayout],
                        vs: &str,
                        fs: &str,
                        topology: wgpu::PrimitiveTopology,
                        cull: Option<wgpu::Face>,
                        depth: (bool, wgpu::CompareFunction),
                        blend: Option<wgpu::BlendState>| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: &shader,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology,
                    front_face,
                    cull_mode: cull,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: depth.0,
                    depth_compare: depth.1,
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: COLOR_FORMAT,
                        blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview: None,
                cache: None,
            })
        };
        use wgpu::CompareFunction::{Always, Less, LessEqual};
        use wgpu::PrimitiveTopology::{LineList, TriangleList};
        let alpha = Some(wgpu::BlendState::ALPHA_BLENDING);
        let mesh_culled = pipeline(
            "mesh",
            &layout,
            &mesh_buffers,
            "vs_mesh",
            "fs_mesh",
            TriangleList,
            Some(wgpu::Face::Back),
            (true, Less),
            None,
        );
        let mesh_double = pipeline(
            "mesh double-sided",
            &layout,
            &mesh_buffers,
            "vs_mesh",
            "fs_mesh",
            TriangleList,
            None,
            (true, Less),
            None,
        );
        let mesh_lines = pipeline(
            "mesh lines",
            &layout,
            &mesh_buffers,
            "vs_mesh",
            "fs_mesh_lines",
            LineList,
            None,
            (true, LessEqual),
            None,
        );
        let sky = pipeline(
            "sky",
            &layout,
            &[],
            "vs_sky",
            "fs_sky",
            TriangleList,
            None,
            (false, Always),
            None,
        );
        let overlay_depth = pipeline(
            "grid",
            &line_layout,
            &line_buffers,
            "vs_line",
            "fs_line",
            LineList,
            None,
            (false, LessEqual),
            alpha,
        );
        let overlay_top = pipeline(
            "skeleton",
            &line_layout,
            &line_buffers,
            "vs_line",
            "fs_line",
            LineList,
            None,
            (false, Always),
            alpha,
        );
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("base colour"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let sky_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("sky"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let white_data = TextureData {
            width: 1,
            height: 1,
            levels: vec![vec![255; 4]],
        };
        let white = upload_texture(&device, &queue, &white_data);
        Renderer {
            device,
            queue,
            globals,
            globals_group,
            material_layout,
            sampler,
            white,
            mesh_culled,
            mesh_double,
            mesh_lines,
            sky,
            sky_sampler,
            environment: None,
            overlay_depth,
            overlay_top,
            meshes: Vec::new(),
            grid: None,
            skeleton: None,
            target: None,
            texture_id: None,
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
            let cutoff = mesh.alpha_cutoff.unwrap_or(-1.0);
            let params = [cutoff, if mesh.double_sided { 1.0 } else { 0.0 }, 0.0, 0.0];
            let mut uniform = mesh.base_color.to_vec();
            uniform.extend_from_slice(&params);
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

    /// Draws the model seen by `view_proj` into a `size` pixel texture and returns the egui
    /// texture showing it. While the camera is `moving`, an eighth of the leaves and of a big
    /// bark mesh are drawn (software renderers cannot turn a 100 000-leaf tree smoothly
    /// otherwise).
    pub fn render(
        &mut self,
        egui_renderer: &mut egui_wgpu::Renderer,
        view_proj: Mat4,
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
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(1, &mesh.material, &[]);
                    pass.set_vertex_buffer(0, vertices.slice(..));
                    pass.set_vertex_buffer(1, mesh.instances.slice(..));
                    pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..count, 0, 0..mesh.instance_count);
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
        self.texture_id.unwrap_or_default()
    }

    /// The sky's bind group: the material layout with the sky image and a sampler that wraps
    /// around the horizon and clamps at the poles.
    fn sky_group(&self, env: &Environment) -> wgpu::BindGroup {
        let view = upload_texture(&self.device, &self.queue, &env.texture);
        let uniform = buffer_init(
            &self.device,
            "sky",
            bytemuck::cast_slice(&[1.0f32, 1.0, 1.0, 1.0, -1.0, 0.0, 0.0, 0.0]),
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

/// The front-face winding to declare so that triangles counter-clockwise in normalized
/// device coordinates (the glTF convention) are front faces.
///
/// wgpu promises that `FrontFace::Ccw` means exactly that, but its OpenGL backend flips the
/// image vertically when drawing into a texture, which mirrors the winding on some drivers
/// (seen with Mesa's llvmpipe): closed meshes then show their inside. One probe triangle,
/// read back once, tells which way this device goes.
fn probe_front_face(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    shader: &wgpu::ShaderModule,
) -> wgpu::FrontFace {
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("winding probe"),
        size: wgpu::Extent3d {
            width: 1,
            height: 1,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("winding probe"),
        bind_group_layouts: &[],
        push_constant_ranges: &[],
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("winding probe"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: shader,
            entry_point: Some("vs_probe"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState {
            front_face: wgpu::FrontFace::Ccw,
            ..Default::default()
        },
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: shader,
            entry_point: Some("fs_probe"),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        multiview: None,
        cache: None,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("winding probe"),
        size: 256,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let view = target.create_view(&Default::default());
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("winding probe"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                resolve_target: None,
                depth_slice: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::RED),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
        });
        pass.set_pipeline(&pipeline);
        pass.draw(0..3, 0..1);
    }
    encoder.copy_texture_to_buffer(
        target.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(256),
                rows_per_image: Some(1),
            },
        },
        wgpu::Extent3d {
            width: 1,
            height: 1,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);
    readback.map_async(wgpu::MapMode::Read, .., |_| {});
    let front = match device.poll(wgpu::PollType::wait_indefinitely()) {
        Ok(_) => readback.get_mapped_range(..).first().copied(),
        Err(_) => None,
    };
    // White: as promised; black: mirrored; anything else (the probe failed): trust wgpu.
    match front {
        Some(0) => wgpu::FrontFace::Cw,
        _ => wgpu::FrontFace::Ccw,
    }
}

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

fn upload_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    data: &TextureData,
) -> wgpu::TextureView {
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("base colour"),
        size: wgpu::Extent3d {
            width: data.width,
            height: data.height,
            depth_or_array_layers: 1,
        },
        mip_level_count: data.levels.len() as u32,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: IMAGE_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let (mut w, mut h) = (data.width, data.height);
    for (level, pixels) in data.levels.iter().enumerate() {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: level as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            pixels,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * w),
                rows_per_image: Some(h),
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        (w, h) = ((w / 2).max(1), (h / 2).max(1));
    }
    texture.create_view(&Default::default())
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
