//! The orbit camera: a target point, a distance, yaw and pitch; Y is up.

use glam::{Mat4, Vec3};
use pge_engine::math;

/// Vertical field of view in radians.
const FOV_Y: f32 = 0.8;

/// An orbit camera around a target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    /// The point looked at and orbited around.
    pub target: Vec3,
    /// Distance from the target.
    pub distance: f32,
    /// Rotation around Y, radians.
    pub yaw: f32,
    /// Elevation above the horizon, radians.
    pub pitch: f32,
}

impl Default for OrbitCamera {
    fn default() -> Self {
        OrbitCamera {
            target: Vec3::new(0.0, 1.0, 0.0),
            distance: 6.0,
            yaw: 0.6,
            pitch: 0.25,
        }
    }
}

impl OrbitCamera {
    /// The eye position.
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = math::sin_cos(self.yaw);
        let (sp, cp) = math::sin_cos(self.pitch);
        self.target + self.distance * Vec3::new(cp * sy, sp, cp * cy)
    }

    /// Rotates by a mouse drag of `dx`, `dy` points.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * 0.008;
        self.pitch = (self.pitch + dy * 0.008).clamp(-1.55, 1.55);
    }

    /// Moves the target in the view plane by a drag of `dx`, `dy` points in a viewport
    /// `height` points tall (the point under the mouse follows it).
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let view = Mat4::look_at_rh(self.eye(), self.target, Vec3::Y).inverse();
        let right = view.x_axis.truncate();
        let up = view.y_axis.truncate();
        let per_point = 2.0 * self.distance * math::tan(FOV_Y / 2.0) / height.max(1.0);
        self.target += (-dx * right + dy * up) * per_point;
    }

    /// Zooms by `steps` (positive: closer), each step 10 %.
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * math::powf(0.9f32, steps)).clamp(1e-3, 1e6);
    }

    /// Looks at the centre of `bounds` from a distance where all of it fits.
    pub fn frame(&mut self, bounds: (Vec3, Vec3)) {
        let (lo, hi) = bounds;
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        self.target = (lo + hi) * 0.5;
        self.distance = radius / math::sin(FOV_Y / 2.0) * 1.05;
    }

    /// Places the eye `distance` metres from `target` (the current target when `None`)
    /// horizontally, at height `height`, keeping the yaw (`--camera`).
    pub fn place(&mut self, distance: f32, height: f32, target: Option<Vec3>) {
        if let Some(t) = target {
            self.target = t;
        }
        let rise = height - self.target.y;
        self.distance = (distance * distance + rise * rise).sqrt().max(1e-3);
        self.pitch = math::atan2(rise, distance).clamp(-1.55, 1.55);
    }

    /// Projection times view for a viewport of the given aspect ratio, with depth in [0, 1].
    #[must_use]
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        let near = (self.distance * 0.01).max(1e-4);
        let far = self.distance * 100.0 + 100.0;
        let proj = Mat4::perspective_rh(FOV_Y, aspect.max(1e-3), near, far);
        proj * Mat4::look_at_rh(self.eye(), self.target, Vec3::Y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::assert_approx_eq;

    #[test]
    fn place_puts_the_eye_at_the_distance_and_height() {
        let mut c = OrbitCamera::default();
        c.place(2.0, 1.5, Some(Vec3::new(0.0, 1.0, 0.0)));
        let eye = c.eye();
        assert!((eye.y - 1.5).abs() < 1e-5, "{eye}");
        let flat = Vec3::new(eye.x, 0.0, eye.z).length();
        assert!((flat - 2.0).abs() < 1e-5, "{flat}");
        let before = c.target;
        c.place(10.0, 0.0, None);
        assert_eq!(c.target, before);
        assert!((c.eye().y).abs() < 1e-5);
    }

    #[test]
    fn framing_puts_the_bounds_in_view() {
        let mut cam = OrbitCamera::default();
        cam.frame((Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 10.0, 1.0)));
        assert_approx_eq!(cam.target, Vec3::new(0.0, 5.0, 0.0), 1e-4);
        let vp = cam.view_projection(1.0);
        for corner in [
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 10.0, 1.0),
            Vec3::new(1.0, 0.0, -1.0),
        ] {
            let p = vp.project_point3(corner);
            assert!(
                p.x.abs() <= 1.0 && p.y.abs() <= 1.0,
                "{corner} projects to {p}"
            );
            assert!((0.0..1.0).contains(&p.z));
        }
    }

    #[test]
    fn orbit_keeps_distance_and_clamps_pitch() {
        let mut cam = OrbitCamera::default();
        cam.orbit(100.0, 10_000.0);
        assert!(((cam.eye() - cam.target).length() - cam.distance).abs() < 1e-4);
        assert!(cam.pitch <= 1.55);
        cam.zoom(1.0);
        assert!((cam.distance - 5.4).abs() < 1e-4);
    }

    #[test]
    fn panning_moves_the_target_sideways() {
        let mut cam = OrbitCamera {
            yaw: 0.0,
            pitch: 0.0,
            ..OrbitCamera::default()
        };
        let before = cam.target;
        cam.pan(-100.0, 0.0, 500.0);
        let moved = cam.target - before;
        assert!(
            moved.x > 0.0 && moved.y.abs() < 1e-5 && moved.z.abs() < 1e-5,
            "{moved}"
        );
    }
}
