//! sample() agrees with eval(): the same value and pdfs for non-delta samples, exact reverse
//! pdfs, and the adjoint shading-normal correction.

use super::*;
use crate::bsdf::LobeKind;
use crate::sampling::{Rng, Sampler};
use std::f32::consts::TAU;

#[test]
fn sample_matches_eval() {
    let mut rng = Rng::new(21, 4);
    for &roughness in &ROUGHNESS_SWEEP {
        for (name, params) in material_classes(roughness) {
            for tilt in [0.0, 0.25] {
                let b = Bsdf::new(&params, n_g(), tilted_normal(tilt), false);
                for &c in &COS_SWEEP {
                    for side in [n_g(), -n_g()] {
                        let wo = direction(side, c, 0.9);
                        for mode in MODES {
                            for _ in 0..200 {
                                let (u_lobe, u) = (rng.uniform(), rng.uniform2());
                                let Some(s) = b.sample(wo, u_lobe, u, mode) else {
                                    continue;
                                };
                                assert!(
                                    s.f_cos.is_finite() && s.pdf_fwd > 0.0 && s.pdf_rev.is_finite()
                                );
                                assert_eq!(s.transmitted, s.wi.dot(n_g()) * wo.dot(n_g()) < 0.0);
                                if s.lobe == LobeKind::Specular {
                                    continue;
                                }
                                let e = b.eval(wo, s.wi, mode);
                                let ctx =
                                    format!("{name} tilt {tilt} cos {c} {mode:?}: {s:?} vs {e:?}");
                                assert!(close(s.f_cos, e.f_cos, 1e-4), "{ctx}");
                                assert!((s.pdf_fwd - e.pdf_fwd).abs() <= 1e-4 * e.pdf_fwd, "{ctx}");
                                assert!(
                                    (s.pdf_rev - e.pdf_rev).abs() <= 1e-4 * e.pdf_rev.max(1e-30),
                                    "{ctx}"
                                );
                                let rev = b.eval(s.wi, wo, mode).pdf_fwd;
                                assert!((s.pdf_rev - rev).abs() <= 1e-4 * rev.max(1e-30), "{ctx}");
                            }
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn pdf_alone_is_the_pdf_of_eval() {
    // Bsdf::pdf skips the value (Fresnel, masking of wi, the layer's albedo lookups) but must
    // return exactly the pdf eval() does, for every lobe mix, side and mode.
    let mut rng = Rng::new(23, 0);
    let mut non_zero = 0;
    for &roughness in &ROUGHNESS_SWEEP {
        for (name, params) in material_classes(roughness) {
            for tilt in [0.0, 0.25] {
                let b = Bsdf::new(&params, n_g(), tilted_normal(tilt), false);
                for _ in 0..400 {
                    let (wo, wi) = (random_direction(&mut rng), random_direction(&mut rng));
                    let expected = b.eval(wo, wi, TransportMode::Radiance).pdf_fwd;
                    assert_eq!(b.pdf(wo, wi), expected, "{name} tilt {tilt}: {wo} -> {wi}");
                    non_zero += usize::from(expected > 0.0);
                }
            }
        }
    }
    assert!(non_zero > 1000, "only {non_zero} pairs with a non-zero pdf");
}

#[test]
fn reverse_pdfs_are_the_pdf_back_from_wi() {
    // eval() and sample() take a reflection's reverse pdf from the forward evaluation's local
    // directions: it must be exactly Bsdf::pdf(wi, wo), which fixes the BSDF at wi anew, for
    // every lobe mix, side, sidedness and mode (transmissions take Bsdf::pdf itself).
    let mut rng = Rng::new(25, 0);
    let mut reflected = 0;
    for &roughness in &ROUGHNESS_SWEEP {
        for (name, params) in material_classes(roughness) {
            for (tilt, double_sided) in [(0.0, false), (0.25, false), (0.25, true)] {
                let b = Bsdf::new(&params, n_g(), tilted_normal(tilt), double_sided);
                for _ in 0..300 {
                    let (wo, wi) = (random_direction(&mut rng), random_direction(&mut rng));
                    let ctx = format!("{name} tilt {tilt} two-sided {double_sided}: {wo} -> {wi}");
                    for mode in MODES {
                        let e = b.eval(wo, wi, mode);
                        let expected = if e.pdf_fwd > 0.0 { b.pdf(wi, wo) } else { 0.0 };
                        assert_eq!(e.pdf_rev, expected, "{ctx} {mode:?}");
                        reflected +=
                            usize::from(expected > 0.0 && wo.dot(n_g()) * wi.dot(n_g()) > 0.0);
                        let (u_lobe, u) = (rng.uniform(), rng.uniform2());
                        if let Some(s) = b.sample(wo, u_lobe, u, mode)
                            && s.lobe != LobeKind::Specular
                        {
                            assert_eq!(s.pdf_rev, b.pdf(s.wi, wo), "{ctx} {mode:?}: {s:?}");
                        }
                    }
                }
            }
        }
    }
    assert!(reflected > 1000, "only {reflected} reflected pairs");
}

#[test]
fn delta_reverse_pdfs_of_pure_interfaces() {
    // For a single smooth interface the reverse choice has the same probability: R(θo) =
    // R(θi) for the mirror, and T is the same on both sides of a refraction.
    for params in [glass(0.0, 1.5), thin_glass(0.0), conductor(0.0)] {
        let b = bsdf(&params);
        let mut rng = Rng::new(22, 0);
        for &c in &COS_SWEEP {
            let wo = direction(n_g(), c, 0.1);
            for _ in 0..50 {
                let s = b
                    .sample(wo, rng.uniform(), rng.uniform2(), TransportMode::Radiance)
                    .unwrap();
                assert_eq!(s.lobe, LobeKind::Specular);
                assert!((s.pdf_rev - s.pdf_fwd).abs() < 1e-4, "{params:?}: {s:?}");
            }
        }
    }
}

#[test]
fn importance_mode_applies_the_shading_normal_correction() {
    // Veach 1997 §5.3: f_cos_importance(wo, wi) = f(wo, wi)·|wo·n_s||wi·n_g|/|wo·n_g|, so with
    // f(wo, wi) = f_radiance(wi, wo) (reciprocity / adjoint) it equals
    // f_cos_radiance(wi, wo) · |wi·n_g| / |wo·n_g|.
    let n_s = tilted_normal(0.35);
    let mut rng = Rng::new(23, 0);
    for (name, params) in material_classes(0.5) {
        let b = Bsdf::new(&params, n_g(), n_s, false);
        let mut checked = 0;
        for _ in 0..4000 {
            let wo = direction(n_g(), 0.05 + 0.95 * rng.uniform(), TAU * rng.uniform());
            let side = if rng.uniform() < 0.5 { n_g() } else { -n_g() };
            let wi = direction(side, 0.05 + 0.95 * rng.uniform(), TAU * rng.uniform());
            if !well_conditioned(wo, wi, params.ior) {
                continue;
            }
            let imp = b.eval(wo, wi, TransportMode::Importance).f_cos;
            let rad = b.eval(wi, wo, TransportMode::Radiance).f_cos;
            let expected = rad * (wi.dot(n_g()).abs() / wo.dot(n_g()).abs());
            assert!(close(imp, expected, 2e-3), "{name}: {imp} vs {expected}");
            checked += usize::from(imp.max_element() > 0.0);
        }
        assert!(checked > 500, "{name}: only {checked} non-zero pairs");
    }
}

#[test]
fn only_zero_roughness_is_delta() {
    let wo = direction(n_g(), 0.6, 0.0);
    for params in [conductor(0.0), glass(0.0, 1.5), thin_glass(0.0)] {
        let b = bsdf(&params);
        assert!(b.is_delta() && !b.has_non_delta());
        assert_eq!(b.classify(), LobeKind::Specular);
        let s = b
            .sample(wo, 0.3, glam::Vec2::new(0.2, 0.7), TransportMode::Radiance)
            .unwrap();
        assert_eq!(s.lobe, LobeKind::Specular);
        assert_eq!(
            b.eval(wo, s.wi, TransportMode::Radiance),
            crate::bsdf::BsdfEval::default()
        );
    }
    // A smooth coat over diffuse is not delta: the diffuse part can be connected.
    let b = bsdf(&dielectric_base(0.0));
    assert!(!b.is_delta());
    assert_eq!(b.classify(), LobeKind::Diffuse);

    // Any roughness above 0 is GGX, polished ones too (a point light's highlight needs it);
    // below r = 0.01 the lobe is that of r = 0.01 (α = MIN_ALPHA).
    let wi = direction(n_g(), 0.6, std::f32::consts::PI);
    for roughness in [0.001f32, 0.01, 0.02] {
        for params in [
            conductor(roughness),
            glass(roughness, 1.5),
            thin_glass(roughness),
        ] {
            let b = bsdf(&params);
            assert!(!b.is_delta() && b.has_non_delta(), "roughness {roughness}");
            assert_eq!(b.classify(), LobeKind::Glossy, "roughness {roughness}");
        }
    }
    let white = |roughness| BsdfParams {
        base_color: Vec3::ONE,
        ..conductor(roughness)
    };
    let mirror_peak = |r| bsdf(&white(r)).eval(wo, wi, TransportMode::Radiance);
    assert_eq!(mirror_peak(0.001), mirror_peak(0.01));
    // At the mirror direction f·cos = F D G2 / (4 cos θo) with F = 1 and D = 1/(π α²): the
    // peak of α = r² = 4·10⁻⁴ (G2 ≈ 1 this far from grazing).
    let peak = mirror_peak(0.02).f_cos.x;
    let expected = 1.0 / (std::f32::consts::PI * 4e-4 * 4e-4 * 4.0 * 0.6);
    assert!((peak / expected - 1.0).abs() < 0.01, "{peak} vs {expected}");
    assert_eq!(bsdf(&lambert(Vec3::ONE)).classify(), LobeKind::Diffuse);
    assert_eq!(bsdf(&mixture(0.5)).classify(), LobeKind::Glossy);
}

#[test]
fn forward_only_evaluation_and_sampling_skip_just_the_reverse_pdf() {
    use crate::bsdf::{BsdfEval, BsdfSample, Pdfs};
    let mut rng = Rng::new(23, 0);
    for (name, params) in material_classes(0.3) {
        let b = Bsdf::new(&params, n_g(), tilted_normal(0.25), false);
        for &c in &COS_SWEEP {
            let wo = direction(n_g(), c, 0.4);
            for mode in MODES {
                let (u_lobe, u) = (rng.uniform(), rng.uniform2());
                let both = b.sample(wo, u_lobe, u, mode);
                let forward = b.sample_with(wo, u_lobe, u, mode, Pdfs::Forward);
                let expected = both.map(|s| BsdfSample { pdf_rev: 0.0, ..s });
                assert_eq!(forward, expected, "{name} cos {c} {mode:?}");
                let wi = direction(n_g(), 0.7, 2.0);
                let both = b.eval(wo, wi, mode);
                let forward = b.eval_with(wo, wi, mode, Pdfs::Forward);
                assert_eq!(
                    forward,
                    BsdfEval {
                        pdf_rev: 0.0,
                        ..both
                    },
                    "{name} cos {c}"
                );
            }
        }
    }
}

#[test]
fn lobes_built_once_give_the_same_bsdf() {
    let mut classes = material_classes(0.3);
    classes.extend(material_classes(0.0));
    classes.push(("lambert".into(), lambert(Vec3::new(0.7, 0.5, 0.2))));
    let mut rng = Rng::new(5, 9);
    for (name, params) in classes {
        let lobes = crate::bsdf::Lobes::new(&params);
        let (n_s, double_sided) = (tilted_normal(0.2), true);
        let per_hit = Bsdf::new(&params, n_g(), n_s, double_sided);
        let reused = Bsdf::from_lobes(&lobes, n_g(), n_s, double_sided);
        for _ in 0..200 {
            let wo = direction(n_g(), rng.uniform() * 2.0 - 1.0, rng.uniform() * TAU);
            let wi = direction(n_g(), rng.uniform() * 2.0 - 1.0, rng.uniform() * TAU);
            let (u_lobe, u) = (rng.uniform(), rng.uniform2());
            for mode in MODES {
                assert_eq!(
                    per_hit.eval(wo, wi, mode),
                    reused.eval(wo, wi, mode),
                    "{name}"
                );
                assert_eq!(
                    per_hit.sample(wo, u_lobe, u, mode),
                    reused.sample(wo, u_lobe, u, mode),
                    "{name}"
                );
            }
        }
    }
}
