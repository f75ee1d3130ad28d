//! Reciprocity of reflection, the η² relation of refraction, and the adjoint relation
//! between the transport modes; n_s = n_g unless stated.

use super::*;
use crate::sampling::{Rng, Sampler, sample_uniform_sphere};

/// Random direction pairs (a, b) with a on the front and b on the side `same_side` says.
fn pairs(seed: u64, same_side: bool) -> impl Iterator<Item = (Vec3, Vec3)> {
    let mut rng = Rng::new(seed, 9);
    let n = n_g();
    std::iter::repeat_with(move || {
        let mut a = sample_uniform_sphere(rng.uniform2());
        let mut b = sample_uniform_sphere(rng.uniform2());
        if a.dot(n) < 0.0 {
            a = -a;
        }
        if (b.dot(n) > 0.0) != same_side {
            b = -b;
        }
        (a, b)
    })
    .filter(move |(a, b)| a.dot(n).abs() > 0.02 && b.dot(n).abs() > 0.02)
    .take(2000)
}

/// f(wo, wi) without the cosine (radiance mode: f_cos / |wi·n_s|).
fn f(bsdf: &Bsdf, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
    bsdf.eval(wo, wi, mode).f_cos / wi.dot(n_g()).abs()
}

#[test]
fn reflection_is_reciprocal() {
    for &roughness in &ROUGH_SWEEP {
        for (name, params) in material_classes(roughness) {
            let b = bsdf(&params);
            for (wo, wi) in pairs(1, true) {
                for mode in MODES {
                    let (fwd, rev) = (f(&b, wo, wi, mode), f(&b, wi, wo, mode));
                    assert!(close(fwd, rev, 1e-3), "{name}, {mode:?}: {fwd} vs {rev}");
                }
            }
        }
    }
}

#[test]
fn lambert_is_reciprocal_and_exact() {
    let base = Vec3::new(0.7, 0.2, 0.4);
    let b = bsdf(&lambert(base));
    for (wo, wi) in pairs(2, true) {
        let value = f(&b, wo, wi, TransportMode::Radiance);
        assert!(close(value, base / std::f32::consts::PI, 1e-5), "{value}");
    }
}

#[test]
fn refraction_obeys_the_eta_squared_relation() {
    // Convention: f(a, b) = eval(wo = a, wi = b), radiance mode (light flowing b → a); η_a,
    // η_b are the IORs of the sides of a and b. Then f(a, b) / η_a² = f(b, a) / η_b²
    // (Veach 1997, §5.2). Here a is outside (η_a = 1) and b inside (η_b = ior).
    for ior in [1.5f32, 1.33] {
        for &roughness in &ROUGH_SWEEP {
            let params = BsdfParams {
                base_color: Vec3::ONE,
                ..glass(roughness, ior)
            };
            let b = bsdf(&params);
            let mut nonzero = 0;
            for (a, bb) in pairs(3, false).filter(|(a, b)| well_conditioned(*a, *b, ior)) {
                let (fab, fba) = (
                    f(&b, a, bb, TransportMode::Radiance),
                    f(&b, bb, a, TransportMode::Radiance),
                );
                let (lhs, rhs) = (fab, fba / (ior * ior));
                assert!(
                    close(lhs, rhs, 2e-3),
                    "ior {ior} r {roughness}: {lhs} vs {rhs}"
                );
                nonzero += usize::from(fab.max_element() > 0.0);
            }
            assert!(nonzero > 100, "too few transmission pairs with a value");
        }
    }
}

#[test]
fn importance_mode_is_the_adjoint() {
    // With n_s = n_g: f_importance(a, b) = f_radiance(b, a), for reflection and refraction.
    for &roughness in &ROUGH_SWEEP {
        for (name, params) in material_classes(roughness) {
            let b = bsdf(&params);
            for same_side in [true, false] {
                let ior = params.ior;
                for (wo, wi) in pairs(4, same_side).filter(|(a, b)| well_conditioned(*a, *b, ior)) {
                    let imp = f(&b, wo, wi, TransportMode::Importance);
                    let rad = f(&b, wi, wo, TransportMode::Radiance);
                    assert!(close(imp, rad, 2e-3), "{name}: {imp} vs {rad}");
                }
            }
        }
    }
}

#[test]
fn thin_sheet_transmission_is_symmetric() {
    let b = bsdf(&thin_glass(0.3));
    for (wo, wi) in pairs(5, false) {
        let (fwd, rev) = (
            f(&b, wo, wi, TransportMode::Radiance),
            f(&b, wi, wo, TransportMode::Radiance),
        );
        assert!(close(fwd, rev, 1e-3), "{fwd} vs {rev}");
    }
}
