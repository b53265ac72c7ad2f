//! The 3D viewport, drawn with wgpu into a texture that egui shows as an image.
//!
//! Drawing into our own texture (with its own depth buffer) keeps the model's frame apart
//! from egui's: the model is redrawn only when the camera, the model or a toggle changes, so
//! panel interaction stays fast even with a large tree on a software renderer.
//!
//! A mesh is uploaded once ([`mesh`]); a forest's meshes draw the plan the planner thread
//! made for a recent camera ([`forest`], [`super::planner`]); the grid and wireframe edges
//! are lines ([`overlay`]).

mod forest;
mod mesh;
mod overlay;

use std::sync::Arc;
use std::time::{Duration, Instant};

use eframe::egui;
use eframe::egui_wgpu::{self, wgpu};
use glam::{Mat4, Vec3};

use self::forest::ForestGpu;
use self::mesh::{GpuMesh, MeshPipelines, bind_material, buffer_init, material_group};
use self::overlay::grid_lines;
use super::forest::{MOVING_MARGIN, MOVING_SHARE, View};
use super::pipeline::{BindLayouts, COLOR_FORMAT, DEPTH_FORMAT, Pipelines, material_uniform};
use super::planner::{ForestSet, Planned, Planner, Request};
use super::scene::{Environment, Scene, TextureData};
use super::texture::{Samplers, upload_data_texture, upload_texture};

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
    /// as many triangles of bark); a moving frame draws a 128th of it ([`MOVING_SHARE`]).
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
            leaf_budget: super::forest::DEFAULT_LEAF_BUDGET,
        }
    }
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
    /// A flat normal, for materials without a normal map.
    flat_normal: wgpu::TextureView,
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
    meshes: Vec<Uploaded>,
    grid: Option<(wgpu::Buffer, u32)>,
    skeleton: Option<(wgpu::Buffer, u32)>,
    target: Option<Target>,
    texture_id: Option<egui::TextureId>,
    /// Triangles drawn by the last frame (lines not counted).
    triangles: u64,
    /// Leaves a forest's leaf meshes with levels drew in the last frame.
    forest_leaves: u64,
    /// Makes the forest's plans off the render thread.
    planner: Planner,
    /// The planner's plan that arrived but is not drawn yet.
    ready: Option<Planned>,
    /// Per entry of the planner's [`ForestSet`]: the index of its mesh in `meshes`.
    forest_meshes: Vec<usize>,
    /// The camera and budget of the last frame.
    last_request: Option<Request>,
    /// The centre of the model's bounds: camera motion is measured against the eye's
    /// distance to it.
    focus: Option<Vec3>,
    /// Where the last frame's time went.
    times: FrameTimes,
    /// Wait for the GPU after each frame, to measure its share ([`FrameTimes::gpu`]).
    measure_gpu: bool,
}

/// A mesh on the GPU and, for a mesh a forest places, its forest side (what it can draw,
/// its instances in the order of the plan drawn, and that plan's draws).
struct Uploaded {
    mesh: GpuMesh,
    forest: Option<ForestGpu>,
}

/// Where one frame's time went on the render thread (`--orbit-frames` prints them).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameTimes {
    /// Planning the forest's draws (culling, levels, bands) of the plan that arrived for
    /// this frame (zero if none did), on the planner thread.
    pub plan: Duration,
    /// Writing the changed instances of that plan into the instance buffers.
    pub upload: Duration,
    /// Instances written.
    pub uploaded: usize,
    /// Recording and submitting the draws.
    pub submit: Duration,
    /// Waiting for the GPU to finish them (measured only when asked:
    /// [`Renderer::measure_gpu`]).
    pub gpu: Duration,
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

