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

/// How many prepared hits the first [`Ahead`] step runs ahead of the second.
const AHEAD_LAG: usize = 8;

/// The two look-ahead steps a prepared hit goes through before it is shaded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Ahead {
    /// Right after the chunk's preparations.
    First,
    /// [`AHEAD_LAG`] hits after the first step.
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
    /// How each path of the chunk is shaded.
    kinds: Vec<Shading>,
    /// What `prepare` computed for each path of the chunk shaded alone at a hit, in path
    /// order, with the path's index in the chunk: only those paths, so that the paths
    /// shaded in lanes cost no write of an empty entry (an `Option` per path was a
    /// store of its whole size, 2.9% of the path tracer's time on the Cornell box).
    prepared: Vec<(usize, T)>,
    /// (index in the chunk, hit) of the paths shaded in lanes.
    lane_group: Vec<(usize, Hit)>,
}

/// How one path of a chunk is shaded.
#[derive(Clone, Copy)]
enum Shading {
    /// Alone, at its hit, or where it escaped (`None`).
    Alone(Option<Hit>),
    /// With others, in SIMD lanes.
    InLanes,
}

impl<T> ChunkLists<T> {
    fn new() -> ChunkLists<T> {
        ChunkLists {
            kinds: Vec::with_capacity(SHADE_CHUNK),
            prepared: Vec::with_capacity(SHADE_CHUNK),
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
/// own, the second [`AHEAD_LAG`] hits behind the first: for chains of loads, each step
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
                kinds,
                prepared,
                lane_group,
            } = lists;
            kinds.clear();
            lane_group.clear();
            for (i, path) in chunk.iter_mut().enumerate() {
                let hit = Hit::from_batch(hits, first + i);
                kinds.push(match hit {
                    Some(hit) if lanes.takes(path, hit) => {
                        lanes.prepare(path, hit);
                        lane_group.push((i, hit));
                        Shading::InLanes
                    }
                    _ => Shading::Alone(hit),
                });
            }
            SobolSampler::prefetch(
                alone_hits(chunk, kinds).map(|(_, path, _)| vertex_sampler(path)),
            );
            prepared.clear();
            prepared.extend(alone_hits(chunk, kinds).map(|(i, path, hit)| (i, prepare(path, hit))));
            if let Some(ahead) = &ahead {
                // Entry k takes its first step, entry k − AHEAD_LAG (if any) its second.
                for k in 0..prepared.len() + AHEAD_LAG {
                    let steps = [
                        (k, Ahead::First),
                        (k.wrapping_sub(AHEAD_LAG), Ahead::Second),
                    ];
                    for (j, step) in steps {
                        if let Some((i, prepared)) = prepared.get_mut(j) {
                            ahead(&chunk[*i], prepared, step);
                        }
                    }
                }
            }
            let mut prepared = prepared.iter().map(|(_, prepared)| prepared);
            for (path, kind) in chunk.iter_mut().zip(kinds.iter()) {
                if let &Shading::Alone(hit) = kind {
                    let ahead = hit.map(|hit| (hit, prepared.next().expect("prepared ahead")));
                    shade(path, ahead);
                }
            }
            for group in lane_group.chunks(LANES) {
                lanes.shade(chunk, group);
            }
        },
    );
}

/// (index in the chunk, path, hit) of the paths of `chunk` shaded alone at a hit.
fn alone_hits<'a, P>(
    chunk: &'a mut [P],
    kinds: &'a [Shading],
) -> impl Iterator<Item = (usize, &'a mut P, Hit)> {
    let paths = chunk.iter_mut().zip(kinds).enumerate();
    paths.filter_map(|(i, (path, kind))| match *kind {
        Shading::Alone(Some(hit)) => Some((i, path, hit)),
        _ => None,
    })
}
