//! Fresnel terms and the reflection/refraction geometry of a (micro)surface.
//!
//! Conventions: `wo` points away from the surface; `n` is a unit normal on the side of `wo`;
//! `eta` is the relative index of refraction η_t / η_i (transmitted side over incident side).

use glam::Vec3;

/// Schlick's approximation (1994): F = F0 + (F90 − F0)(1 − cos θ)^5 for `cos_theta` in [0, 1].
pub(super) fn schlick(f0: Vec3, f90: Vec3, cos_theta: f32) -> Vec3 {
    f0 + (f90 - f0) * schlick_weight(cos_theta)
}

/// The Schlick weight w = (1 − cos θ)^5, clamped to [0, 1].
pub(super) fn schlick_weight(cos_theta: f32) -> f32 {
    let m = (1.0 - cos_theta).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Unpolarized Fresnel reflectance of a dielectric interface (the exact Fresnel equations),
/// for light arriving with cosine `cos_i` (> 0, on the incident side) and relative IOR
/// `eta` = η_t / η_i. Returns 1 under total internal reflection.
pub(super) fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular)
}

/// Reflectance of a thin dielectric sheet (two parallel interfaces, infinitely many internal
/// bounces, no absorption), from the single-interface reflectance R:
/// R' = R + T²R / (1 − R²) with T = 1 − R (pbrt-v4 `ThinDielectricBxDF`). T' = 1 − R'.
pub(super) fn thin_sheet_reflectance(r: f32) -> f32 {
    if r >= 1.0 {
        return 1.0;
    }
    let t = 1.0 - r;
    r + t * t * r / (1.0 - r * r)
}

/// Mirror reflection of `wo` about `n`: 2 (wo·n) n − wo.
pub(super) fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    2.0 * wo.dot(n) * n - wo
}

/// Refraction of `wo` (with `wo·n > 0`) through the interface with normal `n` and relative
/// IOR `eta` (Snell's law); `None` under total internal reflection. The result points into
/// the other side: wt = −wo/η + (cos θi/η − cos θt) n.
pub(super) fn refract(wo: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = wo.dot(n);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-wo / eta + (cos_i / eta - cos_t) * n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_fresnel_values() {
        // Normal incidence: ((η − 1)/(η + 1))².
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
        assert_eq!(fresnel_dielectric(0.0, 1.5), 1.0);
        // Total internal reflection beyond the critical angle (sin θc = 1/1.5).
        assert_eq!(fresnel_dielectric(0.7, 1.0 / 1.5), 1.0);
        assert!(fresnel_dielectric(0.3, 1.0) < 1e-12);
    }

    #[test]
    fn fresnel_is_symmetric_across_the_interface() {
        for cos_i in [0.05f32, 0.3, 0.7, 1.0] {
            let wo = Vec3::new((1.0 - cos_i * cos_i).sqrt(), 0.0, cos_i);
            let wt = refract(wo, Vec3::Z, 1.5).unwrap();
            assert!((wt.length() - 1.0).abs() < 1e-5 && wt.z < 0.0);
            // Snell: sin θt = sin θi / η.
            assert!((wt.x.abs() - wo.x / 1.5).abs() < 1e-6);
            let back = fresnel_dielectric(-wt.z, 1.0 / 1.5);
            assert!((back - fresnel_dielectric(cos_i, 1.5)).abs() < 1e-5);
            // Refracting back returns the original direction.
            let wo2 = refract(-wt, Vec3::Z, 1.0 / 1.5).unwrap();
            assert!((wo2 + wo).length() < 1e-5);
        }
        assert!(refract(Vec3::new(0.8, 0.0, 0.6), Vec3::Z, 1.0 / 1.5).is_none());
    }

    #[test]
    fn thin_sheet_limits() {
        assert_eq!(thin_sheet_reflectance(0.0), 0.0);
        assert_eq!(thin_sheet_reflectance(1.0), 1.0);
        // R' = 2R/(1 + R) for a lossless sheet.
        assert!((thin_sheet_reflectance(0.04) - 0.08 / 1.04).abs() < 1e-6);
    }

    #[test]
    fn schlick_endpoints() {
        let (f0, f90) = (Vec3::splat(0.04), Vec3::ONE);
        assert_eq!(schlick(f0, f90, 1.0), f0);
        assert_eq!(schlick(f0, f90, 0.0), f90);
        assert!(
            (reflect(Vec3::new(0.6, 0.0, 0.8), Vec3::Z) - Vec3::new(-0.6, 0.0, 0.8)).length()
                < 1e-6
        );
    }
}
