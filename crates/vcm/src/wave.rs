//! What every wavefront does with its list of paths each pass: hand out one ray per path,
//! and shade every path at its hit in parallel.

use glam::Vec3;
use rayon::prelude::*;
use vcm_scene::Scene;
use vcm_scene::sampling::SobolSampler;
use vcm_traversal::{HitBatch, RayBatch};

use crate::surface_hit::{Hit, SurfaceHit};

/// Refills `rays` with one unbounded ray per (origin, direction) segment, in order.
pub(crate) fn fill_extension_rays(
    rays: &mut RayBatch,
    segments: impl Iterator<Item = (Vec3, Vec3)>,
) {
    rays.refill(segments.map(|(origin, direction)| (origin, direction, 0.0, f32::INFINITY)));
}

/// Paths shaded together: their random numbers and surface points are computed in one go
/// first.
const SHADE_CHUNK: usize = 64;

/// Calls `shade` for every path with its closest hit (`hits[i]` for path `i`) and the
/// surface point there, in parallel.
///
/// Before a chunk of paths is shaded, the numbers of the vertices they hit are computed
/// together ([`SobolSampler::prefetch`], SIMD across paths): `vertex_sampler` moves a path's
/// sampler to the numbers of the vertex it has reached and returns it. Then the chunk's
/// surface points are computed in a loop of their own: one path's shading is a long chain of
/// dependent steps, while the surface points of different paths are independent, so the CPU
/// overlaps them (the same arithmetic as computing each in its path's turn).
pub(crate) fn shade_in_parallel<P: Send>(
    scene: &Scene,
    paths: &mut [P],
    hits: &HitBatch,
    vertex_sampler: impl Fn(&mut P) -> &mut SobolSampler + Sync,
    shade: impl Fn(&mut P, Option<(Hit, &SurfaceHit)>) + Sync,
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
            let len = chunk.len();
            let surfaces: [Option<(Hit, SurfaceHit)>; SHADE_CHUNK] = std::array::from_fn(|i| {
                let hit = (i < len).then(|| Hit::from_batch(hits, first + i))??;
                Some((hit, SurfaceHit::new(scene, hit.triangle, hit.u, hit.v)))
            });
            for (path, surface) in chunk.iter_mut().zip(&surfaces) {
                shade(path, surface.as_ref().map(|(hit, point)| (*hit, point)));
            }
        });
}
