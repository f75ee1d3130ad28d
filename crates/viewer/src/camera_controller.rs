//! The interactive camera: orbit around a focus point, pan, zoom (dolly towards the focus) and
//! fly (move eye and focus together). It edits the scene's pinhole [`Camera`] in place, so an
//! untouched controller renders exactly the camera of the file.

use glam::{Quat, Vec2, Vec3};
use vcm_scene::{Bounds, Camera};

/// The world's up axis (glTF is +Y up): orbiting turns around it.
const WORLD_UP: Vec3 = Vec3::Y;

/// Orbiting stops this far (radians) from looking straight up or down, so the view never
/// flips over the pole.
const MAX_ELEVATION: f32 = 85.0 * std::f32::consts::PI / 180.0;

/// The closest the focus may come to the eye, as a fraction of the scene's radius.
const MIN_FOCUS_FRACTION: f32 = 1e-3;

/// Flying speed in scene radii per second.
const FLY_SPEED: f32 = 0.5;

/// A camera and the distance from its eye to the point it orbits (the focus, straight ahead).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraController {
    camera: Camera,
    /// Distance from the eye to the focus along the viewing direction (world units).
    focus_distance: f32,
    /// The scene's bounding-sphere radius (world units): sets the flying speed and the
    /// closest zoom.
    scene_radius: f32,
}

impl CameraController {
    /// A controller that starts at `camera` and focuses on the point straight ahead at the
    /// depth of the centre of `bounds` (at least a tenth of the scene's radius away).
    pub fn new(camera: Camera, bounds: &Bounds) -> CameraController {
        let (center, radius) = if bounds.is_empty() {
            (camera.position + camera.forward, 1.0)
        } else {
            (bounds.center(), bounds.radius().max(f32::MIN_POSITIVE))
        };
        let depth = (center - camera.position).dot(camera.forward);
        CameraController {
            camera,
            focus_distance: depth.max(0.1 * radius),
            scene_radius: radius,
        }
    }

    /// The camera to render with.
    pub fn camera(&self) -> Camera {
        self.camera
    }

    /// The point the camera orbits around (world space).
    pub fn focus(&self) -> Vec3 {
        self.camera.position + self.camera.forward * self.focus_distance
    }

    /// Orbits the eye around the focus: `yaw` radians around the world's up axis, `pitch`
    /// radians around the camera's right axis (positive looks up). The elevation is clamped
    /// to ±85°, so the camera never turns upside down.
    pub fn orbit(&mut self, yaw: f32, pitch: f32) {
        let focus = self.focus();
        let elevation = self.camera.forward.dot(WORLD_UP).clamp(-1.0, 1.0).asin();
        let limit = MAX_ELEVATION.max(elevation.abs());
        let pitch = (elevation + pitch).clamp(-limit, limit) - elevation;
        let rotation =
            Quat::from_axis_angle(WORLD_UP, yaw) * Quat::from_axis_angle(self.camera.right, pitch);
        self.rotate_frame(rotation);
        self.camera.position = focus - self.camera.forward * self.focus_distance;
    }

    /// Moves eye and focus across the view so that the scene follows the pointer: `offset`
    /// is the pointer's motion in image heights (x to the right, y down).
    pub fn pan(&mut self, offset: Vec2) {
        let image_height = 2.0 * self.focus_distance * (0.5 * self.camera.yfov).tan();
        let shift = (-self.camera.right * offset.x + self.camera.up * offset.y) * image_height;
        self.camera.position += shift;
    }

    /// Moves the eye towards the focus (`steps` > 0) or away from it: each step scales the
    /// distance by 0.9.
    pub fn zoom(&mut self, steps: f32) {
        let focus = self.focus();
        let closest = MIN_FOCUS_FRACTION * self.scene_radius;
        self.focus_distance = (self.focus_distance * 0.9f32.powf(steps)).max(closest);
        self.camera.position = focus - self.camera.forward * self.focus_distance;
    }

    /// Flies eye and focus together for `seconds` along `direction` in camera space (x right,
    /// y up, z forward; each component in −1 … 1), at half the scene's radius per second.
    pub fn fly(&mut self, direction: Vec3, seconds: f32) {
        let c = &self.camera;
        let world = c.right * direction.x + c.up * direction.y + c.forward * direction.z;
        self.camera.position += world * (FLY_SPEED * self.scene_radius * seconds);
    }

