//! The environment: constant radiance arriving from every direction at infinity (the world
//! background), seen by paths that leave the scene.

use glam::{Vec2, Vec3};

use super::entry_disk::{entry_disk_pdf_a, entry_point};
use super::{Emission, HitEmission, Illumination, channel_mean};
use crate::sampling::{sample_uniform_sphere, uniform_sphere_pdf};

/// Radiance `radiance` from every direction. Light sampling picks directions uniformly on the
/// sphere; emission sampling picks a direction so, then a point on the disk where light of
/// that direction enters the scene (as for directional lights).
#[derive(Clone, Debug)]
pub struct EnvironmentLight {
    /// Radiance arriving from every direction (linear RGB).
    pub radiance: Vec3,
    /// Center of the scene's bounding sphere.
    pub scene_center: Vec3,
    /// Radius of the scene's bounding sphere.
    pub scene_radius: f32,
}

impl EnvironmentLight {
    /// Pdf of emitting a given ray: a direction on the sphere, a point on its entry disk.
    fn emission_pdf_w(&self) -> f32 {
        uniform_sphere_pdf() * entry_disk_pdf_a(self.scene_radius)
    }

    pub(super) fn illuminate(&self, u: Vec2) -> Illumination {
        Illumination {
            direction: sample_uniform_sphere(u),
            distance: f32::INFINITY,
            value: self.radiance,
            direct_pdf_w: uniform_sphere_pdf(),
            emission_pdf_w: self.emission_pdf_w(),
            cos_at_light: 1.0,
        }
    }

    pub(super) fn emit(&self, u_pos: Vec2, u_dir: Vec2) -> Emission {
        let direction = -sample_uniform_sphere(u_dir);
        Emission {
            value: self.radiance,
            position: entry_point(self.scene_center, self.scene_radius, direction, u_pos),
            direction,
            emission_pdf_w: self.emission_pdf_w(),
            direct_pdf_a: uniform_sphere_pdf(),
            cos_at_light: 1.0,
        }
    }

    /// The radiance a path that leaves the scene along `_direction` receives, with the pdfs
    /// of the other techniques: `direct_pdf_a` is light sampling's solid-angle pdf of the
    /// direction.
    pub fn radiance_on_escape(&self, _direction: Vec3) -> HitEmission {
        HitEmission {
            radiance: self.radiance,
            direct_pdf_a: uniform_sphere_pdf(),
            emission_pdf_w: self.emission_pdf_w(),
        }
    }

    /// L · π · 4π r²: the power entering the scene's bounding sphere.
    pub(super) fn power(&self) -> f32 {
        let r = self.scene_radius;
        channel_mean(self.radiance) * 4.0 * std::f32::consts::PI.powi(2) * r * r
    }
}
