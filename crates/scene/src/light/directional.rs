//! Directional lights: parallel light of irradiance E on a surface facing it.

use glam::{Vec2, Vec3};

use super::entry_disk::{entry_disk_pdf_a, entry_point};
use super::{Emission, Illumination, channel_mean};

/// An infinitely distant light. Emission sampling starts rays on a disk covering the scene.
#[derive(Clone, Debug)]
pub struct DirectionalLight {
    /// Unit direction in which the light travels (the node's -Z).
    pub direction: Vec3,
    /// Irradiance on a surface facing the light (glTF `intensity · color`).
    pub irradiance: Vec3,
    /// Center of the scene's bounding sphere.
    pub scene_center: Vec3,
    /// Radius of the scene's bounding sphere.
    pub scene_radius: f32,
}

impl DirectionalLight {
    fn disk_pdf_a(&self) -> f32 {
        entry_disk_pdf_a(self.scene_radius)
    }

    pub(super) fn illuminate(&self) -> Illumination {
        Illumination {
            direction: -self.direction,
            distance: f32::INFINITY,
            value: self.irradiance,
            direct_pdf_w: 1.0,
            emission_pdf_w: self.disk_pdf_a(),
            cos_at_light: 1.0,
        }
    }

    pub(super) fn emit(&self, u_pos: Vec2) -> Emission {
        Emission {
            value: self.irradiance,
            position: entry_point(self.scene_center, self.scene_radius, self.direction, u_pos),
            direction: self.direction,
            emission_pdf_w: self.disk_pdf_a(),
            // Light sampling picks the one direction with probability 1.
            direct_pdf_a: 1.0,
            cos_at_light: 1.0,
        }
    }

    /// E · π r² (the power crossing the scene's bounding disk).
    pub(super) fn power(&self) -> f32 {
        channel_mean(self.irradiance) * std::f32::consts::PI * self.scene_radius * self.scene_radius
    }
}
