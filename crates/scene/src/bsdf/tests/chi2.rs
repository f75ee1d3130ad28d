//! Sampling matches `pdf_fwd` (chi-square over the sphere), for every material class,
//! roughness and incident angle, from the front and (for transmissive materials) the back.

use super::*;
use crate::testing::{Chi2Config, bsdf_chi2_test};

/// Upper bound on the number of chi-square tests in this module (108 at the time of
/// writing). Every test is Šidák-corrected for the whole module, so that a correct BSDF
/// fails any of them with probability at most 1%.
const FAMILY: usize = 120;

/// Chi-square test of sampling against `Bsdf::pdf` for `wo`, binned around n_g.
fn check(name: &str, bsdf: &Bsdf, wo: Vec3, mode: TransportMode) {
    let config = Chi2Config {
        frame: Frame::from_z(n_g()),
        ..Chi2Config::default()
    };
    let result = bsdf_chi2_test(bsdf, wo, mode, &config, FAMILY);
    assert!(result.passed, "{name}, wo = {wo}, {mode:?}: {result:?}");
}

/// Runs the chi-square test for each material over the incident cosines; `back` adds the
/// view from behind the surface for transmissive materials.
fn sweep(materials: &[(String, BsdfParams)], cosines: &[f32], back: bool) {
    let mut cases = Vec::new();
    for (name, params) in materials {
        let b = bsdf(params);
        if b.is_delta() {
            continue;
        }
        for &c in cosines {
            cases.push((name.clone(), direction(n_g(), c, 0.3), params));
            if back && is_transmissive(params) {
                cases.push((format!("{name} (back)"), direction(-n_g(), c, 1.1), params));
            }
        }
    }
    for (name, wo, params) in &cases {
        check(name, &bsdf(params), *wo, TransportMode::Radiance);
    }
}

const CHI2_COS: [f32; 3] = [0.05, 0.5, 1.0];

/// `(name, params)` for each roughness.
fn named(
    label: &str,
    roughness: &[f32],
    make: impl Fn(f32) -> BsdfParams,
) -> Vec<(String, BsdfParams)> {
    roughness
        .iter()
        .map(|&r| (format!("{label} r={r}"), make(r)))
        .collect()
}

#[test]
fn lambert_sampling() {
    let m = named("lambert", &[1.0], |_| lambert(Vec3::new(0.8, 0.5, 0.2)));
    sweep(&m, &CHI2_COS, false);
}

#[test]
fn dielectric_base_sampling_smooth() {
    // Includes a smooth coat (delta) over diffuse: the diffuse part must be sampled with
    // the right probability.
    sweep(
        &named("base", &ROUGHNESS_SWEEP[..3], dielectric_base),
        &CHI2_COS,
        false,
    );
}

#[test]
fn dielectric_base_sampling_rough() {
    sweep(
        &named("base", &ROUGHNESS_SWEEP[3..], dielectric_base),
        &CHI2_COS,
        false,
    );
}

#[test]
fn conductor_sampling() {
    sweep(
        &named("conductor", &ROUGH_SWEEP, conductor),
        &CHI2_COS,
        false,
    );
}

#[test]
fn glass_sampling_narrow() {
    sweep(
        &named("glass 1.5", &[0.1, 0.3], |r| glass(r, 1.5)),
        &CHI2_COS,
        true,
    );
}

#[test]
fn glass_sampling_wide() {
    let mut m = named("glass 1.5", &[0.6, 1.0], |r| glass(r, 1.5));
    m.extend(named("glass 1.33", &[0.3], |r| glass(r, 1.33)));
    sweep(&m, &CHI2_COS, true);
}

#[test]
fn glass_sampling_importance_mode() {
    // The pdfs do not depend on the mode, but refraction weights do: sample in importance
    // mode too (front and back).
    let b = bsdf(&glass(0.3, 1.5));
    for (n, c) in [(n_g(), 0.5f32), (-n_g(), 0.5), (-n_g(), 0.9)] {
        check(
            "glass importance",
            &b,
            direction(n, c, 0.7),
            TransportMode::Importance,
        );
    }
}

