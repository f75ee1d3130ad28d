//! Point and spot lights (`KHR_lights_punctual`): radiant intensity in W/sr, no range cut-off.

use glam::{Vec2, Vec3};

use super::{Emission, Illumination, channel_mean};
use crate::frame::Frame;
use crate::sampling::{
    sample_uniform_cone, sample_uniform_sphere, uniform_cone_pdf, uniform_sphere_pdf,
};

/// An isotropic point light of radiant intensity `intensity` (W/sr, linear RGB).
#[derive(Clone, Debug)]
pub struct PointLight {
    /// Position (world space).
    pub position: Vec3,
    /// Radiant intensity: glTF `intensity · color`.
    pub intensity: Vec3,
}

/// Samples toward a delta position: the "pdf" is the squared distance, so that
/// `value / direct_pdf_w = I / d²`.
fn illuminate_delta(
    position: Vec3,
    receiver: Vec3,
    value: Vec3,
    emission_pdf_w: f32,
) -> Option<Illumination> {
    let to_light = position - receiver;
    let distance_sq = to_light.length_squared();
    let distance = distance_sq.sqrt();
    (distance > 0.0 && distance.is_finite()).then(|| Illumination {
        direction: to_light / distance,
        distance,
        value,
        direct_pdf_w: distance_sq,
        emission_pdf_w,
        cos_at_light: 1.0,
    })
}

impl PointLight {
    /// The pdf of emitting any one direction: uniform over the sphere.
    pub fn emission_pdf_w(&self) -> f32 {
        uniform_sphere_pdf()
    }

    pub(super) fn illuminate(&self, receiver: Vec3) -> Option<Illumination> {
        illuminate_delta(
            self.position,
            receiver,
            self.intensity,
            self.emission_pdf_w(),
        )
    }

    pub(super) fn emit(&self, u_dir: Vec2) -> Emission {
        Emission {
            value: self.intensity,
            position: self.position,
            direction: sample_uniform_sphere(u_dir),
            emission_pdf_w: self.emission_pdf_w(),
            direct_pdf_a: 1.0,
            cos_at_light: 1.0,
        }
    }

    /// 4π · I.
    pub(super) fn power(&self) -> f32 {
        4.0 * std::f32::consts::PI * channel_mean(self.intensity)
    }
}

/// A spot light: a point light restricted to a cone, with the glTF angular falloff
/// (squared linear ramp in cos θ between the outer and inner cone angles).
#[derive(Clone, Debug)]
pub struct SpotLight {
    /// Position (world space).
    pub position: Vec3,
    /// Unit direction of the cone axis (the node's -Z).
    pub direction: Vec3,
    /// Radiant intensity on the axis (W/sr).
    pub intensity: Vec3,
    /// cos(innerConeAngle).
    pub cos_inner: f32,
    /// cos(outerConeAngle).
    pub cos_outer: f32,
}

impl SpotLight {
    /// Angular attenuation for a direction at cos θ from the axis (glTF recommended falloff):
    /// t², t = clamp((cos θ − cos θ_outer) · [`falloff_slope`](Self::falloff_slope), 0, 1).
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        let t = ((cos_theta - self.cos_outer) * self.falloff_slope()).clamp(0.0, 1.0);
        t * t
    }

    /// The slope of the falloff's ramp in cos θ: 1 / max(cos θ_inner − cos θ_outer, 10⁻³).
    pub fn falloff_slope(&self) -> f32 {
        1.0 / (self.cos_inner - self.cos_outer).max(1e-3)
    }

    /// The pdf of emitting any one direction: uniform over the outer cone.
    pub fn emission_pdf_w(&self) -> f32 {
        uniform_cone_pdf(self.cos_outer)
    }

    pub(super) fn illuminate(&self, receiver: Vec3) -> Option<Illumination> {
        let emission_pdf_w = self.emission_pdf_w();
        let sample = illuminate_delta(self.position, receiver, self.intensity, emission_pdf_w)?;
        let attenuation = self.falloff(self.direction.dot(-sample.direction));
        (attenuation > 0.0).then(|| Illumination {
            value: self.intensity * attenuation,
            ..sample
        })
    }

    pub(super) fn emit(&self, u_dir: Vec2) -> Emission {
        let local = sample_uniform_cone(u_dir, self.cos_outer);
        Emission {
            value: self.intensity * self.falloff(local.z),
            position: self.position,
            direction: Frame::from_z(self.direction).to_world(local),
            emission_pdf_w: self.emission_pdf_w(),
            direct_pdf_a: 1.0,
            cos_at_light: 1.0,
        }
    }

    /// I · 2π ∫ falloff d(cos θ) = I · 2π [(1 − cos_inner) + (cos_inner − cos_outer)/3].
    pub(super) fn power(&self) -> f32 {
        let solid_angle = 2.0
            * std::f32::consts::PI
            * ((1.0 - self.cos_inner) + (self.cos_inner - self.cos_outer) / 3.0);
        channel_mean(self.intensity) * solid_angle
    }
}
