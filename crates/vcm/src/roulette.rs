//! Russian roulette, shared by camera and light paths.

use glam::Vec3;

/// Segments after which Russian roulette starts.
const ROULETTE_AFTER_SEGMENTS: u32 = 3;

/// Highest continuation probability of Russian roulette.
const MAX_CONTINUATION: f32 = 0.95;

/// The probability of going on after `segments` segments with `throughput` relative to the
/// path's start (dimensionless: 1 at the camera, or at the light after emission), or `None`
/// while the path is too short for roulette.
pub(crate) fn continuation_probability(segments: u32, throughput: Vec3) -> Option<f32> {
    (segments >= ROULETTE_AFTER_SEGMENTS).then(|| throughput.max_element().min(MAX_CONTINUATION))
}
