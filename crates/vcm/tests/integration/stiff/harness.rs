//! Rendering a generated scene with each algorithm, and the checks every stiff scene shares.

use vcm::{Algorithm, DEFAULT_ALPHA, Integrator, MergeRadius, PtSettings, VcmSettings};
use vcm_scene::Scene;

use crate::common::{self, FrameSeries, RegionSeries};

/// Image side in pixels.
pub const SIZE: u32 = 16;

/// Images are compared in REGIONS × REGIONS blocks of 4 × 4 pixels.
pub const REGIONS: usize = 4;

/// Every algorithm but light tracing, which cannot see what the camera sees through a
/// specular (delta) surface: it only splats light vertices, and a pinhole camera cannot be
/// connected to through a mirror or glass.
pub const ALL_BUT_LIGHT_TRACING: [Option<Algorithm>; 5] = [
    None,
    Some(Algorithm::Bpt),
    Some(Algorithm::Ppm),
    Some(Algorithm::Bpm),
    Some(Algorithm::Vcm),
];

/// What an integrator is set up with besides its scene and algorithm.
#[derive(Clone, Copy, Debug)]
pub struct Setup {
    /// Seed of the random streams.
    pub seed: u64,
    /// Merge radius of the first frame, as a fraction of the scene's bounding-sphere radius.
    pub radius_fraction: f32,
    /// Radius reduction exponent α of progressive photon mapping.
    pub alpha: f32,
}

impl Setup {
    /// Seed `seed`, merge radius `radius_fraction` of the scene, the default α.
    pub fn new(seed: u64, radius_fraction: f32) -> Setup {
        Setup {
            seed,
            radius_fraction,
            alpha: DEFAULT_ALPHA,
        }
    }
}

/// The integrator of `algorithm` (`None`: the path tracer) over `scene` on the CPU backend.
pub fn integrator(scene: Scene, algorithm: Option<Algorithm>, setup: Setup) -> Box<dyn Integrator> {
    match algorithm {
        None => {
            let settings = PtSettings {
                seed: setup.seed,
                ..common::pt_settings(SIZE, SIZE)
            };
            Box::new(common::path_tracer(scene, settings))
        }
        Some(algorithm) => {
            let settings = VcmSettings {
                seed: setup.seed,
                radius: MergeRadius::SceneFraction(setup.radius_fraction),
                alpha: setup.alpha,
                ..common::vcm_settings(algorithm, SIZE, SIZE)
            };
            Box::new(common::vcm(scene, settings))
        }
    }
}

/// A label for messages.
pub fn name(algorithm: Option<Algorithm>) -> String {
    algorithm.map_or("PT".into(), |a| format!("{a:?}"))
}

/// Asserts that every pixel of the merged film is finite (nothing was dropped either).
pub fn assert_finite(series: &FrameSeries, label: &str) {
    assert_eq!(series.film.dropped(), 0, "{label}: non-finite samples");
    let mean = series.film.mean();
    assert!(
        mean.iter().all(|rgb| rgb.is_finite()),
        "{label}: a non-finite pixel"
    );
}

/// z limit of region comparisons: |z| > 4.9 has probability 9.6e-7 for a normal z, so that
/// a test of up to 6 algorithms × 4 scenes × (16 regions + the image) = 408 comparisons
/// raises a false alarm with probability below 4e-4 (Šidák).
pub const Z_LIMIT: f64 = 4.9;

/// z-score of the difference of two independent means with standard errors `ea`, `eb`
/// (0 when both are exact and equal: a region no path reaches is black in both).
fn z_score(a: f64, ea: f64, b: f64, eb: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b) / (ea * ea + eb * eb).sqrt()
    }
}

/// Asserts that two region series of independent renders agree: every region and the whole
/// image within [`Z_LIMIT`] standard errors of the difference.
pub fn assert_regions_agree(a: &RegionSeries, b: &RegionSeries, label: &str) {
    let regions = a.means.len();
    let pairs = (0..regions)
        .map(|r| (a.means[r], a.errors[r], b.means[r], b.errors[r]))
        .chain([(a.image_mean, a.image_error, b.image_mean, b.image_error)]);
    for (r, (ma, ea, mb, eb)) in pairs.enumerate() {
        let z = z_score(ma, ea, mb, eb);
        let what = if r == regions {
            "image".to_string()
        } else {
            format!("region {r}")
        };
        assert!(
            z.abs() < Z_LIMIT,
            "{label}, {what}: {ma} vs {mb}, z = {z:.2}"
        );
    }
}

/// Asserts that every region of `series` and the whole image have the value `want`, within
/// [`Z_LIMIT`] standard errors.
pub fn assert_regions_equal(series: &RegionSeries, want: f64, label: &str) {
    let exact = RegionSeries {
        means: vec![want; series.means.len()],
        errors: vec![0.0; series.means.len()],
        image_mean: want,
        image_error: 0.0,
    };
    assert_regions_agree(series, &exact, label);
}

/// Asserts that no region of `series` and not the whole image exceeds `bound` by more than
/// [`Z_LIMIT`] standard errors (no energy gain).
pub fn assert_regions_at_most(series: &RegionSeries, bound: f64, label: &str) {
    let regions = series.means.iter().zip(&series.errors);
    for (r, (&m, &e)) in regions
        .chain([(&series.image_mean, &series.image_error)])
        .enumerate()
    {
        let z = z_score(m, e, bound, 0.0);
        assert!(
            z < Z_LIMIT,
            "{label}, region {r} (the last: the image): {m} above {bound}, z = {z:.2}"
        );
    }
}
