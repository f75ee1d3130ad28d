//! Area lights: one emissive triangle, emitting from its front face only.

use glam::{Vec2, Vec3};

use super::{Emission, HitEmission, Illumination, channel_mean};
use crate::frame::Frame;
use crate::material::AlphaMask;
use crate::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere, sample_uniform_triangle};
use crate::texture::{Texture, TextureRef};

/// An emissive triangle. Radiance is `emission` times the emissive texture, one-sided (front face).
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// Index of the triangle in the scene mesh.
    pub triangle: u32,
    /// Corner positions (world space).
    pub corners: [Vec3; 3],
    /// Corner texture coordinates.
    pub uvs: [Vec2; 3],
    /// Unit front-face normal.
    pub normal: Vec3,
    /// Surface area.
    pub area: f32,
    /// Emitted radiance factor.
    pub emission: Vec3,
    /// Optional emissive texture (multiplies `emission`).
    pub texture: Option<TextureRef>,
    /// The cut-out of an alpha-masked emitter: no light leaves where rays pass through it.
    pub cut_out: Option<AlphaMask>,
}

impl AreaLight {
    fn point_at(&self, b: Vec3) -> Vec3 {
        self.corners[0] * b.x + self.corners[1] * b.y + self.corners[2] * b.z
    }

    fn uv_at(&self, b: Vec3) -> Vec2 {
        self.uvs[0] * b.x + self.uvs[1] * b.y + self.uvs[2] * b.z
    }

    /// Emitted radiance at barycentric coordinates `b`.
    fn radiance_at(&self, textures: &[Texture], b: Vec3) -> Vec3 {
        match self.texture {
            None => self.emission,
            Some(t) => self.emission * t.sample(textures, self.uv_at(b)).truncate(),
        }
    }

    /// Whether the emitter's surface is present at barycentric coordinates `b` (not cut out).
    fn present_at(&self, textures: &[Texture], b: Vec3) -> bool {
        self.cut_out
            .is_none_or(|mask| mask.covers(textures, self.uv_at(b)))
    }

    #[inline]
    pub(super) fn illuminate(
        &self,
        textures: &[Texture],
        receiver: Vec3,
        u: Vec2,
    ) -> Option<Illumination> {
        let b = sample_uniform_triangle(u);
        if !self.present_at(textures, b) {
            return None;
        }
        let to_light = self.point_at(b) - receiver;
        let distance_sq = to_light.length_squared();
        let distance = distance_sq.sqrt();
        let direction = to_light / distance;
        let cos_at_light = self.normal.dot(-direction);
        if !(cos_at_light > 0.0 && distance > 0.0) {
            return None;
        }
        let inv_area = 1.0 / self.area;
        Some(Illumination {
            direction,
            distance,
            value: self.radiance_at(textures, b),
            // Area to solid angle at the receiver: p_w = p_a · d² / cos θ_light.
            direct_pdf_w: inv_area * distance_sq / cos_at_light,
            emission_pdf_w: inv_area * cosine_hemisphere_pdf(cos_at_light),
            cos_at_light,
        })
    }

    pub(super) fn emit(&self, textures: &[Texture], u_pos: Vec2, u_dir: Vec2) -> Option<Emission> {
        let b = sample_uniform_triangle(u_pos);
        let local = sample_cosine_hemisphere(u_dir);
        let cos_at_light = local.z;
        if cos_at_light <= 0.0 || !self.present_at(textures, b) {
            return None;
        }
        let inv_area = 1.0 / self.area;
        Some(Emission {
            value: self.radiance_at(textures, b),
            position: self.point_at(b),
            direction: Frame::from_z(self.normal).to_world(local),
            emission_pdf_w: inv_area * cosine_hemisphere_pdf(cos_at_light),
            direct_pdf_a: inv_area,
            cos_at_light,
        })
    }

    /// Radiance seen by a ray with unit direction `ray_dir` hitting the light at barycentrics
    /// (u, v); zero from behind.
    #[inline]
    pub fn radiance_on_hit(
        &self,
        textures: &[Texture],
        ray_dir: Vec3,
        u: f32,
        v: f32,
    ) -> Option<HitEmission> {
        let cos_out = self.normal.dot(-ray_dir);
        if cos_out <= 0.0 {
            return None;
        }
        let inv_area = 1.0 / self.area;
        Some(HitEmission {
            radiance: self.radiance_at(textures, Vec3::new(1.0 - u - v, u, v)),
            direct_pdf_a: inv_area,
            emission_pdf_w: inv_area * cosine_hemisphere_pdf(cos_out),
        })
    }

    /// Emitted power π · A · L̄ (one-sided Lambertian emitter).
    pub(super) fn power(&self, textures: &[Texture]) -> f32 {
        let mean = match self.texture {
            None => self.emission,
            Some(t) => self.emission * textures[t.index].average().truncate(),
        };
        std::f32::consts::PI * self.area * channel_mean(mean)
    }
}
