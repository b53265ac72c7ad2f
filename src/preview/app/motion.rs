//! Whether a frame is a moving one: the camera turned by hand or by the turntable, or an
//! `--orbit-frames` turn.

use std::time::{Duration, Instant};

use super::orbit::Orbit;
use crate::preview::camera::OrbitCamera;

/// How long after the last camera motion the viewport is drawn at full quality.
pub(super) const MOTION_SETTLE: Duration = Duration::from_millis(200);

/// The camera's motion from frame to frame.
pub(super) struct Motion {
    /// When the camera last moved.
    last: Option<Instant>,
    /// Draw moving frames at full quality too (for measurements).
    full_quality: bool,
}

/// What [`Motion::frame`] decided for one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Frame {
    /// The frame is drawn as a moving one.
    pub moving: bool,
    /// An orbit is under way and said whether this frame moves.
    pub orbit: Option<bool>,
    /// The orbit needs this frame drawn.
    pub redraw: bool,
}

impl Motion {
    pub fn new(full_quality: bool) -> Motion {
        Motion {
            last: None,
            full_quality,
        }
    }

    /// A frame starts at `now`: the input moved the camera from `before` to `camera`; an
    /// `orbit` under way (once the model is shown) turns it further.
    pub fn frame(
        &mut self,
        camera: &mut OrbitCamera,
        before: OrbitCamera,
        orbit: Option<&mut Orbit>,
        model_shown: bool,
        now: Instant,
    ) -> Frame {
        let (orbit, redraw) = match orbit {
            Some(orbit) if model_shown && !orbit.finished() => {
                let (moving, redraw) = orbit.next_frame(now);
                if moving {
                    camera.yaw += std::f32::consts::TAU / orbit.frames as f32;
                }
                (Some(moving), redraw)
            }
            _ => (None, false),
        };
        if *camera != before {
            self.last = Some(now);
        }
        let moving = orbit.unwrap_or_else(|| {
            !self.full_quality
                && self
                    .last
                    .is_some_and(|t| now.duration_since(t) < MOTION_SETTLE)
        });
        Frame {
            moving,
            orbit,
            redraw,
        }
    }
}