impl Renderer {
    /// Creates the pipelines on egui's device; `wake` is called when a forest plan is ready
    /// to be drawn (to ask the window for a frame).
    #[must_use]
    pub fn new(state: &egui_wgpu::RenderState, wake: impl Fn() + Send + 'static) -> Renderer {
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
            flat_normal: samplers.flat_normal,
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
            planner: Planner::new(wake),
            ready: None,
            forest_meshes: Vec::new(),
            last_request: None,
            focus: None,
            times: FrameTimes::default(),
            measure_gpu: false,
        }
    }

    /// Makes every frame wait for the GPU to finish it, so that [`Renderer::times`] tells
    /// the GPU's share apart (for measurements; it slows frames down on a real GPU).
    pub fn measure_gpu(&mut self, on: bool) {
        self.measure_gpu = on;
    }

    /// Where the last frame's time went.
    #[must_use]
    pub fn times(&self) -> FrameTimes {
        self.times
    }

    /// Whether the last frame drew the forest plan made for its own camera and budget
    /// (a frame that did not is drawn again when that plan arrives: [`Renderer::plan_ready`]).
    #[must_use]
    pub fn settled(&self) -> bool {
        self.last_request
            .is_none_or(|r| self.ready.is_none() && self.planner.settled(&r))
    }

    /// Whether a forest plan arrived that is not drawn yet: the viewport should be redrawn.
    pub fn plan_ready(&mut self) -> bool {
        if self.ready.is_none() {
            self.ready = self.planner.poll();
        }
        self.ready.is_some()
    }

    /// Replaces the model on the GPU; plans made for the previous one are never drawn.
    pub fn upload(&mut self, scene: &Arc<Scene>) {
        self.environment = scene
            .environment
            .as_ref()
            .map(|env| (self.sky_group(env), ambient_tint(env.average)));
        let device = &self.device;
        let mut textures: Vec<(*const TextureData, wgpu::TextureView)> = Vec::new();
        let mut normals: Vec<(*const TextureData, wgpu::TextureView)> = Vec::new();
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
            let normal = match &mesh.normal_texture {
                Some(t) => match normals.iter().find(|(p, _)| *p == Arc::as_ptr(t)) {
                    Some((_, v)) => v.clone(),
                    None => {
                        let v = upload_data_texture(device, &self.queue, t);
                        normals.push((Arc::as_ptr(t), v.clone()));
                        v
                    }
                },
                None => self.flat_normal.clone(),
            };
            let material = material_group(
                device,
                &self.material_layout,
                mesh,
                &view,
                &self.sampler,
                &normal,
            );
            self.meshes.push(Uploaded {
                mesh: GpuMesh::new(device, scene, index, material),
                forest: mesh.forest.then(|| ForestGpu::new(device, mesh)),
            });
        }
        let (forest_meshes, set): (Vec<usize>, Vec<_>) = self
            .meshes
            .iter()
            .enumerate()
            .filter_map(|(k, u)| {
                let detail = u.forest.as_ref()?.detail.clone();
                Some((k, (u.mesh.index_in_scene, detail)))
            })
            .unzip();
        self.forest_meshes = forest_meshes;
        self.focus = scene.bounds.map(|(lo, hi)| (lo + hi) * 0.5);
        self.ready = None;
        self.planner
            .reset(Some(Arc::new(ForestSet::new(scene.clone(), set))));
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

    /// Draws `planned` from now on: its instances written to the forest meshes' buffers.
    fn take_plan(&mut self, planned: Planned) {
        if planned.epoch != self.planner.epoch() {
            return; // of an earlier scene (the planner drops those already)
        }
        let t0 = Instant::now();
        self.forest_leaves = planned.plan.leaves;
        self.times.plan = planned.took;
        let parts = planned
            .plan
            .meshes
            .into_iter()
            .zip(&planned.matrices)
            .zip(planned.changed);
        for (&k, ((p, matrices), changed)) in self.forest_meshes.iter().zip(parts) {
            if let Some(f) = self.meshes.get_mut(k).and_then(|u| u.forest.as_mut()) {
                self.times.uploaded += changed.len();
                f.take_plan(&self.queue, matrices, changed, p.draws);
            }
        }
        self.times.upload = t0.elapsed();
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
    /// the egui texture showing it. A forest's instances are drawn within its leaf budget,
    /// by the last plan the planner thread made ([`super::planner`]). While the camera is
    /// `moving`, an eighth of the leaves and of a big bark mesh are drawn (software
    /// renderers cannot turn a 100 000-leaf tree smoothly otherwise), and a forest a 128th
    /// of its budget ([`MOVING_SHARE`]).
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
            for u in &mut self.meshes {
                u.mesh.build_edges(&self.device);
            }
        }
        if moving {
            for u in &mut self.meshes {
                u.mesh.pick_near(&self.queue, view_proj);
            }
        }
        let budget = if moving {
            toggles.leaf_budget / MOVING_SHARE
        } else {
            toggles.leaf_budget
        };
        self.times = FrameTimes::default();
        // The plan that arrived last is drawn; the next is asked for this camera.
        if let Some(planned) = self.ready.take().or_else(|| self.planner.poll()) {
            self.take_plan(planned);
        }
        // A moving frame's plan is drawn a little later, by then turned a little.
        let plan_view_proj = if moving {
            Mat4::from_scale(Vec3::new(1.0 / MOVING_MARGIN, 1.0 / MOVING_MARGIN, 1.0)) * view_proj
        } else {
            view_proj
        };
        let request = Request {
            view: View {
                eye,
                view_proj: plan_view_proj,
            },
            budget,
        };
        // While moving, the plan asked for last is drawn on while the camera turns little.
        let focus = self.focus.map_or(1.0, |f| f.distance(eye));
        let reuse = moving
            && self
                .planner
                .asked()
                .is_some_and(|last| last.close_to(&request, focus));
        if !reuse {
            self.planner.ask(request);
        }
        self.last_request = Some(request);
        let t0 = Instant::now();
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
            let pipelines = MeshPipelines {
                culled: &self.mesh_culled,
                double: &self.mesh_double,
                lines: &self.mesh_lines,
            };
            for leaves_pass in [false, true] {
                for Uploaded { mesh, forest } in
                    self.meshes.iter().filter(|u| u.mesh.is_leaf == leaves_pass)
                {
                    if mesh.is_leaf && !toggles.leaves {
                        continue;
                    }
                    triangles += match forest {
                        Some(f) if !mesh.lines => f.draw(&mut pass, mesh, pipelines, toggles),
                        _ => mesh.draw(&mut pass, pipelines, toggles, moving),
                    };
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
        self.times.submit = t0.elapsed();
        if self.measure_gpu {
            let t0 = Instant::now();
            // A failed wait only spoils the measurement.
            let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
            self.times.gpu = t0.elapsed();
        }
        self.triangles = triangles;
        self.texture_id.unwrap_or_default()
    }

    /// The sky's bind group: the material layout with the sky image and a sampler that wraps
    /// around the horizon and clamps at the poles.
    fn sky_group(&self, env: &Environment) -> wgpu::BindGroup {
        let view = upload_texture(&self.device, &self.queue, &env.texture);
        bind_material(
            &self.device,
            &self.material_layout,
            "sky",
            &material_uniform([1.0; 4], None, false, None),
            &view,
            &self.sky_sampler,
            &self.flat_normal,
        )
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
}
