//! What every wavefront does with its list of paths: start them tile by tile, and each pass
//! hand out one ray per path and shade every path at its hit in parallel.

use glam::Vec3;
use rayon::prelude::*;
use vcm_scene::sampling::SobolSampler;
use vcm_scheduler::{StopFlag, Tile};
use vcm_traversal::{HitBatch, RayBatch};

use crate::lanes::LANES;
use crate::surface_hit::Hit;

/// Paths started in one go from which they are made in parallel. A tile worker (the
/// default scheduler) starts ~1,000 at a time while the other workers keep the threads
/// busy: handing those to the pool as well cost the path tracer 10% of its samples per
/// second on the Cornell box (2 cores); one wavefront over the whole image (the `none`
/// scheduler) starts all of its paths at once, and needs every thread for it.
const PARALLEL_START_FROM: usize = 16_384;

/// Appends `new_path(key, sample)` to `paths` for samples `0..samples` of every key of
/// `tile` (`y · width + x`: a pixel, or a light path's index), keys in row order and the
/// samples of a key in turn.
pub(crate) fn start_paths<P: Send>(
    paths: &mut Vec<P>,
    (tile, width): (Tile, u32),
    samples: u32,
    new_path: impl Fn(u32, u32) -> P + Sync,
) {
    let keys = tile
        .pixels(width)
        .flat_map(|key| (0..samples).map(move |sample| (key, sample)));
    if tile.len() * (samples as usize) < PARALLEL_START_FROM {
        paths.extend(keys.map(|(key, sample)| new_path(key, sample)));
    } else {
        let keys: Vec<(u32, u32)> = keys.collect();
        let new_paths = keys.into_par_iter().with_min_len(256);
        // An exact count: the paths are written in place.
        paths.par_extend(new_paths.map(|(key, sample)| new_path(key, sample)));
    }
}

/// Runs `each` on the paths just started, `paths`, [`LANES`] at a time: in parallel only
/// from [`PARALLEL_START_FROM`] paths on, as [`start_paths`] makes them (on one thread, the
/// light pass's emission in lanes took 4% less CPU time for VCM on the Cornell box).
pub(crate) fn for_started_in_lanes<P: Send>(paths: &mut [P], each: impl Fn(&mut [P]) + Sync) {
    if paths.len() < PARALLEL_START_FROM {
        paths.chunks_mut(LANES).for_each(each);
    } else {
        paths.par_chunks_mut(LANES).with_min_len(32).for_each(&each);
    }
}

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

/// Vertices shaded several at a time in SIMD lanes, instead of one by one; `T` is what the
/// vertices shaded alone prepare ahead ([`shade_in_parallel`]).
pub(crate) trait LaneShading<P, T>: Sync {
    /// Whether the vertices it takes are prepared ahead as those shaded alone are (`prepare`
    /// and the look-ahead of [`shade_in_parallel`]), for what they read far away in memory.
    const PREPARED: bool = false;

    /// Whether the vertex `path` reached at `hit` is shaded in lanes.
    fn takes(&self, path: &P, hit: Hit) -> bool;

    /// Starts loading what shading a vertex it takes will read from far away in memory,
    /// when its chunk is classified (before the chunk's other paths are shaded): nothing,
    /// unless the integrator has such reads.
    fn prepare(&self, _path: &mut P, _hit: Hit) {}

