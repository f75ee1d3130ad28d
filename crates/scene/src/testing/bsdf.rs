//! Convenience wrappers of the harness for [`Bsdf`]s.

use super::{Chi2Config, Chi2Result, Estimate, chi2_test, estimate_mean};
use crate::bsdf::{Bsdf, LobeKind, TransportMode};
use crate::sampling::Sampler;
use glam::Vec3;

/// Chi-square test of [`Bsdf::sample`] against [`Bsdf::pdf`] for the outgoing direction
/// `wo` (world space). Delta samples count as "no direction", so the test also checks the
/// total probability of the delta lobes (see [`chi2_test`]).
pub fn bsdf_chi2_test(
    bsdf: &Bsdf,
    wo: Vec3,
    mode: TransportMode,
    config: &Chi2Config,
    num_tests: usize,
) -> Chi2Result {
    chi2_test(
        |rng| {
            let (u_lobe, u) = (rng.uniform(), rng.uniform2());
            let s = bsdf.sample(wo, u_lobe, u, mode)?;
            (s.lobe != LobeKind::Specular).then_some(s.wi)
        },
        |wi| bsdf.pdf(wo, wi) as f64,
        config,
        num_tests,
    )
}

/// Directional albedo ∫ f_cos(wo, wi) dωi (including delta lobes) estimated with `n`
/// BSDF samples (weights f_cos / pdf_fwd, zero for failed samples) and a fixed `seed`.
pub fn estimate_albedo(
    bsdf: &Bsdf,
    wo: Vec3,
    mode: TransportMode,
    n: usize,
    seed: u64,
) -> Estimate {
    estimate_mean(n, seed, |rng| {
        let (u_lobe, u) = (rng.uniform(), rng.uniform2());
        bsdf.sample(wo, u_lobe, u, mode)
            .map_or(Vec3::ZERO, |s| s.f_cos / s.pdf_fwd)
    })
}
