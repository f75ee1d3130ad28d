//! A short render of the Cornell box agrees with a long one (different seed) within the
//! standard error estimated from the spread of per-frame values.

use std::path::Path;

use vcm::{Film, PtSettings};
use vcm_scene::Scene;

mod common;

/// Regions per image side: the image is split into REGIONS × REGIONS blocks whose means are
/// compared (a pixel alone is too noisy for a short render's error estimate).
const REGIONS: usize = 4;
const SIZE: u32 = 32;

/// Per-region means over `frames` frames and their standard errors.
fn region_means(seed: u64, frames: u32) -> (Vec<f64>, Vec<f64>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.gltf");
    let scene = Scene::load(&path).unwrap();
    let settings = PtSettings {
        width: SIZE,
        height: SIZE,
        seed,
        max_depth: None,
    };
    let mut tracer = common::path_tracer(scene, settings);
    let block = SIZE as usize / REGIONS;
    let mut per_frame = Vec::new();
    for iteration in 0..frames {
        let mut film = Film::new(SIZE, SIZE);
        tracer.render_frame(&mut film, iteration);
        assert_eq!(film.dropped(), 0);
        let mut regions = vec![0.0; REGIONS * REGIONS];
        for (i, rgb) in film.mean().iter().enumerate() {
            let (x, y) = (i % SIZE as usize / block, i / SIZE as usize / block);
            regions[y * REGIONS + x] += f64::from(rgb.element_sum()) / 3.0 / (block * block) as f64;
        }
        per_frame.push(regions);
    }
    let n = f64::from(frames);
    (0..REGIONS * REGIONS)
        .map(|r| {
            let mean = per_frame.iter().map(|f| f[r]).sum::<f64>() / n;
            let variance = per_frame.iter().map(|f| (f[r] - mean).powi(2)).sum::<f64>() / (n - 1.0);
            (mean, (variance / n).sqrt())
        })
        .unzip()
}

#[test]
fn a_short_render_agrees_with_a_long_one_within_the_standard_error() {
    let (short, short_err) = region_means(11, 24);
    let (long, long_err) = region_means(12, 192);
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
