//! Energy: directional albedo ∫ f_cos dωi, estimated by importance sampling with fixed
//! seeds. Bounds are "≤ 1 + 4σ + 1e-4" with σ the standard error of the estimate, plus the
//! documented table tolerance where the tabulated specular albedo enters.

use super::*;
use crate::bsdf::albedo::SpecularAlbedo;
use crate::bsdf::albedo::tests::TABLE_TOLERANCE;
use crate::bsdf::ggx_alpha;
use crate::bsdf::microfacet::Ggx;
use crate::testing::{Estimate, estimate_albedo};

/// The sharpest rough lobe (α = 10⁻⁴), beside the sweep: energy tests resolve it, chi-square
/// cells do not.
const POLISHED: f32 = 0.01;

/// Samples per albedo estimate.
const N: usize = 100_000;
/// Float round-off allowance.
const EPS: f64 = 1e-4;

fn albedo(bsdf: &Bsdf, wo: Vec3, mode: TransportMode) -> Estimate {
    estimate_albedo(bsdf, wo, mode, N, 0xA1BED0)
}

/// Incident directions at the cosines `cosines`, from the front and (for transmissive
/// materials) the back.
fn incident(params: &BsdfParams, cosines: &[f32]) -> Vec<Vec3> {
    let mut w: Vec<Vec3> = cosines.iter().map(|&c| direction(n_g(), c, 0.4)).collect();
    if is_transmissive(params) {
        w.extend(cosines.iter().map(|&c| direction(-n_g(), c, 2.4)));
    }
    w
}

#[test]
fn lambert_albedo_is_base_color() {
    let base = Vec3::new(0.9, 0.5, 0.1);
    let b = bsdf(&lambert(base));
    for &c in &COS_SWEEP {
        let e = albedo(&b, direction(n_g(), c, 0.0), TransportMode::Radiance);
        let err = (e.mean - base.as_dvec3()).abs().max_element();
        assert!(err <= 4.0 * e.std_err.max_element() + EPS, "cos {c}: {e:?}");
    }
}

#[test]
fn white_materials_conserve_energy() {
    // White base color: the albedo may not exceed 1 (importance mode for transmission:
    // that is flux conservation; radiance mode adds the 1/η² of refraction).
    for &roughness in ROUGHNESS_SWEEP.iter().chain(&[POLISHED]) {
        for (name, params) in material_classes(roughness) {
            let params = BsdfParams {
                base_color: Vec3::ONE,
                ..params
            };
            let table = if params.transmission < 1.0 && params.metallic < 1.0 {
                TABLE_TOLERANCE as f64
            } else {
                0.0
            };
            let b = bsdf(&params);
            for wo in incident(&params, &[0.05, 0.5, 1.0]) {
                let e = albedo(&b, wo, TransportMode::Importance);
                assert!(
                    e.mean.max_element() <= 1.0 + 4.0 * e.std_err.max_element() + EPS + table,
                    "{name}, wo·n = {}: {e:?}",
                    wo.dot(n_g())
                );
            }
        }
    }
}

#[test]
fn white_dielectric_base_reflects_everything() {
    // Energy-conserving diffuse scaling: white base + specular layer has albedo 1 at every
    // angle and roughness (up to the tabulation error of the layer's albedo).
    for &roughness in ROUGHNESS_SWEEP.iter().chain(&[POLISHED]) {
        let b = bsdf(&dielectric_base(roughness));
        for &c in &COS_SWEEP {
            let e = albedo(&b, direction(n_g(), c, 1.0), TransportMode::Radiance);
            let err = (e.mean - glam::DVec3::ONE).abs().max_element();
            let tol = 4.0 * e.std_err.max_element() + EPS + TABLE_TOLERANCE as f64;
            assert!(err <= tol, "roughness {roughness}, cos {c}: {e:?}");
        }
    }
}

#[test]
fn smooth_interfaces_conserve_energy_exactly() {
    // R + T = 1 (and R' + T' = 1 for a thin sheet): every sample has weight exactly 1.
    for params in [glass(0.0, 1.5), glass(0.0, 1.33), thin_glass(0.0)] {
        let b = bsdf(&params);
        for wo in incident(&params, &COS_SWEEP) {
            let e = albedo(&b, wo, TransportMode::Importance);
            assert!(
                (e.mean - glam::DVec3::ONE).abs().max_element() < EPS,
                "{params:?}: {e:?}"
            );
        }
    }
}

#[test]
fn white_conductor_albedo_matches_table() {
    // Independent check of the tabulated albedo: F0 = F90 = 1 gives E = A + B, which the
    // sampled estimate (sample + eval code path) must reproduce.
    for &roughness in &ROUGH_SWEEP {
        let params = BsdfParams {
            base_color: Vec3::ONE,
            ..conductor(roughness)
        };
        let b = bsdf(&params);
        for &c in &COS_SWEEP {
            let e = albedo(&b, direction(n_g(), c, 0.2), TransportMode::Radiance);
            let ggx = ggx_alpha(roughness).map(|alpha| Ggx { alpha });
            let table = SpecularAlbedo::new(Vec3::ONE, Vec3::ONE, ggx)
                .directional(c)
                .x as f64;
            let tol = 4.0 * e.std_err.x + EPS + TABLE_TOLERANCE as f64;
            assert!(
                (e.mean.x - table).abs() <= tol,
                "roughness {roughness}, cos {c}: {e:?} vs {table}"
            );
        }
    }
}

#[test]
fn radiance_refraction_scales_by_inverse_eta_squared() {
    // Smooth glass, radiance mode: the transmitted weight is T/η² (η = η_i/η_o).
    let ior = 1.5;
    let b = bsdf(&glass(0.0, ior));
    for (n, eta) in [(n_g(), ior), (-n_g(), 1.0 / ior)] {
        let wo = direction(n, 0.9, 0.0);
        // u_lobe close to 1 selects transmission (reflection takes [0, R)).
        let s = b
            .sample(wo, 0.999, glam::Vec2::ZERO, TransportMode::Radiance)
            .unwrap();
        assert!(s.transmitted && (s.eta - eta).abs() < 1e-6);
        let weight = s.f_cos / s.pdf_fwd;
        assert!(
            (weight - Vec3::splat(1.0 / (eta * eta)))
                .abs()
                .max_element()
                < 1e-5,
            "{s:?}"
        );
        let s = b
            .sample(wo, 0.999, glam::Vec2::ZERO, TransportMode::Importance)
            .unwrap();
        assert!((s.f_cos / s.pdf_fwd - Vec3::ONE).abs().max_element() < 1e-5);
    }
}
