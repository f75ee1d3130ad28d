//! Where light from infinitely far away enters the scene: a disk with the radius of the
//! scene's bounding sphere, perpendicular to the light's direction, one radius behind the
//! centre. Every ray of that direction that reaches the scene crosses it.

use glam::{Vec2, Vec3};

use crate::frame::Frame;
use crate::sampling::sample_concentric_disk;

/// Area pdf of a uniform point on the entry disk of a scene of radius `scene_radius`.
pub(super) fn entry_disk_pdf_a(scene_radius: f32) -> f32 {
    1.0 / (std::f32::consts::PI * scene_radius * scene_radius)
}

/// A uniform point (from `u`) on the entry disk for light travelling along the unit
/// `direction` into the scene around `scene_center`.
pub(super) fn entry_point(scene_center: Vec3, scene_radius: f32, direction: Vec3, u: Vec2) -> Vec3 {
    let disk = sample_concentric_disk(u) * scene_radius;
    let offset = Frame::from_z(direction).to_world(Vec3::new(disk.x, disk.y, 0.0));
    scene_center + offset - direction * scene_radius
}
