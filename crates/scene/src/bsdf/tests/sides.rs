//! One-sided and double-sided behaviour, transmission from both sides, and degenerate inputs.

use super::*;
use crate::sampling::{Rng, Sampler, sample_uniform_sphere};
use glam::Vec2;
use std::f32::consts::TAU;

fn mirror(w: Vec3) -> Vec3 {
    w - 2.0 * w.dot(n_g()) * n_g()
}

#[test]
fn one_sided_opaque_is_black_from_behind() {
    for params in [
        dielectric_base(0.5),
        conductor(0.3),
        conductor(0.0),
        lambert(Vec3::ONE),
    ] {
        let b = Bsdf::new(&params, n_g(), n_g(), false);
        let wo = direction(-n_g(), 0.7, 0.3);
        for wi in [direction(-n_g(), 0.5, 2.0), direction(n_g(), 0.5, 2.0)] {
            assert_eq!(
                b.eval(wo, wi, TransportMode::Radiance),
                crate::bsdf::BsdfEval::default()
            );
        }
        assert!(
            b.sample(wo, 0.5, Vec2::splat(0.5), TransportMode::Radiance)
                .is_none()
        );
    }
}

#[test]
fn double_sided_mirrors_the_front() {
    let mut rng = Rng::new(31, 0);
    // Opaque materials only: for transmissive ones the back is the inside of the medium.
    for params in [dielectric_base(0.5), conductor(0.3), lambert(Vec3::ONE)] {
        let b = Bsdf::new(&params, n_g(), n_g(), true);
        for _ in 0..500 {
            let wo = direction(n_g(), 0.05 + 0.95 * rng.uniform(), TAU * rng.uniform());
            let wi = direction(n_g(), 0.05 + 0.95 * rng.uniform(), TAU * rng.uniform());
            let front = b.eval(wo, wi, TransportMode::Radiance);
            let back = b.eval(mirror(wo), mirror(wi), TransportMode::Radiance);
            assert!(
                close(front.f_cos, back.f_cos, 1e-4),
                "{front:?} vs {back:?}"
            );
            assert!((front.pdf_fwd - back.pdf_fwd).abs() <= 1e-4 * front.pdf_fwd);
        }
        let s = b.sample(
            mirror(direction(n_g(), 0.6, 0.0)),
            0.5,
            Vec2::splat(0.3),
            TransportMode::Radiance,
        );
        assert!(s.is_some_and(|s| s.wi.dot(n_g()) < 0.0 && !s.transmitted));
    }
}

#[test]
fn transmission_works_from_both_sides() {
    let ior = 1.5;
    let b = Bsdf::new(&glass(0.0, ior), n_g(), n_g(), false);
    for (n, eta) in [(n_g(), ior), (-n_g(), 1.0 / ior)] {
        let wo = direction(n, 0.95, 0.0);
        let s = b
            .sample(wo, 0.999, Vec2::ZERO, TransportMode::Radiance)
            .unwrap();
        assert!(s.transmitted && (s.eta - eta).abs() < 1e-6 && s.wi.dot(n) < 0.0);
        // Snell's law with the relative IOR of the side of wo.
        let sin_o = (1.0 - wo.dot(n).powi(2)).sqrt();
        let sin_i = (1.0 - s.wi.dot(n).powi(2)).sqrt();
        assert!((sin_o - eta * sin_i).abs() < 1e-5);
    }
    // Beyond the critical angle from inside: total internal reflection only.
    let wo = direction(-n_g(), 0.3, 0.0);
    for u in [0.0, 0.5, 0.999] {
        let s = b
            .sample(wo, u, Vec2::ZERO, TransportMode::Radiance)
            .unwrap();
        assert!(!s.transmitted && (s.f_cos / s.pdf_fwd - Vec3::ONE).abs().max_element() < 1e-5);
    }
    // Thin sheets pass straight through with η = 1 from either side.
    let thin = Bsdf::new(&thin_glass(0.0), n_g(), n_g(), false);
    for n in [n_g(), -n_g()] {
        let wo = direction(n, 0.8, 1.0);
        let s = thin
            .sample(wo, 0.999, Vec2::ZERO, TransportMode::Radiance)
            .unwrap();
        assert!(s.transmitted && s.eta == 1.0 && (s.wi + wo).length() < 1e-5);
    }
}

