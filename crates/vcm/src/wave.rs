//! What every wavefront does with its list of paths each pass: hand out one ray per path,
//! and shade every path at its hit in parallel.

use glam::Vec3;
use rayon::prelude::*;
use vcm_scene::sampling::SobolSampler;
use vcm_traversal::{HitBatch, RayBatch};

use crate::surface_hit::Hit;

/// Refills `rays` with one unbounded ray per (origin, direction) segment, in order.
pub(crate) fn fill_extension_rays(
    rays: &mut RayBatch,
    segments: impl Iterator<Item = (Vec3, Vec3)>,
) {
    rays.refill(segments.map(|(origin, direction)| (origin, direction, 0.0, f32::INFINITY)));
}

/// Paths shaded together: their random numbers are computed in one go first.
const SHADE_CHUNK: usize = 64;

/// Calls `shade` for every path with its closest hit (`hits[i]` for path `i`), in parallel.
///
/// Before a chunk of paths is shaded, the numbers of the vertices they hit are computed
/// together ([`SobolSampler::prefetch`], SIMD across paths): `vertex_sampler` moves a path's
/// sampler to the numbers of the vertex it has reached and returns it.
pub(crate) fn shade_in_parallel<P: Send>(
    paths: &mut [P],
    hits: &HitBatch,
    vertex_sampler: impl Fn(&mut P) -> &mut SobolSampler + Sync,
    shade: impl Fn(&mut P, Option<Hit>) + Sync,
) {
    paths
        .par_chunks_mut(SHADE_CHUNK)
        .enumerate()
        .for_each(|(chunk_index, chunk)| {
            let first = chunk_index * SHADE_CHUNK;
            let hit_paths = chunk.iter_mut().enumerate();
            SobolSampler::prefetch(
                hit_paths
                    .filter(|(i, _)| hits.is_hit(first + i))
                    .map(|(_, path)| vertex_sampler(path)),
            );
            for (i, path) in chunk.iter_mut().enumerate() {
                shade(path, Hit::from_batch(hits, first + i));
            }
        });
}
