//! What every wavefront does with its list of paths each pass: hand out one ray per path,
//! and shade every path at its hit in parallel.

use glam::Vec3;
use rayon::prelude::*;
use vcm_scene::sampling::SobolSampler;
use vcm_traversal::{HitBatch, RayBatch};

use crate::lanes::LANES;
use crate::surface_hit::Hit;

/// Refills `rays` with one unbounded ray per (origin, direction) segment, in order.
pub(crate) fn fill_extension_rays(
    rays: &mut RayBatch,
    segments: impl Iterator<Item = (Vec3, Vec3)>,
) {
    rays.refill(segments.map(|(origin, direction)| (origin, direction, 0.0, f32::INFINITY)));
}

/// Paths shaded together: what their shading can do ahead is done for all of them first.
const SHADE_CHUNK: usize = 64;

/// How many paths the first [`Ahead`] step runs ahead of the second.
const AHEAD_LAG: usize = 8;

/// The two look-ahead steps a prepared hit goes through before it is shaded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Ahead {
    /// Right after the chunk's preparations.
    First,
    /// [`AHEAD_LAG`] paths after the first step.
    Second,
}

/// Vertices shaded several at a time in SIMD lanes, instead of one by one.
pub(crate) trait LaneShading<P>: Sync {
    /// Whether the vertex `path` reached at `hit` is shaded in lanes.
    fn takes(&self, path: &P, hit: Hit) -> bool;

    /// Starts loading what shading a vertex it takes will read from far away in memory,
    /// when its chunk is classified (before the chunk's other paths are shaded): nothing,
    /// unless the integrator has such reads.
    fn prepare(&self, _path: &mut P, _hit: Hit) {}

    /// Shades `paths[i]` at `hit` for each `(i, hit)` of `group` (at most [`LANES`] of
    /// them, each taken by [`LaneShading::takes`]), whose samplers are where the last
    /// vertex left them.
    fn shade(&self, paths: &mut [P], group: &[(usize, Hit)]);
}

/// Takes no vertex: every path is shaded on its own.
pub(crate) struct NoLanes;

impl<P> LaneShading<P> for NoLanes {
    fn takes(&self, _: &P, _: Hit) -> bool {
        false
    }

    fn shade(&self, _: &mut [P], group: &[(usize, Hit)]) {
        debug_assert!(group.is_empty(), "no vertex was taken");
    }
}

/// A chunk's lists between its steps, kept from chunk to chunk by each rayon job: as arrays
/// on the stack they were cleared in full for every chunk (their memset was ~2.6 k
/// instructions a chunk, 3.5% of VCM's on the Cornell box), however few paths used them.
struct ChunkLists<T> {
    /// Each path's hit, where it is shaded alone.
    hits: Vec<Option<Hit>>,
    /// What `prepare` computed from each of those hits.
    prepared: Vec<Option<T>>,
    /// Whether each path is shaded in lanes.
    in_lanes: Vec<bool>,
    /// (index in the chunk, hit) of the paths shaded in lanes.
    lane_group: Vec<(usize, Hit)>,
}

impl<T> ChunkLists<T> {
    fn new() -> ChunkLists<T> {
        ChunkLists {
            hits: Vec::with_capacity(SHADE_CHUNK),
            prepared: Vec::with_capacity(SHADE_CHUNK),
            in_lanes: Vec::with_capacity(SHADE_CHUNK),
            lane_group: Vec::with_capacity(SHADE_CHUNK),
        }
    }
}

/// Calls `shade` for every path with its closest hit (`hits[i]` for path `i`), in parallel,
/// and for a path that hit something, what `prepare` computed from that hit ahead.
///
/// Before a chunk of paths is shaded, the numbers of the vertices they hit are computed
/// together ([`SobolSampler::prefetch`], SIMD across paths): `vertex_sampler` moves a path's
/// sampler to the numbers of the vertex it has reached and returns it. Then `prepare` runs
/// for every hit path of the chunk in a loop of its own (the surface point, and loads that
/// take long to arrive): one path's shading is a long chain of dependent steps, while these
/// first steps of different paths are independent, so the CPU overlaps them. `ahead`, if
/// given, then takes each prepared hit through two more steps ([`Ahead`]) in a loop of its
/// own, the second [`AHEAD_LAG`] paths behind the first: for chains of loads, each step
/// reading what the step before it requested, which has arrived by then.
///
/// The vertices `lanes` takes are shaded by it instead, [`LANES`] at a time, once the
/// others of the chunk are done; it moves their samplers and computes their numbers itself.
pub(crate) fn shade_in_parallel<P: Send, T: Send>(
    paths: &mut [P],
    hits: &HitBatch,
    vertex_sampler: impl Fn(&mut P) -> &mut SobolSampler + Sync,
    lanes: &impl LaneShading<P>,
    prepare: impl Fn(&mut P, Hit) -> T + Sync,
    ahead: Option<impl Fn(&P, &mut T, Ahead) + Sync>,
    shade: impl Fn(&mut P, Option<(Hit, &T)>) + Sync,
) {
    paths.par_chunks_mut(SHADE_CHUNK).enumerate().for_each_init(
        ChunkLists::new,
        |lists, (chunk_index, chunk)| {
            let first = chunk_index * SHADE_CHUNK;
            let ChunkLists {
                hits: chunk_hits,
                prepared,
                in_lanes,
                lane_group,
            } = lists;
            chunk_hits.clear();
            in_lanes.clear();
            lane_group.clear();
            for (i, path) in chunk.iter_mut().enumerate() {
                let hit = Hit::from_batch(hits, first + i);
                let taken = hit.filter(|&hit| lanes.takes(path, hit));
                if let Some(hit) = taken {
                    lanes.prepare(path, hit);
                    lane_group.push((i, hit));
                }
                in_lanes.push(taken.is_some());
                chunk_hits.push(if taken.is_some() { None } else { hit });
            }
            let alone_hits = chunk.iter_mut().zip(chunk_hits.iter());
            SobolSampler::prefetch(
                alone_hits
                    .filter(|(_, hit)| hit.is_some())
                    .map(|(path, _)| vertex_sampler(path)),
            );
            prepared.clear();
            let prepare_hit = |(path, hit): (&mut P, &Option<Hit>)| hit.map(|h| prepare(path, h));
            prepared.extend(chunk.iter_mut().zip(chunk_hits.iter()).map(prepare_hit));
            if let Some(ahead) = &ahead {
                // Path k takes its first step, path k − AHEAD_LAG (if any) its second.
                for k in 0..chunk.len() + AHEAD_LAG {
                    let steps = [
                        (k, Ahead::First),
                        (k.wrapping_sub(AHEAD_LAG), Ahead::Second),
                    ];
                    for (i, step) in steps {
                        if let Some(Some(prepared)) = prepared.get_mut(i) {
                            ahead(&chunk[i], prepared, step);
                        }
                    }
                }
            }
            let alone = chunk
                .iter_mut()
                .zip(chunk_hits.iter())
                .zip(prepared.iter())
                .zip(in_lanes.iter());
            for (((path, hit), ahead), _) in alone.filter(|(_, in_lanes)| !**in_lanes) {
                shade(path, hit.zip(ahead.as_ref()));
            }
            for group in lane_group.chunks(LANES) {
                lanes.shade(chunk, group);
            }
        },
    );
}
