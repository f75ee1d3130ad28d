//! Dielectric interface between two media (glass, water): exact Fresnel reflection plus
//! refraction, smooth (delta) or rough GGX (Walter et al. 2007).
//!
//! With η = η(ωi side)/η(ωo side) (pbrt-v4's `etap`), m the (generalized) half vector:
//! * reflection: f_r = F(ωo·m) D G2 / (4 cos θo cos θi), m = normalize(ωo + ωi);
//! * transmission (Walter eq. 21, rearranged as in pbrt-v4):
//!   f_t = (1 − F(ωo·m)) D G2 |ωi·m| |ωo·m| / (|cos θi| cos θo (ωi·m + ωo·m/η)²) · s,
//!   m = ±normalize(ωo + η ωi), with s = 1/η² when transporting radiance and s = 1 for
//!   importance (so f_radiance(ωo, ωi) = f_importance(ωi, ωo): the adjoint).
//!
//! The transmitted part is tinted by the base color (glTF KHR_materials_transmission).
//!
//! Sampling: a visible normal m ~ D_ωo, then reflection with probability F(ωo·m), else
//! refraction, so pdf_r = D_ωo(m) F / (4 ωo·m), pdf_t = D_ωo(m) (1 − F) |ωi·m| / (ωi·m + ωo·m/η)².
//! Smooth: reflection with probability R = F(cos θo) and coefficient R, refraction with
//! probability T = 1 − R and coefficient T·s.

use super::fresnel::{fresnel_dielectric, reflect, refract};
use super::lobe::{
    Lobe, LobeSample, interface_delta_prob, interface_selection_weight, microfacet_kind,
};
use super::microfacet::Ggx;
use super::{LobeKind, TransportMode};
use glam::{Vec2, Vec3};

/// Refracting dielectric interface. Its relative IOR comes from the side of ωo (`eta`).
#[derive(Clone, Debug)]
pub(super) struct Dielectric {
    /// Mixture weight.
    pub weight: f32,
    /// Transmission tint (glTF base color).
    pub tint: Vec3,
    /// `None` for a smooth interface (also used for index-matched interfaces, η = 1).
    pub ggx: Option<Ggx>,
}

/// Radiance scaling of refracted transport, 1/η² (pbrt-v4 §9.5.2); 1 for importance.
fn refraction_scale(eta: f32, mode: TransportMode) -> f32 {
    match mode {
        TransportMode::Radiance => 1.0 / (eta * eta),
        TransportMode::Importance => 1.0,
    }
}

impl Dielectric {
    /// Microfacet normal of a transmission pair, oriented up; `None` for back-facing
    /// configurations (ωo·m ≤ 0 or ωi·m ≥ 0).
    fn transmission_half_vector(wo: Vec3, wi: Vec3, eta: f32) -> Option<Vec3> {
        let m = (wo + eta * wi).try_normalize()?;
        let m = if m.z < 0.0 { -m } else { m };
        (wo.dot(m) > 0.0 && wi.dot(m) < 0.0).then_some(m)
    }
}

impl Lobe for Dielectric {
    fn eval(&self, wo: Vec3, wi: Vec3, eta: f32, mode: TransportMode) -> (Vec3, f32) {
        let Some(ggx) = self.ggx else {
            return (Vec3::ZERO, 0.0);
        };
        if wi.z > 0.0 {
            let Some(m) = (wo + wi).try_normalize() else {
                return (Vec3::ZERO, 0.0);
            };
            let f = fresnel_dielectric(wo.dot(m), eta);
            let f_cos = self.weight * f * ggx.d(m) * ggx.g2(wo, wi) / (4.0 * wo.z);
            return (
                Vec3::splat(f_cos),
                ggx.visible_pdf(wo, m) * f / (4.0 * wo.dot(m)),
            );
        }
        let Some(m) = Self::transmission_half_vector(wo, wi, eta) else {
            return (Vec3::ZERO, 0.0);
        };
        let (wo_m, wi_m) = (wo.dot(m), wi.dot(m));
        let denom = (wi_m + wo_m / eta).powi(2);
        if denom <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let t = 1.0 - fresnel_dielectric(wo_m, eta);
        // f_t · |cos θi|: the |cos θi| of the denominator cancels.
        let f_cos = t * ggx.d(m) * ggx.g2(wo, wi) * (wi_m * wo_m).abs() / (wo.z * denom)
            * refraction_scale(eta, mode)
            * self.weight;
        let pdf = ggx.visible_pdf(wo, m) * wi_m.abs() / denom * t;
        (self.tint * f_cos, pdf)
    }

    fn sample(
        &self,
        wo: Vec3,
        eta: f32,
        u_sub: f32,
        u: Vec2,
        mode: TransportMode,
    ) -> Option<LobeSample> {
        let Some(ggx) = self.ggx else {
            let r = fresnel_dielectric(wo.z, eta);
            if u_sub < r {
                return Some(LobeSample::Delta {
                    wi: Vec3::new(-wo.x, -wo.y, wo.z),
                    weight: Vec3::splat(self.weight * r),
                    prob: r,
                    transmitted: false,
                    eta: 1.0,
                });
            }
            let wi = refract(wo, Vec3::Z, eta)?;
            let t = 1.0 - r;
            return Some(LobeSample::Delta {
                wi,
                weight: self.tint * (self.weight * t * refraction_scale(eta, mode)),
                prob: t,
                transmitted: true,
                eta,
            });
        };
        let m = ggx.sample_visible(wo, u)?;
        let f = fresnel_dielectric(wo.dot(m), eta);
        let wi = if u_sub < f {
            reflect(wo, m)
        } else {
            refract(wo, m, eta)?
        };
        let valid = if u_sub < f { wi.z > 0.0 } else { wi.z < 0.0 };
        valid.then_some(LobeSample::Direction(wi))
    }

    fn delta_prob(&self, wo: Vec3, eta: f32, transmitted: bool) -> f32 {
        let r = fresnel_dielectric(wo.z, eta);
        interface_delta_prob(self.ggx.as_ref(), r, transmitted)
    }

    fn selection_weight(&self, wo: Vec3, eta: f32) -> f32 {
        interface_selection_weight(self.weight, self.tint, fresnel_dielectric(wo.z, eta))
    }

    fn kind(&self) -> LobeKind {
        microfacet_kind(self.ggx.as_ref())
    }
}
