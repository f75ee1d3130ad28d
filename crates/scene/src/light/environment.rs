//! The environment: radiance arriving from every direction at infinity (the world
//! background), constant or from an equirectangular image, seen by paths that leave the
//! scene.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::entry_disk::{entry_disk_pdf_a, entry_point};
use super::{Emission, EnvironmentMap, HitEmission, Illumination, channel_mean};
use crate::sampling::{sample_uniform_sphere, uniform_sphere_pdf};

/// Radiance `radiance` (times `map`'s, if any) from every direction. Light sampling picks
/// directions uniformly on the sphere, or by the map's brightness; emission sampling picks a
/// direction so, then a point on the disk where light of that direction enters the scene (as
/// for directional lights).
#[derive(Clone, Debug)]
pub struct EnvironmentLight {
    /// Radiance arriving from every direction (linear RGB), a scale of `map`'s if there is one.
    pub radiance: Vec3,
    /// The sky's image, if it is not constant.
    pub map: Option<Arc<EnvironmentMap>>,
    /// Center of the scene's bounding sphere.
    pub scene_center: Vec3,
    /// Radius of the scene's bounding sphere.
    pub scene_radius: f32,
}

impl EnvironmentLight {
    /// A direction toward the sky with its solid-angle pdf (`None`: a black map).
    fn sample_direction(&self, u: Vec2) -> Option<(Vec3, f32)> {
        match &self.map {
            None => Some((sample_uniform_sphere(u), uniform_sphere_pdf())),
            Some(map) => map.sample(u),
        }
    }

    /// The radiance arriving from the unit `direction`.
    fn radiance_from(&self, direction: Vec3) -> Vec3 {
        match &self.map {
            None => self.radiance,
            Some(map) => self.radiance * map.radiance(direction),
        }
    }

    pub(super) fn illuminate(&self, u: Vec2) -> Option<Illumination> {
        let (direction, direct_pdf_w) = self.sample_direction(u)?;
        Some(Illumination {
            direction,
            distance: f32::INFINITY,
            value: self.radiance_from(direction),
            direct_pdf_w,
            emission_pdf_w: direct_pdf_w * entry_disk_pdf_a(self.scene_radius),
            cos_at_light: 1.0,
        })
    }

    pub(super) fn emit(&self, u_pos: Vec2, u_dir: Vec2) -> Option<Emission> {
        let (toward_sky, direct_pdf_w) = self.sample_direction(u_dir)?;
        let direction = -toward_sky;
        Some(Emission {
            value: self.radiance_from(toward_sky),
            position: entry_point(self.scene_center, self.scene_radius, direction, u_pos),
            direction,
            emission_pdf_w: direct_pdf_w * entry_disk_pdf_a(self.scene_radius),
            direct_pdf_a: direct_pdf_w,
            cos_at_light: 1.0,
        })
    }

    /// The radiance a path that leaves the scene along the unit `direction` receives, with
    /// the pdfs of the other techniques: `direct_pdf_a` is light sampling's solid-angle pdf
    /// of the direction.
    pub fn radiance_on_escape(&self, direction: Vec3) -> HitEmission {
        let direct_pdf_w = match &self.map {
            None => uniform_sphere_pdf(),
            Some(map) => map.pdf(direction),
        };
        HitEmission {
            radiance: self.radiance_from(direction),
            direct_pdf_a: direct_pdf_w,
            emission_pdf_w: direct_pdf_w * entry_disk_pdf_a(self.scene_radius),
        }
    }

    /// L̄ · π · 4π r²: the power entering the scene's bounding sphere (L̄ the mean radiance).
    pub(super) fn power(&self) -> f32 {
        let mean = match &self.map {
            None => self.radiance,
            Some(map) => self.radiance * map.mean(),
        };
        let r = self.scene_radius;
        channel_mean(mean) * 4.0 * std::f32::consts::PI.powi(2) * r * r
    }
}