#[test]
fn inconsistent_shading_normal_pairs_are_black() {
    // wi above n_g but below n_s: reflection by n_g, transmission by n_s.
    let n_s = tilted_normal(0.5);
    let f = Frame::from_z(n_g());
    let wi = (n_g() * 0.1 - f.x).normalize();
    assert!(wi.dot(n_g()) > 0.0 && wi.dot(n_s) < 0.0);
    let wo = direction(n_g(), 0.8, 0.0);
    for params in [dielectric_base(0.5), glass(0.5, 1.5), mixture(0.5)] {
        let b = Bsdf::new(&params, n_g(), n_s, true);
        assert_eq!(b.eval(wo, wi, TransportMode::Radiance).f_cos, Vec3::ZERO);
        assert_eq!(b.eval(wo, wi, TransportMode::Importance).f_cos, Vec3::ZERO);
    }
}

#[test]
fn degenerate_inputs_give_no_nan() {
    let mut rng = Rng::new(32, 0);
    let t = Frame::from_z(n_g()).x;
    let special = [
        n_g(),
        -n_g(),
        t,
        -t,
        Vec3::ZERO,
        Vec3::NAN,
        Vec3::new(f32::INFINITY, 0.0, 0.0),
    ];
    let shading = [n_g(), tilted_normal(0.4), tilted_normal(1.5)];
    for &roughness in &ROUGHNESS_SWEEP {
        for (name, params) in material_classes(roughness) {
            for &n_s in &shading {
                for double_sided in [false, true] {
                    let b = Bsdf::new(&params, n_g(), n_s, double_sided);
                    for &wo in &special {
                        for _ in 0..20 {
                            let wi = sample_uniform_sphere(rng.uniform2());
                            for mode in MODES {
                                for (a, c) in [(wo, wi), (wi, wo), (wo, wo), (wo, -wo)] {
                                    let e = b.eval(a, c, mode);
                                    assert!(
                                        e.f_cos.is_finite()
                                            && e.pdf_fwd.is_finite()
                                            && e.pdf_rev.is_finite(),
                                        "{name}: {e:?}"
                                    );
                                    assert!(e.f_cos.min_element() >= 0.0 && e.pdf_fwd >= 0.0);
                                }
                                for u in [0.0, 0.5, 1.0 - f32::EPSILON] {
                                    if let Some(s) = b.sample(wo, u, Vec2::new(u, 1.0 - u), mode) {
                                        assert!(
                                            s.f_cos.is_finite()
                                                && s.pdf_fwd > 0.0
                                                && s.pdf_rev.is_finite(),
                                            "{name}: {s:?}"
                                        );
                                        assert!((s.wi.length() - 1.0).abs() < 1e-4);
                                    }
                                }
                            }
                        }
                    }
                    // Grazing wo: exactly in the tangent plane.
                    assert!(
                        b.sample(t, 0.5, Vec2::splat(0.5), TransportMode::Radiance)
                            .is_none()
                    );
                }
            }
        }
    }
}

#[test]
fn nan_parameters_are_sanitized() {
    let params = BsdfParams {
        base_color: Vec3::new(f32::NAN, 0.5, -1.0),
        metallic: f32::NAN,
        roughness: f32::INFINITY,
        specular: -3.0,
        specular_color: Vec3::NAN,
        transmission: 2.0,
        ior: f32::NAN,
        thin_walled: false,
    };
    let b = bsdf(&params);
    let wo = direction(n_g(), 0.7, 0.0);
    for u in [0.1f32, 0.6, 0.95] {
        if let Some(s) = b.sample(wo, u, Vec2::splat(u), TransportMode::Radiance) {
            assert!(s.f_cos.is_finite() && s.f_cos.min_element() >= 0.0);
        }
    }
}
