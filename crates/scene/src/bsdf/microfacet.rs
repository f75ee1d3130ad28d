//! Trowbridge-Reitz (GGX) microfacet distribution with the Smith height-correlated
//! masking-shadowing function, and visible-normal sampling.
//!
//! All vectors are in the local shading frame (normal = +z) and unit length.
//! * D(m) = 1 / (π α² cos⁴θm (1 + tan²θm / α²)²)   (Walter et al. 2007, eq. 33)
//! * Λ(ω) = (√(1 + α² tan²θ) − 1) / 2,  G1(ω) = 1 / (1 + Λ(ω))
//! * G2(ωo, ωi) = 1 / (1 + Λ(ωo) + Λ(ωi))   (height-correlated; Heitz 2014,
//!   "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs")
//! * visible normals: D_ωo(m) = G1(ωo) max(0, ωo·m) D(m) / cos θo   (Heitz 2014)

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Isotropic GGX distribution with roughness `alpha` (> 0).
#[derive(Clone, Copy, Debug)]
pub(super) struct Ggx {
    pub alpha: f32,
}

impl Ggx {
    /// Normal distribution D(m) (per steradian of microfacet normals, projected-area
    /// normalized: ∫ D(m) cos θm dm = 1). Written with the tangential components so that
    /// it stays accurate in `f32` for tiny α.
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let t = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
        1.0 / (PI * a2 * t * t)
    }

    /// Smith Λ(ω) for the GGX distribution.
    pub fn lambda(&self, w: Vec3) -> f32 {
        let z2 = w.z * w.z;
        if z2 == 0.0 {
            return f32::INFINITY;
        }
        let tan2 = (w.x * w.x + w.y * w.y) / z2;
        0.5 * ((1.0 + self.alpha * self.alpha * tan2).sqrt() - 1.0)
    }

    /// Masking function G1(ω) = 1 / (1 + Λ(ω)).
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing G2(ωo, ωi) = 1 / (1 + Λ(ωo) + Λ(ωi)) (used for
    /// both reflection and transmission).
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Density of visible normals D_ωo(m) (per steradian of m), for `wo.z > 0`.
    pub fn visible_pdf(&self, wo: Vec3, m: Vec3) -> f32 {
        self.g1(wo) * wo.dot(m).max(0.0) * self.d(m) / wo.z
    }

    /// Samples a visible normal m ~ D_ωo for `wo.z > 0`, by the spherical-cap method of
    /// Dupuy & Benyoub 2023 ("Sampling Visible GGX Normals with Spherical Caps"):
    /// stretch wo to the α = 1 configuration, sample the cap of the unit sphere that the
    /// hemisphere of wo projects to, add wo, and unstretch. `None` only in degenerate cases.
    pub fn sample_visible(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        let wo_std = Vec3::new(wo.x * self.alpha, wo.y * self.alpha, wo.z).normalize();
        let phi = 2.0 * PI * u.x;
        let z = (1.0 - u.y) * (1.0 + wo_std.z) - wo_std.z;
        let sin_theta = (1.0 - z * z).clamp(0.0, 1.0).sqrt();
        let c = Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), z);
        let h = c + wo_std;
        let m = Vec3::new(h.x * self.alpha, h.y * self.alpha, h.z.max(0.0)).try_normalize()?;
        (m.z > 0.0).then_some(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Frame;
    use crate::sampling::Sampler;
    use crate::testing::{Chi2Config, chi2_test, integrate_sphere};

    fn up() -> Frame {
        Frame::from_z(Vec3::Z)
    }

    #[test]
    fn distribution_is_normalized() {
        for alpha in [0.01f32, 0.1, 0.5, 1.0] {
            let ggx = Ggx { alpha };
            let projected = integrate_sphere(&up(), |m| (ggx.d(m) * m.z.max(0.0)) as f64);
            assert!((projected - 1.0).abs() < 1e-4, "alpha {alpha}: {projected}");
            // The visible normals of any direction are a probability density too.
            let wo = Vec3::new(0.8, 0.0, 0.6);
            let visible = integrate_sphere(&up(), |m| ggx.visible_pdf(wo, m) as f64);
            assert!((visible - 1.0).abs() < 1e-4, "alpha {alpha}: {visible}");
        }
    }

    #[test]
    fn visible_normal_sampling_matches_pdf() {
        let cases = [(0.05f32, 0.9f32), (0.3, 0.2), (0.3, 1.0), (1.0, 0.05)];
        for (alpha, cos_o) in cases {
            let ggx = Ggx { alpha };
            let wo = Vec3::new((1.0 - cos_o * cos_o).sqrt(), 0.0, cos_o);
            let result = chi2_test(
                |rng| ggx.sample_visible(wo, rng.uniform2()),
                |m| ggx.visible_pdf(wo, m) as f64,
                &Chi2Config::default(),
                cases.len(),
            );
            assert!(result.passed, "alpha {alpha}, cos {cos_o}: {result:?}");
        }
    }
}