#[test]
fn thin_glass_sampling() {
    // A thin sheet is symmetric: the back side is checked at one roughness only.
    sweep(&named("thin", &ROUGH_SWEEP, thin_glass), &CHI2_COS, false);
    let back: Vec<_> = named("thin", &[0.3], thin_glass)
        .into_iter()
        .flat_map(|(name, p)| CHI2_COS.map(|c| (name.clone(), p, c)))
        .collect();
    for (name, params, c) in back {
        check(
            &format!("{name} (back)"),
            &bsdf(&params),
            direction(-n_g(), c, 1.1),
            TransportMode::Radiance,
        );
    }
}

#[test]
fn mixture_sampling_smooth() {
    // Delta metal + glass + coat over diffuse, and the narrowest rough lobes.
    sweep(&named("mixture", &[0.0, 0.1], mixture), &CHI2_COS, true);
}

#[test]
fn mixture_sampling_rough() {
    sweep(&named("mixture", &[0.3, 1.0], mixture), &CHI2_COS, true);
}

#[test]
fn tilted_shading_normal_sampling() {
    // Pairs that n_g and n_s classify differently are rejected by sample() and have zero
    // pdf in eval(): the two must still agree.
    let cases = [
        ("mixture", mixture(0.3)),
        ("glass", glass(0.3, 1.5)),
        ("base", dielectric_base(0.6)),
    ];
    for (name, params) in &cases {
        let b = Bsdf::new(params, n_g(), tilted_normal(0.3), false);
        check(
            name,
            &b,
            direction(n_g(), 0.4, 2.0),
            TransportMode::Radiance,
        );
    }
}

/// Lobes narrower than the cells above resolve (α down to 10⁻⁴, roughness 0.01). Seen at
/// normal incidence, the half vectors of a GGX lobe's visible-normal samples have slopes
/// u = tan θh / α of density (1/π)(1 + |u|²)⁻², so P(|u| < R) = R² / (1 + R²): 16 radial bins
/// equally likely under that law must fill evenly (chi-square), and each sample's pdf must be
/// D(h) cos θh / (4 ωo·h) = 1 / (4π α² cos⁴θh (1 + u²)²), to 1% (f32 directions resolve
/// slopes of 10⁻⁴ to about 10⁻³).
#[test]
fn polished_lobes_sample_their_slope_distribution() {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    const BINS: usize = 16;
    const SAMPLES: usize = 200_000;
    let cases = [0.01f32, 0.02];
    let frame = Frame::from_z(n_g());
    let wo = n_g();
    let mut rng = Rng::new(31, 0);
    for roughness in cases {
        let b = bsdf(&BsdfParams {
            base_color: Vec3::ONE,
            ..conductor(roughness)
        });
        let alpha = f64::from(roughness * roughness);
        let mut counts = [0u32; BINS];
        for _ in 0..SAMPLES {
            let (u_lobe, u) = (rng.uniform(), rng.uniform2());
            let s = b.sample(wo, u_lobe, u, TransportMode::Radiance).unwrap();
            let h = frame.to_local((wo + s.wi).normalize()).as_dvec3();
            let u2 = (h.x * h.x + h.y * h.y) / (h.z * h.z * alpha * alpha);
            let bin = (u2 / (1.0 + u2) * BINS as f64) as usize;
            counts[bin.min(BINS - 1)] += 1;
            let cos4 = h.z.powi(4);
            let pdf =
                1.0 / (4.0 * std::f64::consts::PI * alpha * alpha * cos4 * (1.0 + u2).powi(2));
            let reported = f64::from(s.pdf_fwd);
            assert!(
                (reported / pdf - 1.0).abs() < 1e-2,
                "roughness {roughness}, u² {u2}: pdf {reported} vs {pdf}"
            );
        }
        let expected = SAMPLES as f64 / BINS as f64;
        let statistic: f64 = counts
            .iter()
            .map(|&c| (f64::from(c) - expected).powi(2) / expected)
            .sum();
        let p_value = ChiSquared::new((BINS - 1) as f64).unwrap().sf(statistic);
        let significance = crate::testing::sidak_significance(0.01, cases.len());
        assert!(
            p_value >= significance,
            "roughness {roughness}: counts {counts:?}, p = {p_value}"
        );
    }
}
