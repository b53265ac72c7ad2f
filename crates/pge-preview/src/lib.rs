//! PGE's preview: a window that shows the model a script makes and regenerates it on save
//! (`pge preview`, or a host application's own window with its own plugins).
//!
//! ```no_run
//! use pge_preview::{PreviewOptions, preview};
//!
//! let engine = pge_engine::Engine::builder().build()?;
//! preview(engine, PreviewOptions::new("scripts/examples/spiral.lua"))?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! The script runs on a background thread ([`worker`]); a save of the script or of any file
//! it loaded ([`watch`]) starts a new generation that supersedes the running one, following
//! the rules of [`reload`]; the last good model stays on screen while an error is shown as
//! `FILE:LINE: message`. The model is drawn with wgpu ([`render`]) in an egui window
//! ([`app`]); the side panel holds the script's parameters, the seed, a step scrubber,
//! statistics and export.
//!
//! With `--screenshot PNG` the window writes its first complete frame (after the first
//! generation has ended) to the file and closes; the command then fails if the generation
//! did. Setting the environment variable `PGE_PREVIEW_LOG=1` starts the turntable and prints
//! frames per second, the mean and 95th-percentile frame times, and the time from each save
//! to its model on screen to stderr (for
//! measuring the viewport's speed and the reload latency); `PGE_PREVIEW_LOG=full` does the
//! same with every frame drawn at full quality (no reduced detail while moving).
//! `--orbit-frames N` turns the camera once around the model in N frames and prints where
//! each frame's time went (a forest's plans are made off the window's thread: [`planner`]).

mod app;
pub mod args;
pub mod camera;
pub mod forest;
pub mod live;
pub mod lod;
mod pipeline;
pub mod planner;
pub mod reload;
pub mod render;
pub mod scene;
mod texture;
pub mod watch;
pub mod worker;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use anyhow::{anyhow, bail};
use eframe::egui;
use pge_engine::geometry::Model;
use pge_engine::{Engine, ParamInfo};

use self::app::{AppOptions, PreviewApp};
use self::reload::Settings;

/// Floats per vertex: position (3), normal (3), uv (2), linear RGBA colour (4), tangent (4:
/// the mesh's tangent where its material has a normal map, as the glb's
/// `TANGENT`; zero elsewhere).
pub const VERTEX_FLOATS: usize = 16;

/// Writes a model to a file as the host's command line does (`pge run`'s writer: `.glb`, or
/// `.obj` with its `.mtl` and textures): the preview's export button. Receives the model,
/// the seed and the declared parameters with their values, and the file.
pub type ExportFn = fn(&Model, u64, &[ParamInfo], &Path) -> anyhow::Result<()>;

/// What the preview window shows and how.
#[derive(Clone, Debug)]
pub struct PreviewOptions {
    /// The Lua script to show.
    pub script: PathBuf,
    /// Seed of every random draw (default 1).
    pub seed: u64,
    /// `NAME=VALUE` overrides of parameters declared with `pge.params`.
    pub params: Vec<(String, String)>,
    /// Draws trees with levels of detail (`lod`) at this fraction of their leaves, 0.01 to 1
    /// (default 1).
    pub lod_level: f64,
    /// A forest's leaf budget: the most leaves its trees draw in a frame at rest (default
    /// [`forest::DEFAULT_LEAF_BUDGET`]).
    pub leaf_budget: u64,
    /// Writes the first complete frame to this PNG file and exits.
    pub screenshot: Option<PathBuf>,
    /// Places the camera instead of framing the model.
    pub camera: Option<CameraSpec>,
    /// Turns the camera once around the model in N frames drawn as while dragging, prints
    /// where each frame's time went to stderr and closes.
    pub orbit_frames: Option<u32>,
    /// The export button's writer; `None`: no export.
    pub export: Option<ExportFn>,
}

impl PreviewOptions {
    /// The defaults for `script`.
    #[must_use]
    pub fn new(script: impl Into<PathBuf>) -> PreviewOptions {
        PreviewOptions {
            script: script.into(),
            seed: 1,
            params: Vec::new(),
            lod_level: 1.0,
            leaf_budget: forest::DEFAULT_LEAF_BUDGET,
            screenshot: None,
            camera: None,
            orbit_frames: None,
            export: None,
        }
    }
}

/// A camera placement from `--camera D,H[,TX,TY,TZ]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSpec {
    /// Horizontal distance from the target, metres.
    pub distance: f32,
    /// Height of the eye, metres.
    pub height: f32,
    /// The point looked at; `None`: the centre of the model's bounds.
    pub target: Option<glam::Vec3>,
}

/// Opens the preview window for `options.script`, generating with `engine` (its plugins and
/// limits); returns when the window closes (with the screenshot's or the orbit's error,
/// when one was asked for and failed).
pub fn preview(engine: Engine, options: PreviewOptions) -> anyhow::Result<()> {
    let settings = Settings {
        seed: options.seed,
        params: options.params.clone(),
        steps: None,
    };
    let screenshot_result = Arc::new(Mutex::new(None));
    let log = std::env::var("PGE_PREVIEW_LOG").unwrap_or_default();
    let measuring = log == "1" || log == "full";
    let app_options = AppOptions {
        screenshot: options.screenshot.clone(),
        lod_percent: (options.lod_level * 100.0).round().clamp(1.0, 100.0) as u8,
        leaf_budget: options.leaf_budget,
        screenshot_result: screenshot_result.clone(),
        camera: options.camera,
        log_fps: measuring,
        turntable: measuring,
        full_quality_motion: log == "full",
        orbit_frames: options.orbit_frames,
        export: options.export,
    };
    let title = format!("PGE preview: {}", options.script.display());
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title(title.clone())
            .with_app_id("pge-preview")
            .with_inner_size([1280.0, 800.0]),
        ..eframe::NativeOptions::default()
    };
    let script = options.script.clone();
    let failure: Arc<Mutex<Option<anyhow::Error>>> = Arc::new(Mutex::new(None));
    let failure_slot = failure.clone();
    eframe::run_native(
        &title,
        native,
        Box::new(move |cc| {
            let app = PreviewApp::new(cc, engine, script, settings, app_options);
            match app {
                Ok(app) => Ok(Box::new(app) as Box<dyn eframe::App>),
                Err(e) => {
                    let message = e.to_string();
                    if let Ok(mut slot) = failure_slot.lock() {
                        *slot = Some(e);
                    }
                    Err(message.into())
                }
            }
        }),
    )
    .map_err(|e| {
        let inner = failure.lock().ok().and_then(|mut f| f.take());
        inner.unwrap_or_else(|| anyhow!("cannot open the preview window: {e}"))
    })?;
    if options.screenshot.is_none() && options.orbit_frames.is_some() {
        // An orbit whose generation failed leaves its error here.
        let result = screenshot_result
            .lock()
            .map_err(|_| anyhow!("orbit state poisoned"))?
            .take();
        if let Some(r) = result {
            r?;
        }
    }
    if let Some(path) = &options.screenshot {
        let result = screenshot_result
            .lock()
            .map_err(|_| anyhow!("screenshot state poisoned"))?
            .take();
        match result {
            Some(r) => r?,
            None => bail!(
                "the window closed before the screenshot {} was taken",
                path.display()
            ),
        }
    }
    Ok(())
}
