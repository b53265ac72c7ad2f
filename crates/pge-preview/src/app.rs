//! The window: side panel, viewport, input, screenshot.

use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use eframe::egui::{self, Color32};
use pge_engine::{Engine, ParamValue};

use self::motion::{Frame, MOTION_SETTLE, Motion};
use self::orbit::Orbit;
use super::camera::OrbitCamera;
use super::live::Live;
use super::reload::{Settings, Status};
use super::render::{Renderer, Toggles};

mod motion;
mod orbit;
mod panel;

const ERROR_COLOR: Color32 = Color32::from_rgb(255, 110, 100);

/// How a `--screenshot` run ended, read after the window closed.
pub type ScreenshotResult = Arc<Mutex<Option<anyhow::Result<()>>>>;

/// Options of the window besides the script's settings.
pub struct AppOptions {
    /// Percent of the leaves drawn of trees with levels of detail (`--lod-level`).
    pub lod_percent: u8,
    /// A forest's leaf budget (`--leaf-budget`).
    pub leaf_budget: u64,
    /// Write the first complete frame here and close.
    pub screenshot: Option<PathBuf>,
    /// Where the screenshot run's result goes.
    pub screenshot_result: ScreenshotResult,
    /// Print frames per second to stderr every second (for measurements).
    pub log_fps: bool,
    /// Start with the turntable on.
    pub turntable: bool,
    /// Draw moving frames at full quality too (for measurements).
    pub full_quality_motion: bool,
    /// Where `--camera` places the camera once the first model is framed.
    pub camera: Option<super::CameraSpec>,
    /// `--orbit-frames N`: turn once around the model in N moving frames, then rest,
    /// printing where each frame's time went.
    pub orbit_frames: Option<u32>,
    /// The export button's writer; `None`: no export section.
    pub export: Option<crate::ExportFn>,
}

enum Shot {
    /// Waiting for the first generation and its frame.
    Waiting,
    /// Asked egui for the screenshot of this frame, which drew these triangles and forest
    /// leaves (the picture arrives a few frames later: what those draw is not in it).
    Requested { triangles: u64, leaves: u64 },
    /// Written (or failed); closing.
    Done,
}

/// The preview application.
pub struct PreviewApp {
    live: Live,
    renderer: Option<Renderer>,
    uploaded: u64,
    camera: OrbitCamera,
    /// `--camera`, applied when the first model is framed.
    camera_spec: Option<super::CameraSpec>,
    framed: bool,
    toggles: Toggles,
    turntable: bool,
    viewport_dirty: bool,
    last_viewport: Option<([u32; 2], OrbitCamera, Toggles)>,
    texture: Option<egui::TextureId>,
    edits: BTreeMap<String, ParamValue>,
    text_edits: BTreeMap<String, String>,
    total_steps: Option<u32>,
    /// The step scrubber advances by itself after each generation.
    playing: bool,
    /// The export button's writer, if the host gave one.
    export: Option<crate::ExportFn>,
    export_path: String,
    export_message: Option<Result<String, String>>,
    shown_error: Option<String>,
    shot: Option<(PathBuf, Shot)>,
    shot_result: ScreenshotResult,
    frames: VecDeque<Instant>,
    render_ms: f64,
    log_fps: bool,
    last_fps_log: Instant,
    /// A model caused by a save was drawn in the last frame: (save time, generation count).
    drawn_after_save: Option<(Instant, u64)>,
    /// When the camera moved, and whether a frame is a moving one.
    motion: Motion,
    /// Save to first frame on screen of the latest model a save caused.
    save_to_screen: Option<Duration>,
    /// The `--orbit-frames` measurement, while it runs.
    orbit: Option<Orbit>,
}