    /// Rotates the camera's frame and makes it orthonormal again (no drift over many moves).
    fn rotate_frame(&mut self, rotation: Quat) {
        let forward = (rotation * self.camera.forward).normalize();
        let up = rotation * self.camera.up;
        let up = (up - forward * forward.dot(up)).normalize();
        self.camera.forward = forward;
        self.camera.up = up;
        self.camera.right = forward.cross(up);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const EPS: f32 = 1e-4;

    fn bounds() -> Bounds {
        Bounds {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        }
    }

    fn controller() -> CameraController {
        CameraController::new(Camera::framing(&bounds()), &bounds())
    }

    fn assert_close(a: Vec3, b: Vec3) {
        assert!((a - b).length() < EPS, "{a} ≠ {b}");
    }

    fn assert_orthonormal(c: &Camera) {
        for v in [c.right, c.up, c.forward] {
            assert!((v.length() - 1.0).abs() < EPS);
        }
        assert!(c.right.dot(c.up).abs() < EPS);
        assert!(c.up.dot(c.forward).abs() < EPS);
        assert_close(c.right, c.forward.cross(c.up));
    }

    #[test]
    fn starts_at_the_scene_camera_focused_on_the_scene_centre() {
        let c = controller();
        assert_eq!(c.camera(), Camera::framing(&bounds()));
        assert_close(c.focus(), bounds().center());
    }

    #[test]
    fn orbiting_keeps_the_focus_and_its_distance() {
        let mut c = controller();
        let focus = c.focus();
        let distance = (c.camera().position - focus).length();
        c.orbit(0.7, 0.3);
        c.orbit(-0.2, -0.5);
        assert_close(c.focus(), focus);
        assert!(((c.camera().position - focus).length() - distance).abs() < EPS);
        assert_orthonormal(&c.camera());
    }

    #[test]
    fn a_full_turn_of_yaw_returns_to_the_start() {
        let mut c = controller();
        let start = c.camera();
        for _ in 0..8 {
            c.orbit(std::f32::consts::FRAC_PI_4, 0.0);
        }
        assert_close(c.camera().position, start.position);
        assert_close(c.camera().forward, start.forward);
    }

    #[test]
    fn a_quarter_turn_of_yaw_looks_along_the_next_axis() {
        let mut c = controller();
        c.orbit(std::f32::consts::FRAC_PI_2, 0.0);
        // Looking down −Z, turning +90° around +Y looks down −X, from the +X side.
        assert_close(c.camera().forward, -Vec3::X);
        assert!(c.camera().position.x > 1.0);
    }

    #[test]
    fn pitch_stops_short_of_the_poles() {
        let mut c = controller();
        for _ in 0..100 {
            c.orbit(0.0, 0.1);
        }
        let elevation = c.camera().forward.dot(WORLD_UP).asin();
        assert!((elevation - MAX_ELEVATION).abs() < EPS, "{elevation}");
        assert!(c.camera().up.dot(WORLD_UP) > 0.0, "the view never flips");
        c.orbit(0.0, -10.0);
        let elevation = c.camera().forward.dot(WORLD_UP).asin();
        assert!((elevation + MAX_ELEVATION).abs() < EPS, "{elevation}");
    }

    #[test]
    fn panning_by_one_image_height_moves_the_focus_by_the_view_height() {
        let mut c = controller();
        let before = c.focus();
        let distance = (c.camera().position - before).length();
        c.pan(Vec2::new(0.0, 1.0));
        let view_height = 2.0 * distance * (0.5 * c.camera().yfov).tan();
        assert_close(c.focus() - before, Vec3::Y * view_height);
        c.pan(Vec2::new(0.5, 0.0));
        assert_close(c.focus() - before, Vec3::new(-0.5, 1.0, 0.0) * view_height);
        assert_eq!(
            c.camera().forward,
            -Vec3::Z,
            "panning does not turn the camera"
        );
    }

    #[test]
    fn zooming_dollies_towards_the_focus_and_stops_before_it() {
        let mut c = controller();
        let focus = c.focus();
        let distance = (c.camera().position - focus).length();
        c.zoom(1.0);
        assert!(((c.camera().position - focus).length() - 0.9 * distance).abs() < EPS);
        c.zoom(-1.0);
        assert!(((c.camera().position - focus).length() - distance).abs() < EPS);
        c.zoom(1e4);
        let closest = (c.camera().position - focus).length();
        assert!(closest > 0.0 && closest <= MIN_FOCUS_FRACTION * bounds().radius() + EPS);
        assert_close(c.focus(), focus);
    }

    #[test]
    fn flying_moves_eye_and_focus_together() {
        let mut c = controller();
        let (eye, focus) = (c.camera().position, c.focus());
        c.fly(Vec3::new(1.0, 0.0, 1.0), 2.0);
        let step = FLY_SPEED * bounds().radius() * 2.0;
        let expected = Vec3::new(step, 0.0, -step);
        assert_close(c.camera().position - eye, expected);
        assert_close(c.focus() - focus, expected);
    }
}
