//! GGX microfacet reflection with Schlick Fresnel: the metal lobe and the specular layer of
//! the dielectric base, merged (Schlick's F is linear in F0 and F90, so
//! metallic·F(F0ᵐ, F90ᵐ) + w·F(F0ᵈ, F90ᵈ) = F(metallic·F0ᵐ + w·F0ᵈ, metallic·F90ᵐ + w·F90ᵈ)).
//!
//! f(ωo, ωi) = F(ωo·m) D(m) G2(ωo, ωi) / (4 cos θo cos θi), m = normalize(ωo + ωi)
//! (Walter et al. 2007, eq. 20), sampled with visible normals: pdf = D_ωo(m) / (4 ωo·m).
//! Mirror (delta) at roughness 0 ([`ggx_alpha`](super::ggx_alpha)): coefficient F(cos θo).

use super::albedo::SpecularAlbedo;
use super::fresnel::{reflect, schlick};
use super::lobe::{Lobe, LobeSample, mean, microfacet_kind};
use super::microfacet::Ggx;
use super::{FlatSchlick, LobeKind, TransportMode};
use glam::{Vec2, Vec3};

/// Schlick-Fresnel GGX (or mirror) reflection; F0 and F90 include the mixture weights.
#[derive(Clone, Debug)]
pub(super) struct SchlickReflection {
    f0: Vec3,
    f90: Vec3,
    /// `None` for the smooth (mirror) case.
    ggx: Option<Ggx>,
    /// Directional albedo of the lobe (its selection weight).
    albedo: SpecularAlbedo,
}

impl SchlickReflection {
    /// Lobe with Schlick (F0, F90), GGX `ggx` or a mirror for `None`.
    pub fn new(f0: Vec3, f90: Vec3, ggx: Option<Ggx>) -> SchlickReflection {
        let albedo = SpecularAlbedo::new(f0, f90, ggx);
        SchlickReflection {
            f0,
            f90,
            ggx,
            albedo,
        }
    }
}

/// Minimum selection weight, relative to the largest Fresnel coefficient, so that a lobe
/// whose albedo estimate is tiny (F0 = 0 at normal incidence) is still sampled.
impl SchlickReflection {
    /// The lobe as plain numbers.
    pub fn flat(&self) -> FlatSchlick {
        FlatSchlick {
            f0: self.f0,
            f90: self.f90,
            alpha: self.ggx.map(|g| g.alpha),
            albedo: self.albedo.flat(),
        }
    }
}

const MIN_SELECTION: f32 = 1e-3;

impl Lobe for SchlickReflection {
    fn eval(&self, wo: Vec3, wi: Vec3, _eta: f32, _mode: TransportMode) -> (Vec3, f32) {
        let Some(ggx) = self.ggx else {
            return (Vec3::ZERO, 0.0);
        };
        if wi.z <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let Some(m) = (wo + wi).try_normalize() else {
            return (Vec3::ZERO, 0.0);
        };
        let d = ggx.d(m);
        let f_cos = schlick(self.f0, self.f90, wo.dot(m)) * (d * ggx.g2(wo, wi) / (4.0 * wo.z));
        (f_cos, ggx.visible_pdf(wo, m) / (4.0 * wo.dot(m)))
    }

    /// The visible-normal pdf, without the Fresnel term and the masking of `wi`.
    fn pdf(&self, wo: Vec3, wi: Vec3, _eta: f32) -> f32 {
        let Some(ggx) = self.ggx.filter(|_| wi.z > 0.0) else {
            return 0.0;
        };
        (wo + wi)
            .try_normalize()
            .map_or(0.0, |m| ggx.visible_pdf(wo, m) / (4.0 * wo.dot(m)))
    }

    fn sample(
        &self,
        wo: Vec3,
        _eta: f32,
        _u_sub: f32,
        u: Vec2,
        _mode: TransportMode,
    ) -> Option<LobeSample> {
        let Some(ggx) = self.ggx else {
            return Some(LobeSample::Delta {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: schlick(self.f0, self.f90, wo.z),
                prob: 1.0,
                transmitted: false,
                eta: 1.0,
            });
        };
        let wi = reflect(wo, ggx.sample_visible(wo, u)?);
        (wi.z > 0.0).then_some(LobeSample::Direction(wi))
    }

    fn delta_prob(&self, _wo: Vec3, _eta: f32, transmitted: bool) -> f32 {
        if self.ggx.is_none() && !transmitted {
            1.0
        } else {
            0.0
        }
    }

    fn selection_weight(&self, wo: Vec3, _eta: f32) -> f32 {
        let albedo = mean(self.albedo.directional(wo.z));
        albedo.max(MIN_SELECTION * self.f0.max(self.f90).max_element())
    }

    fn kind(&self) -> LobeKind {
        microfacet_kind(self.ggx.as_ref())
    }
}