impl PreviewApp {
    /// Starts the worker and the watcher; the first generation starts at the first frame.
    pub fn new(
        cc: &eframe::CreationContext<'_>,
        engine: Engine,
        script: PathBuf,
        settings: Settings,
        options: AppOptions,
    ) -> anyhow::Result<PreviewApp> {
        let wake = cc.egui_ctx.clone();
        let live = Live::start(Arc::new(engine), script.clone(), settings, move || {
            wake.request_repaint()
        })?;
        let wake = cc.egui_ctx.clone();
        let mut renderer = cc
            .wgpu_render_state
            .as_ref()
            .map(|state| Renderer::new(state, move || wake.request_repaint()));
        if let Some(r) = &mut renderer {
            r.measure_gpu(options.orbit_frames.is_some());
        }
        let export_path = script.with_extension("glb").to_string_lossy().into_owned();
        Ok(PreviewApp {
            live,
            renderer,
            uploaded: 0,
            camera: OrbitCamera::default(),
            camera_spec: options.camera,
            framed: false,
            toggles: Toggles {
                lod_percent: options.lod_percent,
                leaf_budget: options.leaf_budget,
                ..Toggles::default()
            },
            turntable: options.turntable,
            viewport_dirty: true,
            last_viewport: None,
            texture: None,
            edits: BTreeMap::new(),
            text_edits: BTreeMap::new(),
            total_steps: None,
            playing: false,
            export: options.export,
            export_path,
            export_message: None,
            shown_error: None,
            shot: options.screenshot.map(|p| (p, Shot::Waiting)),
            shot_result: options.screenshot_result,
            frames: VecDeque::new(),
            render_ms: 0.0,
            log_fps: options.log_fps,
            motion: Motion::new(options.full_quality_motion),
            last_fps_log: Instant::now(),
            drawn_after_save: None,
            save_to_screen: None,
            orbit: options.orbit_frames.map(Orbit::new),
        })
    }

    /// File events, worker reports, new requests, the watch list.
    fn pump(&mut self) {
        self.live.pump(Instant::now());
        self.play();
        match self.live.reloader().status() {
            Status::Error(message) if self.shown_error.as_ref() != Some(message) => {
                // A screenshot or orbit run reports its error when the window closes.
                if self.shot.is_none() && self.orbit.is_none() {
                    eprintln!("{message}");
                }
                self.shown_error = Some(message.clone());
            }
            Status::Ready => self.shown_error = None,
            _ => {}
        }
        if self.uploaded != self.live.reloader().generation_count() {
            self.uploaded = self.live.reloader().generation_count();
            if let Some(g) = self.live.reloader().current() {
                if let Some(r) = &mut self.renderer {
                    r.upload(&g.scene);
                }
                if !self.framed
                    && let Some(b) = g.scene.bounds
                {
                    self.camera.frame(b);
                    if let Some(spec) = self.camera_spec {
                        self.camera.place(spec.distance, spec.height, spec.target);
                    }
                    self.framed = true;
                }
                if g.settings.steps.is_none() {
                    self.total_steps = Some(g.steps_taken);
                }
                if let Some(saved) = self.live.reloader().current_trigger() {
                    self.drawn_after_save = Some((saved, self.uploaded));
                }
                self.viewport_dirty = true;
            }
        }
    }

    /// While playing, asks for the next step once the current one is on screen.
    fn play(&mut self) {
        let reloader = self.live.reloader();
        if !self.playing || reloader.is_running() {
            return;
        }
        if matches!(reloader.status(), Status::Error(_) | Status::Gone) {
            self.playing = false;
            return;
        }
        let (Some(total), Some(shown)) = (self.total_steps, reloader.current()) else {
            return;
        };
        if let Some(next) = next_play_step(total, &shown.settings, reloader.settings()) {
            self.playing = next.steps.is_some();
            self.settings_changed(next);
        }
    }

    fn settings_changed(&mut self, settings: Settings) {
        self.live.reloader_mut().set_settings(settings);
    }

    fn fps(&self) -> f64 {
        match (self.frames.front(), self.frames.back()) {
            (Some(a), Some(b)) if self.frames.len() > 1 && b > a => {
                (self.frames.len() - 1) as f64 / b.duration_since(*a).as_secs_f64()
            }
            _ => 0.0,
        }
    }

