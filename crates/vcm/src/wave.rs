//! What every wavefront does with its list of paths each pass: hand out one ray per path,
//! and shade every path at its hit in parallel.

use glam::Vec3;
use rayon::prelude::*;
use vcm_traversal::{HitBatch, RayBatch};

use crate::surface_hit::Hit;

/// Refills `rays` with one unbounded ray per (origin, direction) segment, in order.
pub(crate) fn fill_extension_rays(
    rays: &mut RayBatch,
    segments: impl Iterator<Item = (Vec3, Vec3)>,
) {
    rays.refill(segments.map(|(origin, direction)| (origin, direction, 0.0, f32::INFINITY)));
}

/// Calls `shade` for every path with its closest hit (`hits[i]` for path `i`), in parallel.
pub(crate) fn shade_in_parallel<P: Send>(
    paths: &mut [P],
    hits: &HitBatch,
    shade: impl Fn(&mut P, Option<Hit>) + Sync,
) {
    paths
        .par_iter_mut()
        .with_min_len(64)
        .enumerate()
        .for_each(|(i, path)| shade(path, Hit::from_batch(hits, i)));
}
