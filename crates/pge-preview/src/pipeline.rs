//! The viewport's render pipelines: bind group layouts, vertex layouts, the shader's entry
//! points per pipeline and the probe of the device's front-face winding.

use eframe::egui_wgpu::wgpu;
use pge_engine::geometry::DiffuseTransmission;

use crate::VERTEX_FLOATS;

/// The viewport texture holds sRGB-encoded values in a plain format: egui samples every
/// texture as gamma-encoded colour. The shaders encode.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// The viewport's depth buffer.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The material uniform of the mesh shader (`Material` in shader.wgsl), three vec4s: the
/// base colour factor; the alpha cutoff (negative: none) and 1 when double-sided; the tint of
/// back faces (rgb) and the share of the sun behind a face that shines through it (w), from
/// the material's diffuse transmission (leaves), white and 0 without one. The shader
/// multiplies a back face's colour by the tint, so a leaf's underside is told from its top
/// in the preview as in a client that reads `KHR_materials_diffuse_transmission`.
#[must_use]
pub fn material_uniform(
    base_color: [f32; 4],
    alpha_cutoff: Option<f32>,
    double_sided: bool,
    transmission: Option<DiffuseTransmission>,
) -> [f32; 12] {
    let [r, g, b, a] = base_color;
    let sided = if double_sided { 1.0 } else { 0.0 };
    let (tint, through) = match transmission {
        Some(t) => (t.color, t.factor.clamp(0.0, 1.0)),
        None => ([1.0; 3], 0.0),
    };
    [
        r,
        g,
        b,
        a,
        alpha_cutoff.unwrap_or(-1.0),
        sided,
        0.0,
        0.0,
        tint[0],
        tint[1],
        tint[2],
        through,
    ]
}

/// The bind group layouts: group 0 the globals, group 1 a material (uniform, base colour
/// texture, sampler, normal map).
pub struct BindLayouts {
    /// Group 0: the `Globals` uniform.
    pub globals: wgpu::BindGroupLayout,
    /// Group 1: a material's uniform, texture and sampler.
    pub material: wgpu::BindGroupLayout,
}

impl BindLayouts {
    /// Creates both layouts.
    #[must_use]
    pub fn new(device: &wgpu::Device) -> BindLayouts {
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
        let texture_entry = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let globals_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("globals"),
            entries: &[uniform_entry(0)],
        });
        let material_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("material"),
            entries: &[
                uniform_entry(0),
                texture_entry(1),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
                texture_entry(3),
            ],
        });
        BindLayouts {
            globals: globals_layout,
            material: material_layout,
        }
    }
}

/// Every pipeline the viewport draws with.
pub struct Pipelines {
    /// Meshes with back faces culled.
    pub mesh_culled: wgpu::RenderPipeline,
    /// Double-sided meshes (leaves).
    pub mesh_double: wgpu::RenderPipeline,
    /// Line meshes and the wireframe.
    pub mesh_lines: wgpu::RenderPipeline,
    /// The environment's sky behind everything.
    pub sky: wgpu::RenderPipeline,
    /// Overlay lines hidden by the model (the ground grid).
    pub overlay_depth: wgpu::RenderPipeline,
    /// Overlay lines drawn on top (the skeleton).
    pub overlay_top: wgpu::RenderPipeline,
}

impl Pipelines {
    /// Compiles the shader and creates the pipelines, with the front-face winding this
    /// device needs (see [`probe_front_face`]).
    #[must_use]
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, layouts: &BindLayouts) -> Pipelines {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("pge preview"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shader.wgsl").into()),
        });
        let globals_layout = &layouts.globals;
        let material_layout = &layouts.material;
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mesh"),
            bind_group_layouts: &[globals_layout, material_layout],
            push_constant_ranges: &[],
        });
        let line_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lines"),
            bind_group_layouts: &[globals_layout],
            push_constant_ranges: &[],
        });
        let front_face = probe_front_face(device, queue, &shader);
        let f32x = |n: u64| n * 4;
        let vertex_attributes = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4, 8 => Float32x4
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
        Pipelines {
            mesh_culled,
            mesh_double,
            mesh_lines,
            sky,
            overlay_depth,
            overlay_top,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The colour factor the shader applies to a face: the back tint on back faces (see
    /// `fs_mesh` in shader.wgsl), white on front faces.
    fn face_factor(uniform: &[f32; 12], front: bool) -> [f32; 3] {
        if front {
            [1.0; 3]
        } else {
            [uniform[8], uniform[9], uniform[10]]
        }
    }

    #[test]
    fn back_faces_of_leaves_are_tinted_and_lit_through() {
        let leaf = DiffuseTransmission {
            factor: 0.4,
            color: [0.6, 0.8, 0.2],
        };
        let u = material_uniform([1.0, 0.5, 0.25, 1.0], Some(0.5), true, Some(leaf));
        assert_eq!(&u[..6], &[1.0, 0.5, 0.25, 1.0, 0.5, 1.0]);
        assert_eq!(face_factor(&u, true), [1.0; 3]);
        assert_eq!(
            face_factor(&u, false),
            [0.6, 0.8, 0.2],
            "the back face's own tint"
        );
        assert_eq!(u[11], 0.4, "sunlight through the leaf");
        // Without transmission both faces shade alike and nothing shines through.
        let plain = material_uniform([1.0; 4], None, true, None);
        assert_eq!(face_factor(&plain, false), face_factor(&plain, true));
        assert_eq!((plain[4], plain[11]), (-1.0, 0.0));
        // The shader reads the tint and the transmitted light from this uniform.
        let shader = include_str!("shader.wgsl");
        assert!(
            shader.contains("back: vec4<f32>"),
            "the uniform's third vec4"
        );
        assert!(shader.contains("select(m.back.rgb, vec3<f32>(1.0), front)"));
        assert!(shader.contains("m.back.w"));
    }
}