    fn viewport(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame) {
        let (rect, response) =
            ui.allocate_exact_size(ui.available_size(), egui::Sense::click_and_drag());
        let camera_before = self.camera;
        let shift = ui.input(|i| i.modifiers.shift);
        let drag = response.drag_delta();
        if response.dragged_by(egui::PointerButton::Primary) && !shift {
            self.camera.orbit(drag.x, drag.y);
            self.viewport_dirty = true;
        } else if response.dragged_by(egui::PointerButton::Secondary)
            || response.dragged_by(egui::PointerButton::Middle)
            || (response.dragged_by(egui::PointerButton::Primary) && shift)
        {
            self.camera.pan(drag.x, drag.y, rect.height());
            self.viewport_dirty = true;
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.camera.zoom(scroll / 50.0);
                self.viewport_dirty = true;
            }
        }
        if self.turntable {
            let dt = ui.input(|i| i.stable_dt).min(0.1);
            self.camera.yaw += 0.5 * dt;
            self.viewport_dirty = true;
        }
        let model_shown = self.framed && !self.live.reloader().is_running();
        // While the camera moves, draw at 30 % resolution with an eighth of the leaves and the
        // largest eighth of big bark meshes (measured: a 126k-leaf tree turns at 38-40
        // frames/s on llvmpipe instead of 18-20); once it rests, draw once more at full
        // quality.
        let Frame {
            moving,
            orbit: orbit_moving,
            redraw,
        } = self.motion.frame(
            &mut self.camera,
            camera_before,
            self.orbit.as_mut(),
            model_shown,
            Instant::now(),
        );
        self.viewport_dirty |= redraw;
        if moving {
            ui.ctx().request_repaint_after(MOTION_SETTLE);
        }
        let scale = if moving { 0.3 } else { 1.0 };
        let ppp = ui.ctx().pixels_per_point() * scale;
        let size = [
            (rect.width() * ppp).round() as u32,
            (rect.height() * ppp).round() as u32,
        ];
        let state = (size, self.camera, self.toggles);
        // A forest plan for the camera arrived after the frame was drawn: draw it.
        if let Some(renderer) = &mut self.renderer
            && !renderer.settled()
            && renderer.plan_ready()
        {
            self.viewport_dirty = true;
        }
        if self.viewport_dirty || self.last_viewport != Some(state) {
            if let (Some(renderer), Some(rs)) = (&mut self.renderer, frame.wgpu_render_state()) {
                let t0 = Instant::now();
                let vp = self
                    .camera
                    .view_projection(rect.width() / rect.height().max(1.0));
                let id = renderer.render(
                    &mut rs.renderer.write(),
                    vp,
                    self.camera.eye(),
                    size,
                    self.toggles,
                    moving,
                );
                self.texture = Some(id);
                self.render_ms = t0.elapsed().as_secs_f64() * 1000.0;
                if let Some(orbit) = &mut self.orbit
                    && orbit_moving.is_some()
                {
                    orbit.drawn(moving, renderer.times(), t0.elapsed(), renderer.settled());
                }
            }
            self.viewport_dirty = false;
            self.last_viewport = Some(state);
        }
        let painter = ui.painter_at(rect);
        match self.texture {
            Some(id) => {
                let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
                painter.image(id, rect, uv, Color32::WHITE);
            }
            None => {
                painter.rect_filled(rect, 0.0, Color32::from_gray(20));
                painter.text(
                    rect.center(),
                    egui::Align2::CENTER_CENTER,
                    "no GPU renderer (wgpu) available",
                    egui::FontId::proportional(16.0),
                    ERROR_COLOR,
                );
            }
        }
        let banner = match self.live.reloader().status() {
            Status::Error(m) => Some(m.clone()),
            Status::Gone => Some(gone_message(self.live.reloader().script())),
            _ => None,
        };
        if let Some(text) = banner {
            let galley = painter.layout(
                text,
                egui::FontId::monospace(14.0),
                ERROR_COLOR,
                (rect.width() - 24.0).max(50.0),
            );
            let r = egui::Rect::from_min_size(
                rect.min + egui::vec2(8.0, 8.0),
                galley.size() + egui::vec2(16.0, 12.0),
            );
            painter.rect_filled(r, 4.0, Color32::from_rgba_unmultiplied(40, 0, 0, 220));
            painter.galley(r.min + egui::vec2(8.0, 6.0), galley, ERROR_COLOR);
        } else if self.live.reloader().current().is_none() {
            painter.text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "generating…",
                egui::FontId::proportional(18.0),
                Color32::from_gray(200),
            );
        }
    }

    fn keys(&mut self, ctx: &egui::Context) {
        if ctx.wants_keyboard_input() {
            return;
        }
        let pressed = |k| ctx.input(|i| i.key_pressed(k));
        let before = (self.toggles, self.turntable);
        if pressed(egui::Key::F) {
            self.frame_model();
        }
        if pressed(egui::Key::W) {
            self.toggles.wireframe ^= true;
        }
        if pressed(egui::Key::K) {
            self.toggles.skeleton ^= true;
        }
        if pressed(egui::Key::L) {
            self.toggles.leaves ^= true;
        }
        if pressed(egui::Key::G) {
            self.toggles.grid ^= true;
        }
        if pressed(egui::Key::T) {
            self.turntable ^= true;
        }
        if before != (self.toggles, self.turntable) {
            self.viewport_dirty = true;
        }
    }

    /// The `--screenshot` sequence: once the first generation has ended and its frame is
    /// drawn, ask egui for the window's pixels; write them when they arrive; close.
    fn screenshot(&mut self, ctx: &egui::Context) {
        let Some((path, state)) = &mut self.shot else {
            return;
        };
        match state {
            Shot::Waiting => {
                let settled = self.orbit.as_ref().is_none_or(Orbit::finished)
                    && self.renderer.as_ref().is_none_or(Renderer::settled)
                    && !self.live.reloader().is_running()
                    && (self.live.reloader().current().is_some()
                        || !matches!(self.live.reloader().status(), Status::Running))
                    && self.uploaded == self.live.reloader().generation_count()
                    && !self.viewport_dirty;
                if settled {
                    ctx.send_viewport_cmd(egui::ViewportCommand::Screenshot(
                        egui::UserData::default(),
                    ));
                    let drawn = self
                        .renderer
                        .as_ref()
                        .map(|r| (r.triangles(), r.forest_leaves()));
                    let (triangles, leaves) = drawn.unwrap_or_default();
                    *state = Shot::Requested { triangles, leaves };
                }
            }
            Shot::Requested { triangles, leaves } => {
                let image = ctx.input(|i| {
                    i.raw.events.iter().find_map(|e| match e {
                        egui::Event::Screenshot { image, .. } => Some(image.clone()),
                        _ => None,
                    })
                });
                if let Some(image) = image {
                    let mut result = save_png(path, &image);
                    if result.is_ok() {
                        match self.live.reloader().status() {
                            Status::Error(m) => result = Err(anyhow::anyhow!("{m}")),
                            Status::Gone => {
                                result = Err(anyhow::anyhow!(
                                    "{}",
                                    gone_message(self.live.reloader().script())
                                ))
                            }
                            _ => {}
                        }
                    }
                    if result.is_ok() && self.renderer.is_some() {
                        println!(
                            "{}: {triangles} triangles drawn ({leaves} forest leaves)",
                            path.display()
                        );
                    }
                    if let Ok(mut slot) = self.shot_result.lock() {
                        *slot = Some(result);
                    }
                    *state = Shot::Done;
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                }
            }
            Shot::Done => {}
        }
        ctx.request_repaint();
    }

    /// An `--orbit-frames` run whose generation failed has no model to turn around: it ends
    /// (the error goes to the screenshot's result, or is the run's when there is none).
    fn orbit_without_model(&mut self) {
        let reloader = self.live.reloader();
        if reloader.is_running() || reloader.current().is_some() {
            return;
        }
        let message = match reloader.status() {
            Status::Error(m) => m.clone(),
            Status::Gone => gone_message(reloader.script()),
            _ => return,
        };
        let Some(orbit) = &mut self.orbit else {
            return;
        };
        if orbit.finished() {
            return;
        }
        orbit.abandon();
        if self.shot.is_none()
            && let Ok(mut slot) = self.shot_result.lock()
        {
            *slot = Some(Err(anyhow::anyhow!("{message}")));
        }
    }

    fn count_frame(&mut self) {
        let now = Instant::now();
        // The previous frame, which drew a model a save caused, has been presented.
        if let Some((saved, count)) = self.drawn_after_save.take() {
            let latency = now.duration_since(saved);
            self.save_to_screen = Some(latency);
            if self.log_fps {
                let generation = self.live.reloader().current().map_or(0.0, |g| g.seconds);
                eprintln!(
                    "preview: model {count} on screen {:.0} ms after the save (generation {:.0} ms)",
                    latency.as_secs_f64() * 1000.0,
                    generation * 1000.0
                );
            }
        }
        self.frames.push_back(now);
        while self
            .frames
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(2))
        {
            self.frames.pop_front();
        }
        if self.log_fps && now.duration_since(self.last_fps_log) >= Duration::from_secs(1) {
            self.last_fps_log = now;
            // Frame times over the last two seconds: mean and 95th percentile.
            let mut gaps: Vec<f64> = self
                .frames
                .iter()
                .zip(self.frames.iter().skip(1))
                .map(|(a, b)| b.duration_since(*a).as_secs_f64() * 1000.0)
                .collect();
            gaps.sort_by(f64::total_cmp);
            let mean = gaps.iter().sum::<f64>() / gaps.len().max(1) as f64;
            let p95 = gaps.get(gaps.len() * 95 / 100).copied().unwrap_or(0.0);
            eprintln!(
                "preview: {:.1} frames/s, frame {mean:.0} ms mean, {p95:.0} ms p95, draw {:.1} ms",
                self.fps(),
                self.render_ms
            );
        }
    }
}

