//! `pge preview`: a window that shows the model a script makes and regenerates it on save.
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

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::{anyhow, bail};
use eframe::egui;
use pge_engine::EngineBuilder;

use self::app::{AppOptions, PreviewApp};
use self::reload::Settings;

/// Arguments of `pge preview`.
#[derive(clap::Args, Clone, Debug)]
pub struct PreviewArgs {
    /// The Lua script to show.
    pub script: PathBuf,
    /// Draws trees with levels of detail (`lod`) at this fraction of their leaves, 0.01 to 1.
    #[arg(long, value_name = "FRACTION", default_value_t = 1.0, value_parser = lod::parse_fraction)]
    pub lod_level: f64,
    /// A forest's leaf budget: the most leaves its trees draw in a frame at rest, nearer
    /// trees finer (as many triangles again go to bark and other meshes).
    #[arg(long, value_name = "N", default_value_t = forest::DEFAULT_LEAF_BUDGET, value_parser = forest::parse_budget)]
    pub leaf_budget: u64,
    /// Seed of every random draw.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Overrides a parameter declared with pge.params (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_set)]
    pub set: Vec<(String, String)>,
    /// Writes the first complete frame to this PNG file and exits.
    #[arg(long, value_name = "PNG")]
    pub screenshot: Option<PathBuf>,
    /// Places the camera instead of framing the model: `D` metres from the target
    /// horizontally, the eye at height `H`, looking at `TX,TY,TZ` (default: the centre of the
    /// model's bounds).
    #[arg(long, value_name = "D,H[,TX,TY,TZ]", value_parser = parse_camera, allow_hyphen_values = true)]
    pub camera: Option<CameraSpec>,
    /// Measures the viewport: once the first model is on screen, turns the camera once
    /// around it in N frames drawn as while dragging, then rests; prints where each frame's
    /// time went to stderr and closes (after `--screenshot`, if given, of the resting frame).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub orbit_frames: Option<u32>,
    /// Seconds one generation may take.
    #[arg(long, value_name = "SECONDS", default_value_t = 300.0, value_parser = crate::common::parse_seconds)]
    pub time_limit: f64,
    /// MiB of memory the Lua state may use.
    #[arg(long, value_name = "MIB", default_value_t = 4096, value_parser = crate::common::parse_mib)]
    pub memory_limit: usize,
}

fn parse_set(text: &str) -> Result<(String, String), String> {
    match text.split_once('=') {
        Some((name, value)) if !name.trim().is_empty() => {
            Ok((name.trim().to_string(), value.to_string()))
        }
        _ => Err(format!("'{text}' is not NAME=VALUE")),
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

fn parse_camera(text: &str) -> Result<CameraSpec, String> {
    let bad = || format!("'{text}' is not D,H or D,H,TX,TY,TZ (numbers, D > 0)");
    let numbers = text
        .split(',')
        .map(|s| s.trim().parse::<f32>().ok().filter(|v| v.is_finite()))
        .collect::<Option<Vec<f32>>>()
        .ok_or_else(bad)?;
    let target = match numbers.len() {
        2 => None,
        5 => Some(glam::Vec3::new(numbers[2], numbers[3], numbers[4])),
        _ => return Err(bad()),
    };
    if numbers[0] <= 0.0 {
        return Err(bad());
    }
    Ok(CameraSpec {
        distance: numbers[0],
        height: numbers[1],
        target,
    })
}

/// Opens the preview window for `args.script` with every plugin of the `pge` command.
pub fn preview(args: &PreviewArgs) -> anyhow::Result<()> {
    preview_with(args, pge::default_engine())
}

/// Opens the preview window with the engine `builder` makes (plugins of a host application).
pub fn preview_with(args: &PreviewArgs, builder: EngineBuilder) -> anyhow::Result<()> {
    let engine = builder
        .memory_limit_mib(args.memory_limit)
        .time_limit(Some(Duration::from_secs_f64(args.time_limit)))
        .build()?;
    let settings = Settings {
        seed: args.seed,
        params: args.set.clone(),
        steps: None,
    };
    let screenshot_result = Arc::new(Mutex::new(None));
    let log = std::env::var("PGE_PREVIEW_LOG").unwrap_or_default();
    let measuring = log == "1" || log == "full";
    let options = AppOptions {
        screenshot: args.screenshot.clone(),
        lod_percent: (args.lod_level * 100.0).round().clamp(1.0, 100.0) as u8,
        leaf_budget: args.leaf_budget,
        screenshot_result: screenshot_result.clone(),
        camera: args.camera,
        log_fps: measuring,
        turntable: measuring,
        full_quality_motion: log == "full",
        orbit_frames: args.orbit_frames,
    };
    let title = format!("PGE preview: {}", args.script.display());
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title(title.clone())
            .with_app_id("pge-preview")
            .with_inner_size([1280.0, 800.0]),
        ..eframe::NativeOptions::default()
    };
    let script = args.script.clone();
    let failure: Arc<Mutex<Option<anyhow::Error>>> = Arc::new(Mutex::new(None));
    let failure_slot = failure.clone();
    eframe::run_native(
        &title,
        native,
        Box::new(move |cc| {
            let app = PreviewApp::new(cc, engine, script, settings, options);
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
    if args.screenshot.is_none() && args.orbit_frames.is_some() {
        // An orbit whose generation failed leaves its error here.
        let result = screenshot_result
            .lock()
            .map_err(|_| anyhow!("orbit state poisoned"))?
            .take();
        if let Some(r) = result {
            r?;
        }
    }
    if let Some(path) = &args.screenshot {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_placements_are_parsed() {
        assert_eq!(
            parse_camera("2,1.5"),
            Ok(CameraSpec {
                distance: 2.0,
                height: 1.5,
                target: None
            })
        );
        assert_eq!(
            parse_camera("30, 8, 0, -1, 2.5").map(|c| c.target),
            Ok(Some(glam::Vec3::new(0.0, -1.0, 2.5)))
        );
        for bad in ["2", "2,1,0", "0,1", "-1,2", "a,b", "2,NaN"] {
            assert!(parse_camera(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn set_and_seconds_are_parsed() {
        assert_eq!(parse_set("height=3.5"), Ok(("height".into(), "3.5".into())));
        assert_eq!(parse_set("name=a=b"), Ok(("name".into(), "a=b".into())));
        assert!(parse_set("height").is_err());
        assert!(parse_set("=3").is_err());
        use crate::common::{parse_mib, parse_seconds};
        assert_eq!(parse_seconds("2.5"), Ok(2.5));
        assert!(parse_seconds("0").is_err());
        assert!(parse_seconds("inf").is_err());
        assert!(parse_seconds("x").is_err());
        assert_eq!(parse_mib("64"), Ok(64));
        assert!(parse_mib("0").is_err());
        assert!(parse_mib("-1").is_err());
    }
}
