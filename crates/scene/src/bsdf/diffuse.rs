//! Lambertian diffuse under a Schlick-Fresnel GGX specular layer, with reciprocal
//! energy-conserving albedo scaling (Kelemen & Szirmay-Kalos 2001; Kulla & Conty 2017):
//!
//! f(ωo, ωi) = ρ/π · (1 − E(μo)) (1 − E(μi)) / (1 − E_avg)
//!
//! where E is the directional albedo of the specular layer ([`super::albedo`]). Its
//! directional albedo is exactly ρ (1 − E(μo)), so layer + diffuse reflect E + ρ(1 − E) ≤ 1.
//! With F0 = F90 = 0 it is exactly Lambert. Sampled by the cosine-weighted hemisphere.

use super::albedo::SpecularAlbedo;
use super::lobe::{Lobe, LobeSample, mean};
use super::{FlatDiffuse, LobeKind, TransportMode};
use crate::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// Energy-compensated diffuse lobe.
#[derive(Clone, Debug)]
pub(super) struct CompensatedDiffuse {
    /// ρ (with the mixture weight).
    albedo: Vec3,
    /// Albedo E of the specular layer above; `None` when the layer reflects nothing (then
    /// the lobe is plain Lambert and skips the albedo lookups).
    layer: Option<SpecularAlbedo>,
    /// ρ / (π (1 − E_avg)), zero where E_avg = 1 (nothing gets through the layer).
    scale: Vec3,
}

impl CompensatedDiffuse {
    /// Diffuse albedo `albedo` under the specular layer `layer`.
    pub fn new(albedo: Vec3, layer: SpecularAlbedo) -> CompensatedDiffuse {
        let transmitted = Vec3::ONE - layer.average();
        let scale = Vec3::select(
            transmitted.cmpgt(Vec3::splat(1e-6)),
            albedo * FRAC_1_PI / transmitted,
            Vec3::ZERO,
        );
        CompensatedDiffuse {
            albedo,
            layer: layer.reflects().then_some(layer),
            scale,
        }
    }

    /// The lobe as plain numbers.
    pub fn flat(&self) -> FlatDiffuse {
        FlatDiffuse {
            albedo: self.albedo,
            scale: self.scale,
            layer: self.layer.map(|layer| layer.flat()),
        }
    }

    /// f = ρ/π when no layer reflects above the lobe (plain Lambert).
    pub fn lambert(&self) -> Option<Vec3> {
        self.layer.is_none().then_some(self.scale)
    }

    /// 1 − E(μ) of the layer.
    fn layer_transmission(&self, mu: f32) -> Vec3 {
        self.layer.as_ref().map_or(Vec3::ONE, |layer| {
            (Vec3::ONE - layer.directional(mu)).max(Vec3::ZERO)
        })
    }
}

impl Lobe for CompensatedDiffuse {
    fn eval(&self, wo: Vec3, wi: Vec3, _eta: f32, _mode: TransportMode) -> (Vec3, f32) {
        if wi.z <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let f = self.scale * self.layer_transmission(wo.z) * self.layer_transmission(wi.z);
        (f * wi.z, cosine_hemisphere_pdf(wi.z))
    }

    /// The cosine pdf, without the layer's albedo lookups.
    fn pdf(&self, _wo: Vec3, wi: Vec3, _eta: f32) -> f32 {
        if wi.z <= 0.0 {
            return 0.0;
        }
        cosine_hemisphere_pdf(wi.z)
    }

    fn sample(
        &self,
        _wo: Vec3,
        _eta: f32,
        _u_sub: f32,
        u: Vec2,
        _mode: TransportMode,
    ) -> Option<LobeSample> {
        let wi = sample_cosine_hemisphere(u);
        (wi.z > 0.0).then_some(LobeSample::Direction(wi))
    }

    fn delta_prob(&self, _wo: Vec3, _eta: f32, _transmitted: bool) -> f32 {
        0.0
    }

    fn selection_weight(&self, wo: Vec3, _eta: f32) -> f32 {
        mean(self.albedo * self.layer_transmission(wo.z))
    }

    /// Without a reflecting layer the transmission is exactly 1 at every angle.
    fn constant_selection_weight(&self) -> Option<f32> {
        self.layer.is_none().then(|| mean(self.albedo))
    }

    fn kind(&self) -> LobeKind {
        LobeKind::Diffuse
    }
}
