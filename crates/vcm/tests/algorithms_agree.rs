//! All algorithms agree: on the Cornell box and its indirectly lit variant, scenes every
//! technique can sample, light tracing, BPT and VCM converge to the path tracer's image, region
//! by region and as a whole, within the standard errors measured from the spread of per-frame
//! values; PPM and BPM, whose merging is biased by the radius, agree once the radius is small.

mod common;

use common::RegionSeries;
use vcm::{Algorithm, Integrator, PtSettings, VcmSettings};

/// The image is compared in REGIONS × REGIONS blocks.
const REGIONS: usize = 4;
const SIZE: u32 = 32;
const FRAMES: u32 = 1000;
/// Per test, at most 2 scenes × 3 algorithms × (16 regions + the image) = 102 comparisons:
/// |z| < 4.9 keeps the family-wise false alarm rate near 1e-4 (Šidák).
const Z_LIMIT: f64 = 4.9;

fn reference(name: &str) -> RegionSeries {
    let settings = PtSettings {
        seed: 100,
        ..common::pt_settings(SIZE, SIZE)
    };
    let mut tracer = common::path_tracer(common::scene_file(name), settings);
    common::region_means(&mut tracer, FRAMES, REGIONS)
}

fn vcm_family(name: &str, algorithm: Algorithm, radius_fraction: f32) -> Box<dyn Integrator> {
    let settings = VcmSettings {
        seed: 200,
        radius_fraction,
        ..common::vcm_settings(algorithm, SIZE, SIZE)
    };
    Box::new(common::vcm(common::scene_file(name), settings))
}

/// z-scores of the region means of `integrator` against the reference, and last that of the
/// image mean.
fn z_scores(reference: &RegionSeries, integrator: &mut dyn Integrator, frames: u32) -> Vec<f64> {
    common::region_means(integrator, frames, REGIONS).z_scores(reference)
}

#[test]
fn light_tracing_bpt_and_vcm_agree_with_path_tracing() {
    for name in ["cornell-box.gltf", "cornell-indirect.gltf"] {
        let reference = reference(name);
        for algorithm in [Algorithm::LightTracing, Algorithm::Bpt, Algorithm::Vcm] {
            let mut integrator = vcm_family(name, algorithm, vcm::DEFAULT_RADIUS_FRACTION);
            let z = z_scores(&reference, integrator.as_mut(), FRAMES);
            for (r, z) in z.iter().enumerate() {
                assert!(
                    z.abs() < Z_LIMIT,
                    "{name}, {algorithm:?}, region {r}: z = {z:.2}"
                );
            }
        }
    }
}

#[test]
fn photon_mapping_approaches_path_tracing_as_the_radius_shrinks() {
    for name in ["cornell-box.gltf", "cornell-indirect.gltf"] {
        let reference = reference(name);
        for algorithm in [Algorithm::Ppm, Algorithm::Bpm] {
            // At 2% of the scene radius the blur of merging is below the noise of 1000 frames.
            let mut integrator = vcm_family(name, algorithm, 0.02);
            let z = z_scores(&reference, integrator.as_mut(), FRAMES);
            for (r, z) in z.iter().enumerate() {
                assert!(
                    z.abs() < Z_LIMIT,
                    "{name}, {algorithm:?}, region {r}: z = {z:.2}"
                );
            }
        }
    }
    // At 10% it is not: the comparison above sees a bias of that size (the ceiling around the
    // light is darkened by merging across the corner).
    let reference = reference("cornell-box.gltf");
    let mut blurred = vcm_family("cornell-box.gltf", Algorithm::Ppm, 0.1);
    let z = z_scores(&reference, blurred.as_mut(), FRAMES);
    assert!(
        z.iter().any(|z| z.abs() > Z_LIMIT),
        "no bias seen at 10%: {z:.2?}"
    );
}
