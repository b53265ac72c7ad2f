//! Whether a frame is a moving one: the camera turned by hand or by the turntable, or an
//! `--orbit-frames` turn.

use std::time::{Duration, Instant};

use super::orbit::Orbit;
use crate::camera::OrbitCamera;

/// How long after the last camera motion the viewport is drawn at full quality.
pub(super) const MOTION_SETTLE: Duration = Duration::from_millis(200);

/// The camera's motion from frame to frame.
pub(super) struct Motion {
    /// When the camera was last moved by hand or by the turntable.
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

    /// A frame starts at `now`: the input (or the turntable) moved the camera from `before`
    /// to `camera`; an `orbit` under way (once the model is shown) turns it further.
    pub fn frame(
        &mut self,
        camera: &mut OrbitCamera,
        before: OrbitCamera,
        orbit: Option<&mut Orbit>,
        model_shown: bool,
        now: Instant,
    ) -> Frame {
        // By hand or by the turntable. An orbit's turns are not: its frames move exactly
        // when it says so, and once it has rested, the frames after it rest too (the
        // picture of an `--orbit-frames --screenshot` run arrives a few frames later, and a
        // moving frame drawn meanwhile would take a moving frame's forest plan).
        if *camera != before {
            self.last = Some(now);
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::FrameTimes;

    #[test]
    fn once_an_orbit_has_rested_the_frames_after_it_rest_too() {
        let mut motion = Motion::new(false);
        let mut orbit = Orbit::new(2);
        let mut camera = OrbitCamera::default();
        let t0 = Instant::now();
        let ms = |k: u64| t0 + Duration::from_millis(k);
        let mut frame = |motion: &mut Motion, orbit: &mut Orbit, at| {
            let before = camera;
            motion.frame(&mut camera, before, Some(orbit), true, at)
        };
        // Two moving frames turn the camera, then it rests until the forest's final plan
        // is drawn.
        for k in 0..2 {
            let f = frame(&mut motion, &mut orbit, ms(10 * k));
            assert_eq!((f.moving, f.orbit, f.redraw), (true, Some(true), true));
            orbit.drawn(true, FrameTimes::default(), Duration::ZERO, false);
        }
        let f = frame(&mut motion, &mut orbit, ms(20));
        assert_eq!((f.moving, f.orbit, f.redraw), (false, Some(false), true));
        orbit.drawn(false, FrameTimes::default(), Duration::ZERO, true);
        assert!(orbit.finished());
        // The picture may be taken a few frames later (a screenshot arrives late): those
        // frames must not be moving ones, however soon they follow the turn.
        for k in [21, 30, 100] {
            let f = frame(&mut motion, &mut orbit, ms(k));
            assert_eq!(f.orbit, None);
            assert!(!f.moving, "{k} ms after the turn began: {f:?}");
        }
    }

    #[test]
    fn a_camera_moved_by_hand_moves_until_it_has_rested_a_while() {
        let mut motion = Motion::new(false);
        let mut camera = OrbitCamera::default();
        let t0 = Instant::now();
        let before = camera;
        camera.orbit(10.0, 0.0);
        assert!(motion.frame(&mut camera, before, None, true, t0).moving);
        let still = |motion: &mut Motion, camera: &mut OrbitCamera, at| {
            let before = *camera;
            motion.frame(camera, before, None, true, at).moving
        };
        assert!(still(&mut motion, &mut camera, t0 + MOTION_SETTLE / 2));
        assert!(!still(&mut motion, &mut camera, t0 + MOTION_SETTLE));
        // Measurements draw moving frames at full quality.
        let mut full = Motion::new(true);
        let before = camera;
        camera.orbit(10.0, 0.0);
        assert!(!full.frame(&mut camera, before, None, true, t0).moving);
    }
}
