//! White-furnace tests: inside a closed sphere that emits Le everywhere and reflects with
//! Lambertian albedo ρ, the radiance is Le · Σₖ ρᵏ over the path lengths allowed, Le / (1 − ρ)
//! without a limit, in every pixel and every direction, whatever the sphere's size.

use glam::Vec3;
use vcm::{Algorithm, Integrator, MergeRadius, PtSettings, VcmSettings};
use vcm_scene::Material;
use vcm_scene::sampling::SampleSequence;

use crate::common;

const ALBEDO: f32 = 0.5;
const EMITTED: f32 = 1.0;
const SIZE: u32 = 16;

/// The diffuse furnace with a sphere of radius `scale`, path traced.
fn furnace(max_depth: Option<u32>, scale: f32) -> Box<dyn Integrator> {
    diffuse_furnace(max_depth, scale, None)
}

/// The diffuse furnace rendered by `algorithm` (`None`: the path tracer).
fn diffuse_furnace(
    max_depth: Option<u32>,
    scale: f32,
    algorithm: Option<Algorithm>,
) -> Box<dyn Integrator> {
    let material = Material {
        emission: Vec3::splat(EMITTED),
        ..Material::diffuse("furnace", Vec3::splat(ALBEDO))
    };
    let independent = Sampling::new(SampleSequence::Independent, 5);
    furnace_of(material, max_depth, scale, algorithm, independent)
}

/// How a furnace's samples are drawn.
#[derive(Clone, Copy, Debug)]
struct Sampling {
    sequence: SampleSequence,
    seed: u64,
}

impl Sampling {
    fn new(sequence: SampleSequence, seed: u64) -> Sampling {
        Sampling { sequence, seed }
    }
}

/// A furnace of `material` with a sphere of radius `scale`, rendered by `algorithm`
/// (`None`: the path tracer) with `sampling`.
fn furnace_of(
    material: Material,
    max_depth: Option<u32>,
    scale: f32,
    algorithm: Option<Algorithm>,
    sampling: Sampling,
) -> Box<dyn Integrator> {
    let Sampling { sequence, seed } = sampling;
    let (positions, triangles) = common::inward_icosphere(2);
    let positions = positions.into_iter().map(|p| p * scale).collect();
    let material_ids = vec![0; triangles.len()];
    let scene = common::scene(
        common::mesh(positions, triangles, material_ids),
        vec![material],
        Vec::new(),
        common::camera(Vec3::new(0.1, -0.2, 0.05) * scale, 1.2),
    );
    match algorithm {
        None => {
            let settings = PtSettings {
                seed,
                sequence,
                max_depth,
                ..PtSettings::new(SIZE, SIZE)
            };
            Box::new(common::path_tracer(scene, settings))
        }
        Some(algorithm) => {
            // With 256 light paths a frame, the default radius (0.3% of the sphere's) would
            // catch a light vertex in one query of a thousand: a heavy-tailed estimate whose
            // spread 200 frames cannot measure. Within distance r of a point, a sphere has
            // area π r² exactly (Archimedes), so a large radius adds no bias here.
            let settings = VcmSettings {
                seed,
                sequence,
                max_depth,
                radius: MergeRadius::SceneFraction(0.1),
                ..VcmSettings::new(algorithm, SIZE, SIZE)
            };
            Box::new(common::vcm(scene, settings))
        }
    }
}

/// Le · (1 + ρ + … + ρ^(segments − 1)).
fn expected(segments: Option<u32>) -> f64 {
    let (le, rho) = (f64::from(EMITTED), f64::from(ALBEDO));
    match segments {
        None => le / (1.0 - rho),
        Some(n) => le * (1.0 - rho.powi(n as i32)) / (1.0 - rho),
    }
}

fn assert_converges(max_depth: Option<u32>, scale: f32, frames: u32) {
    assert_algorithm_converges(None, max_depth, scale, frames);
}

fn assert_algorithm_converges(
    algorithm: Option<Algorithm>,
    max_depth: Option<u32>,
    scale: f32,
    frames: u32,
) {
    let mut integrator = diffuse_furnace(max_depth, scale, algorithm);
    let series = common::render_series(integrator.as_mut(), frames);
    let want = expected(max_depth);
    let (mean, se) = (series.image_mean, series.image_std_err);
    assert!(
        (mean - want).abs() < 4.0 * se,
        "{algorithm:?}: image mean {mean} vs {want} ± 4·{se} (max_depth {max_depth:?}, scale {scale})"
    );
    // Every pixel sees the same distribution, whose tail is long (path length, near-edge light
    // samples): a pixel's own few samples often miss the rare large values and understate its
    // spread, so the per-pixel bound uses the variance pooled over all pixels. 5σ: with 256
    // pixels the chance of a false failure stays below 1e-3.
    let e = series.pooled_pixel_std_err;
    for (p, &m) in series.pixel_mean.iter().enumerate() {
        assert!(
            (m - want).abs() < 5.0 * e,
            "{algorithm:?}, pixel {p}: {m} vs {want} ± 5·{e} (scale {scale})"
        );
    }
    assert_eq!(series.film.dropped(), 0);
}

#[test]
fn unlimited_paths_converge_to_le_over_one_minus_albedo() {
    assert_converges(None, 1.0, 200);
}

const VCM_ALGORITHMS: [Algorithm; 5] = [
    Algorithm::LightTracing,
    Algorithm::Bpt,
    Algorithm::Ppm,
    Algorithm::Bpm,
    Algorithm::Vcm,
];

#[test]
fn every_vcm_algorithm_converges_to_le_over_one_minus_albedo() {
    for algorithm in VCM_ALGORITHMS {
        assert_algorithm_converges(Some(algorithm), None, 1.0, 200);
    }
}

