//! Light sources and their sampling, in the form bidirectional integrators need
//! (the interface of SmallVCM's lights: illuminate, emit, radiance on hit, with every pdf).
//!
//! Measures: `direct_pdf_w` is the solid-angle pdf of choosing the light point as seen from the
//! receiving point; `emission_pdf_w` is the product of the area pdf of the emitted position and
//! the solid-angle pdf of the emitted direction; `direct_pdf_a` is the area pdf of the position
//! alone (1 for delta positions). None of them include the light selection probability.

mod area;
mod directional;
mod entry_disk;
mod environment;
mod environment_map;
mod punctual;
mod sampler;

pub use area::AreaLight;
pub use directional::DirectionalLight;
pub use environment::EnvironmentLight;
pub use environment_map::EnvironmentMap;
pub use punctual::{PointLight, SpotLight};
pub use sampler::LightSampler;

use glam::{Vec2, Vec3};

use crate::texture::Texture;

/// A light source.
#[derive(Clone, Debug)]
pub enum Light {
    /// One emissive triangle.
    Area(AreaLight),
    /// `KHR_lights_punctual` point light.
    Point(PointLight),
    /// `KHR_lights_punctual` spot light.
    Spot(SpotLight),
    /// `KHR_lights_punctual` directional light (infinitely distant).
    Directional(DirectionalLight),
    /// Constant radiance from every direction at infinity (the world background).
    Environment(EnvironmentLight),
}

/// A light sample seen from a receiving point (next event estimation).
#[derive(Clone, Copy, Debug)]
pub struct Illumination {
    /// Unit direction from the receiving point toward the light sample.
    pub direction: Vec3,
    /// Distance to the light sample (`f32::INFINITY` for distant lights).
    pub distance: f32,
    /// Emitted radiance toward the receiver (area lights), radiant intensity (point, spot) or
    /// irradiance (directional); the contribution is `value · f · cos / direct_pdf_w`.
    pub value: Vec3,
    /// Solid-angle pdf of the sample at the receiver (`distance²` for point lights, 1 for directional).
    pub direct_pdf_w: f32,
    /// Pdf of emitting this same light path from the light (area pdf × direction pdf).
    pub emission_pdf_w: f32,
    /// Cosine between the light's normal and the emitted direction (1 for point-like lights).
    pub cos_at_light: f32,
}

/// A light path's first vertex and direction (emission sampling).
#[derive(Clone, Copy, Debug)]
pub struct Emission {
    /// Emitted radiance (area), intensity (point, spot) or irradiance (directional).
    pub value: Vec3,
    /// Start of the light path.
    pub position: Vec3,
    /// Unit direction of the first segment.
    pub direction: Vec3,
    /// Area pdf of `position` times solid-angle pdf of `direction`.
    pub emission_pdf_w: f32,
    /// Pdf with which light sampling ([`Light::illuminate`]) picks this light point: the area
    /// pdf of `position` for area lights, 1 for point, spot and directional lights (a delta
    /// position or direction is picked with probability 1).
    pub direct_pdf_a: f32,
    /// Cosine between the light's normal and `direction` (1 for point-like lights).
    pub cos_at_light: f32,
}

/// Radiance found by a path that hits an area light or leaves the scene into the environment.
#[derive(Clone, Copy, Debug)]
pub struct HitEmission {
    /// Emitted radiance toward the path.
    pub radiance: Vec3,
    /// Area pdf of choosing the hit point by light sampling (for the environment: the
    /// solid-angle pdf of choosing the direction).
    pub direct_pdf_a: f32,
    /// Pdf of emitting from the hit point toward the path (area × solid angle).
    pub emission_pdf_w: f32,
}

impl Light {
    /// Samples a point on the light as seen from `receiver`, with two uniform numbers `u`.
    ///
    /// Returns `None` when the sample cannot contribute (back of a one-sided emitter, outside a
    /// spot cone, receiver on the light, a cut-out part of an alpha-masked emitter, a black
    /// environment map).
    #[inline]
    pub fn illuminate(
        &self,
        textures: &[Texture],
        receiver: Vec3,
        u: Vec2,
    ) -> Option<Illumination> {
        match self {
            Light::Area(l) => l.illuminate(textures, receiver, u),
            Light::Point(l) => l.illuminate(receiver),
            Light::Spot(l) => l.illuminate(receiver),
            Light::Directional(l) => Some(l.illuminate()),
            Light::Environment(l) => l.illuminate(u),
        }
    }

    /// Samples an emitted ray with two pairs of uniform numbers (position, direction);
    /// `None` where no light leaves (a cut-out part of an alpha-masked emitter, a black
    /// environment map).
    #[inline]
    pub fn emit(&self, textures: &[Texture], u_pos: Vec2, u_dir: Vec2) -> Option<Emission> {
        match self {
            Light::Area(l) => l.emit(textures, u_pos, u_dir),
            Light::Point(l) => Some(l.emit(u_dir)),
            Light::Spot(l) => Some(l.emit(u_dir)),
            Light::Directional(l) => Some(l.emit(u_pos)),
            Light::Environment(l) => l.emit(u_pos, u_dir),
        }
    }

    /// Total emitted power (W in scene units, averaged over RGB): the selection weight (of an
    /// alpha-masked emitter, as if nothing were cut out).
    pub fn power(&self, textures: &[Texture]) -> f32 {
        match self {
            Light::Area(l) => l.power(textures),
            Light::Point(l) => l.power(),
            Light::Spot(l) => l.power(),
            Light::Directional(l) => l.power(),
            Light::Environment(l) => l.power(),
        }
    }

    /// True for lights with a delta position or direction (point, spot, directional): paths
    /// cannot hit them, only light sampling reaches them.
    #[inline]
    pub fn is_delta(&self) -> bool {
        !matches!(self, Light::Area(_) | Light::Environment(_))
    }

    /// True for lights at a finite position (all but directional and the environment).
    #[inline]
    pub fn is_finite(&self) -> bool {
        !matches!(self, Light::Directional(_) | Light::Environment(_))
    }
}

/// Mean of the three channels: the scalar used for power-proportional selection.
fn channel_mean(v: Vec3) -> f32 {
    (v.x + v.y + v.z) / 3.0
}

#[cfg(test)]
mod tests;