impl eframe::App for PreviewApp {
    fn update(&mut self, ctx: &egui::Context, frame: &mut eframe::Frame) {
        let started = Instant::now();
        self.count_frame();
        self.pump();
        self.keys(ctx);
        egui::SidePanel::left("side")
            .resizable(true)
            .default_width(300.0)
            .show(ctx, |ui| self.side_panel(ui));
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ctx, |ui| self.viewport(ui, frame));
        self.screenshot(ctx);
        self.orbit_without_model();
        if let Some(orbit) = &mut self.orbit {
            orbit.updated(started.elapsed());
            if orbit.finished() && self.shot.is_none() {
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
            // While resting, the planner's plan wakes the window.
            if orbit.turning() || orbit.finished() || !self.framed {
                ctx.request_repaint();
            }
        }
        if self.turntable || self.drawn_after_save.is_some() {
            ctx.request_repaint();
        } else if self.live.reloader().is_running() {
            ctx.request_repaint_after(Duration::from_millis(100));
        }
        if let Some(at) = self.live.reloader().next_wake() {
            ctx.request_repaint_after(at.saturating_duration_since(Instant::now()));
        }
    }
}

/// The settings of the next step of playback, once the `shown` generation is the one
/// `requested`: one step further, or to the end (`steps: None`) after the last.
fn next_play_step(total: u32, shown: &Settings, requested: &Settings) -> Option<Settings> {
    if shown != requested {
        return None;
    }
    let mut next = requested.clone();
    let step = requested.steps.map_or(total, |k| k + 1);
    next.steps = (step < total).then_some(step);
    Some(next)
}

fn gone_message(script: &Path) -> String {
    format!(
        "{}: file is gone; waiting for it to come back",
        script.display()
    )
}

fn save_png(path: &Path, image: &egui::ColorImage) -> anyhow::Result<()> {
    let [w, h] = image.size;
    let mut rgba = Vec::with_capacity(w * h * 4);
    for c in &image.pixels {
        rgba.extend_from_slice(&c.to_srgba_unmultiplied());
    }
    let img = image::RgbaImage::from_raw(w as u32, h as u32, rgba)
        .ok_or_else(|| anyhow::anyhow!("screenshot of {w}x{h} has the wrong number of pixels"))?;
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn playback_steps_to_the_end_once_each_step_is_shown() {
        let at = |k| Settings {
            steps: Some(k),
            ..Settings::default()
        };
        assert_eq!(next_play_step(3, &at(0), &at(0)), Some(at(1)));
        assert_eq!(
            next_play_step(3, &at(1), &at(2)),
            None,
            "step 2 is not shown yet"
        );
        assert_eq!(
            next_play_step(3, &at(2), &at(2)).map(|s| s.steps),
            Some(None),
            "the end"
        );
    }
}