#[test]
fn every_vcm_algorithm_respects_the_path_length_limit() {
    for algorithm in VCM_ALGORITHMS {
        assert_algorithm_converges(Some(algorithm), Some(3), 1.0, 100);
    }
}

#[test]
fn vcm_furnaces_of_any_size_converge_to_the_same_value() {
    for scale in [1e-4, 1e5] {
        assert_algorithm_converges(Some(Algorithm::Vcm), None, scale, 100);
    }
}

#[test]
fn tiny_and_huge_furnaces_converge_to_the_same_value() {
    for scale in [1e-4, 1e5] {
        assert_converges(None, scale, 100);
    }
}

#[test]
fn three_segments_give_the_first_three_terms() {
    assert_converges(Some(3), 1.0, 100);
}

#[test]
fn one_segment_sees_only_the_emission_and_zero_segments_nothing() {
    for (max_depth, want) in [(1, EMITTED), (0, 0.0)] {
        let mut tracer = furnace(Some(max_depth), 1.0);
        let mut film = vcm::Film::new(SIZE, SIZE);
        let stats = tracer.render_frame(&mut film, 0);
        assert_eq!(stats.camera_rays, u64::from(SIZE * SIZE));
        assert_eq!((stats.continuation_rays, stats.shadow_rays), (0, 0));
        for rgb in film.mean() {
            assert_eq!(rgb, Vec3::splat(want), "max_depth {max_depth}");
        }
    }
}

#[test]
fn a_perfect_mirror_furnace_adds_le_per_segment() {
    // Schlick Fresnel with F0 = 1 reflects everything: every segment ends on Le, always with
    // full MIS weight since delta bounces cannot be light-sampled.
    let mirror = Material {
        emission: Vec3::splat(EMITTED),
        metallic: 1.0,
        roughness: 0.0,
        ..Material::default()
    };
    let segments = 3;
    let sampling = Sampling::new(SampleSequence::Sobol, 5);
    let mut tracer = furnace_of(mirror, Some(segments), 1.0, None, sampling);
    let mut film = vcm::Film::new(SIZE, SIZE);
    let stats = tracer.render_frame(&mut film, 0);
    assert_eq!(stats.shadow_rays, 0);
    let want = EMITTED * segments as f32;
    for rgb in film.mean() {
        assert!(
            (rgb - Vec3::splat(want)).abs().max_element() < 1e-5 * want,
            "{rgb}"
        );
    }
}

/// The image means of `renders` renders of the diffuse furnace by `algorithm` (`None`: the
/// path tracer) over `frames` frames, each render with a seed of its own, and the mean
/// squared error of their pixels against the furnace value.
fn independent_renders(
    algorithm: Option<Algorithm>,
    sequence: SampleSequence,
    renders: u64,
    frames: u32,
) -> (Vec<f64>, f64) {
    let want = expected(None);
    let material = Material {
        emission: Vec3::splat(EMITTED),
        ..Material::diffuse("furnace", Vec3::splat(ALBEDO))
    };
    let (mut image_means, mut squared_error) = (Vec::new(), 0.0);
    for seed in 0..renders {
        let sampling = Sampling::new(sequence, 1000 + seed);
        let mut integrator = furnace_of(material.clone(), None, 1.0, algorithm, sampling);
        let mut film = vcm::Film::new(SIZE, SIZE);
        for frame in 0..frames {
            integrator.render_frame(&mut film, frame);
        }
        assert_eq!(film.dropped(), 0);
        let pixels: Vec<f64> = film
            .mean()
            .iter()
            .map(|rgb| f64::from(rgb.element_sum()) / 3.0)
            .collect();
        image_means.push(pixels.iter().sum::<f64>() / pixels.len() as f64);
        squared_error += pixels.iter().map(|m| (m - want).powi(2)).sum::<f64>();
    }
    let pixels = renders as f64 * f64::from(SIZE * SIZE);
    (image_means, squared_error / pixels)
}

/// Stratified samples (the default, [`SampleSequence::Sobol`]) converge to the furnace
/// value. Frames of stratified samples are not independent, so their spread is no error
/// estimate: renders with different seeds are (each an independent randomization), and 16
/// of them give the image mean's standard error (4.5σ: below 10⁻³ for Student's t with 15
/// degrees of freedom). Where a pixel's value comes from its own camera paths, stratifying
/// them lowers its error (by 2.9 and 2.4 times here); where it comes from light paths
/// landing on it at random (light tracing, photon mapping's merges), the gain is within
/// the noise, and those are only held to the furnace value.
#[test]
fn stratified_samples_converge_to_the_furnace_value() {
    let want = expected(None);
    let camera_driven = [None, Some(Algorithm::Bpt), Some(Algorithm::Ppm)];
    for algorithm in camera_driven
        .into_iter()
        .chain([Some(Algorithm::LightTracing)])
    {
        let (means, stratified) = independent_renders(algorithm, SampleSequence::Sobol, 16, 32);
        let n = means.len() as f64;
        let mean = means.iter().sum::<f64>() / n;
        let variance = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let se = (variance / n).sqrt();
        assert!(
            (mean - want).abs() < 4.5 * se,
            "{algorithm:?}: stratified image mean {mean} vs {want} ± 4.5·{se}"
        );
        if camera_driven.contains(&algorithm) {
            let (_, independent) =
                independent_renders(algorithm, SampleSequence::Independent, 16, 32);
            assert!(
                stratified < independent,
                "{algorithm:?}: pixel MSE {stratified} stratified, {independent} independent"
            );
        }
    }
}