    /// Shades `paths[i]` at `hit` for each `(i, hit)` of `group` (at most [`LANES`] of
    /// them, each taken by [`LaneShading::takes`]), whose samplers are where the last
    /// vertex left them. Where [`LaneShading::PREPARED`], `prepared` holds what was
    /// prepared for each of them, in the same order; else it is empty.
    fn shade(&self, paths: &mut [P], group: &[(usize, Hit)], prepared: &[(usize, T)]);
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
    /// What `prepare` computed for each of `lane_group`, where the lanes ask for it
    /// ([`LaneShading::PREPARED`]).
    lane_prepared: Vec<(usize, T)>,
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
            lane_prepared: Vec::new(),
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
/// Where it asks for them ([`LaneShading::PREPARED`]), they are prepared and looked ahead for
/// too, after the others.
///
/// Once `stop` is raised no further chunk is shaded: the pass is being dropped.
pub(crate) fn shade_in_parallel<P: Send, T: Send, L: LaneShading<P, T>>(
    paths: &mut [P],
    (hits, stop): (&HitBatch, &StopFlag),
    vertex_sampler: impl Fn(&mut P) -> &mut SobolSampler + Sync,
    lanes: &L,
    prepare: impl Fn(&mut P, Hit) -> T + Sync,
    ahead: Option<impl Fn(&P, &mut T, Ahead) + Sync>,
    shade: impl Fn(&mut P, Option<(Hit, &T)>) + Sync,
) {
    paths.par_chunks_mut(SHADE_CHUNK).enumerate().for_each_init(
        ChunkLists::new,
        |lists, (chunk_index, chunk)| {
            if stop.is_raised() {
                return;
            }
            let first = chunk_index * SHADE_CHUNK;
            let ChunkLists {
                kinds,
                prepared,
                lane_group,
                lane_prepared,
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
            lane_prepared.clear();
            if L::PREPARED {
                let hits = lane_group
                    .iter()
                    .map(|&(i, hit)| (i, prepare(&mut chunk[i], hit)));
                lane_prepared.extend(hits);
            }
            if let Some(ahead) = &ahead {
                look_ahead(chunk, prepared, ahead);
                look_ahead(chunk, lane_prepared, ahead);
            }
            let mut prepared = prepared.iter().map(|(_, prepared)| prepared);
            for (path, kind) in chunk.iter_mut().zip(kinds.iter()) {
                if let &Shading::Alone(hit) = kind {
                    let ahead = hit.map(|hit| (hit, prepared.next().expect("prepared ahead")));
                    shade(path, ahead);
                }
            }
            let mut prepared = lane_prepared.chunks(LANES);
            for group in lane_group.chunks(LANES) {
                lanes.shade(chunk, group, prepared.next().unwrap_or_default());
            }
        },
    );
}

/// Takes each of `prepared` (index in `chunk`, what was prepared) through the two [`Ahead`]
/// steps, the second [`AHEAD_LAG`] entries behind the first.
fn look_ahead<P, T>(chunk: &[P], prepared: &mut [(usize, T)], ahead: &impl Fn(&P, &mut T, Ahead)) {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Takes no vertex: every path is shaded on its own.
    struct NoLanes;

    impl<P, T> LaneShading<P, T> for NoLanes {
        fn takes(&self, _: &P, _: Hit) -> bool {
            false
        }

        fn shade(&self, _: &mut [P], group: &[(usize, Hit)], _: &[(usize, T)]) {
            assert!(group.is_empty(), "no vertex was taken");
        }
    }

    #[test]
    fn paths_start_in_key_and_sample_order_in_one_go_and_in_parallel() {
        let width = 300;
        let small = (
            Tile {
                x0: 5,
                y0: 1,
                x1: 9,
                y1: 4,
            },
            3,
        );
        let large = (
            Tile {
                x0: 3,
                y0: 2,
                x1: 203,
                y1: 90,
            },
            1,
        );
        assert!(small.0.len() * (small.1 as usize) < PARALLEL_START_FROM);
        assert!(large.0.len() >= PARALLEL_START_FROM);
        for (tile, samples) in [small, large] {
            let mut paths = vec![(u32::MAX, u32::MAX)];
            start_paths(&mut paths, (tile, width), samples, |key, sample| {
                (key, sample)
            });
            let mut expected = vec![(u32::MAX, u32::MAX)];
            for y in tile.y0..tile.y1 {
                for x in tile.x0..tile.x1 {
                    expected.extend((0..samples).map(|sample| (y * width + x, sample)));
                }
            }
            assert_eq!(paths, expected, "{tile:?}, {samples} samples");
        }
    }

    #[test]
    fn started_paths_are_each_visited_once_in_lanes_on_one_thread_and_in_parallel() {
        for count in [13, PARALLEL_START_FROM + 5] {
            let mut paths = vec![0u32; count];
            for_started_in_lanes(&mut paths, |chunk| {
                assert!(chunk.len() <= LANES);
                chunk.iter_mut().for_each(|visits| *visits += 1);
            });
            assert!(paths.iter().all(|&visits| visits == 1), "{count} paths");
        }
    }

    #[test]
    fn shading_shades_every_path_once_and_none_after_a_stop() {
        let mut hits = HitBatch::default();
        hits.resize(3 * SHADE_CHUNK + 1);
        for raised in [false, true] {
            let stop = StopFlag::new();
            if raised {
                stop.raise();
            }
            let mut paths = vec![(SobolSampler::new(&[1], 0), 0u32); hits.len()];
            shade_in_parallel(
                &mut paths,
                (&hits, &stop),
                |(rng, _)| rng,
                &NoLanes,
                |_, _| (),
                None::<fn(&_, &mut _, _)>,
                |(_, shaded), _| *shaded += 1,
            );
            let expected = u32::from(!raised);
            assert!(
                paths.iter().all(|&(_, shaded)| shaded == expected),
                "stop {raised}"
            );
        }
    }
}
