//! Thin-walled dielectric sheet (glTF transmission without KHR_materials_volume): light is
//! reflected or passes through without bending, with the sheet's multiple-bounce
//! reflectance R' = R + T²R/(1 − R²), T' = 1 − R' ([`thin_sheet_reflectance`]).
//!
//! * Smooth (pbrt-v4 `ThinDielectricBxDF`): a mirror delta with coefficient R'(cos θo) and a
//!   straight-through delta ωi = −ωo with coefficient T'(cos θo)·tint; no 1/η² (η = 1).
//! * Rough: the GGX reflection lobe f_r = R'(ωo·m) D G2 / (4 cos θo cos θi) and its mirror
//!   image through the tangent plane for transmission:
//!   f_t(ωo, ωi) = T'(ωo·m̃) D(m̃) G2(ωo, ω̃i) / (4 cos θo |cos θi|)·tint, with
//!   ω̃i = (ωi.x, ωi.y, −ωi.z) and m̃ = normalize(ωo + ω̃i). Sampled with visible normals:
//!   reflect ωo about m, keep it with probability R'(ωo·m), else mirror it.

use super::fresnel::{fresnel_dielectric, reflect, thin_sheet_reflectance};
use super::lobe::{
    Lobe, LobeSample, interface_delta_prob, interface_selection_weight, microfacet_kind,
};
use super::microfacet::Ggx;
use super::{LobeKind, TransportMode};
use glam::{Vec2, Vec3};

/// Thin dielectric sheet with IOR `ior` on both sides.
#[derive(Clone, Debug)]
pub(super) struct ThinDielectric {
    /// Mixture weight.
    pub weight: f32,
    /// Transmission tint (glTF base color).
    pub tint: Vec3,
    pub ior: f32,
    /// `None` for a smooth sheet.
    pub ggx: Option<Ggx>,
}

fn mirror(w: Vec3) -> Vec3 {
    Vec3::new(w.x, w.y, -w.z)
}

impl ThinDielectric {
    /// Sheet reflectance R' for the cosine `cos` with the (micro)surface normal.
    fn reflectance(&self, cos: f32) -> f32 {
        thin_sheet_reflectance(fresnel_dielectric(cos, self.ior))
    }
}

impl Lobe for ThinDielectric {
    fn eval(&self, wo: Vec3, wi: Vec3, _eta: f32, _mode: TransportMode) -> (Vec3, f32) {
        let Some(ggx) = self.ggx else {
            return (Vec3::ZERO, 0.0);
        };
        let transmitted = wi.z < 0.0;
        let wr = if transmitted { mirror(wi) } else { wi };
        let Some(m) = (wo + wr).try_normalize() else {
            return (Vec3::ZERO, 0.0);
        };
        let r = self.reflectance(wo.dot(m));
        let (fresnel, tint) = if transmitted {
            (1.0 - r, self.tint)
        } else {
            (r, Vec3::ONE)
        };
        let f_cos = self.weight * fresnel * ggx.d(m) * ggx.g2(wo, wr) / (4.0 * wo.z);
        (
            tint * f_cos,
            ggx.visible_pdf(wo, m) * fresnel / (4.0 * wo.dot(m)),
        )
    }

    fn sample(
        &self,
        wo: Vec3,
        _eta: f32,
        u_sub: f32,
        u: Vec2,
        _mode: TransportMode,
    ) -> Option<LobeSample> {
        let Some(ggx) = self.ggx else {
            let r = self.reflectance(wo.z);
            let (wi, weight, prob, transmitted) = if u_sub < r {
                (
                    Vec3::new(-wo.x, -wo.y, wo.z),
                    Vec3::splat(self.weight * r),
                    r,
                    false,
                )
            } else {
                (-wo, self.tint * (self.weight * (1.0 - r)), 1.0 - r, true)
            };
            return Some(LobeSample::Delta {
                wi,
                weight,
                prob,
                transmitted,
                eta: 1.0,
            });
        };
        let m = ggx.sample_visible(wo, u)?;
        let wr = reflect(wo, m);
        if wr.z <= 0.0 {
            return None;
        }
        let wi = if u_sub < self.reflectance(wo.dot(m)) {
            wr
        } else {
            mirror(wr)
        };
        Some(LobeSample::Direction(wi))
    }

    fn delta_prob(&self, wo: Vec3, _eta: f32, transmitted: bool) -> f32 {
        interface_delta_prob(self.ggx.as_ref(), self.reflectance(wo.z), transmitted)
    }

    fn selection_weight(&self, wo: Vec3, _eta: f32) -> f32 {
        interface_selection_weight(self.weight, self.tint, self.reflectance(wo.z))
    }

    fn kind(&self) -> LobeKind {
        microfacet_kind(self.ggx.as_ref())
    }
}
