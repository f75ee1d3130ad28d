//! A short render of the Cornell box agrees with a long one (different seed) within the
//! standard error estimated from the spread of per-frame values.

use std::path::Path;

use vcm::PtSettings;
use vcm_scene::Scene;

use crate::common;

/// Regions per image side: the image is split into REGIONS × REGIONS blocks whose means are
/// compared (a pixel alone is too noisy for a short render's error estimate).
const REGIONS: usize = 4;
const SIZE: u32 = 32;

/// Per-region means of the path-traced Cornell box over `frames` frames and their standard
/// errors.
fn region_means(seed: u64, frames: u32) -> common::RegionSeries {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.gltf");
    let scene = Scene::load(&path).unwrap();
    let settings = PtSettings {
        seed,
        ..common::pt_settings(SIZE, SIZE)
    };
    common::region_means(&mut common::path_tracer(scene, settings), frames, REGIONS)
}

#[test]
fn a_short_render_agrees_with_a_long_one_within_the_standard_error() {
    let short = region_means(11, 24);
    let long = region_means(12, 192);
    let (short, short_err, long, long_err) = (short.means, short.errors, long.means, long.errors);
    // 16 comparisons: 4.4σ keeps the family-wise false alarm rate near 1e-4 (Šidák).
    for r in 0..REGIONS * REGIONS {
        let sigma = (short_err[r].powi(2) + long_err[r].powi(2)).sqrt();
        let z = (short[r] - long[r]) / sigma;
        assert!(
            z.abs() < 4.4,
            "region {r}: {} vs {} (z = {z:.2})",
            short[r],
            long[r]
        );
        assert!(long[r] > 0.0, "region {r} is black");
    }
}
