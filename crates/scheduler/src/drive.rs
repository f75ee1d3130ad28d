//! The scheduling modes, and the loop of the `none` and `tile` workers.

use std::time::Instant;

use rayon::prelude::*;
use vcm_traversal::{HitBatch, RayBatch, Traversal};

use crate::StopFlag;
use crate::stats::{SchedulerStats, time};
use crate::tiles::{TileCounter, TileGrid};
use crate::wavefront::{Wavefront, note_queue_memory, top_up};

/// How paths are grouped into batches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scheduler {
    /// One wavefront over the whole image: every pass is one batch of all active paths.
    None,
    /// Every worker thread takes `size × size` tiles from a shared counter and traces them
    /// to completion; when its active paths drop below `merge_below` × a full tile, it adds
    /// the next tile's camera paths to the same batches (tile merging).
    Tile {
        /// Tile side in pixels.
        size: u32,
        /// Fraction of a full tile below which the next tile is merged in (0 disables it).
        merge_below: f32,
    },
    /// A pool of `queues` wavefronts, each with its own ray, hit and shadow buffers, taking
    /// `size × size` tiles from a shared counter (and merging in the next one below
    /// `merge_below` of a tile, as [`Tile`](Self::Tile) does). Each queue passes through
    /// explicit states (empty, in use, ready for traversal, for shading, for shadow
    /// traversal, for resolving); one thread collects every traversal job
    /// ([`Traversal::submit`]), keeping several in flight, while the shading threads start,
    /// shade and resolve the queues that are ready for it and, where the backend submits
    /// asynchronously, submit their jobs themselves. With an asynchronous backend (the
    /// GPU) the CPU shades some queues while others are traversed; the pool size bounds the
    /// memory.
    Queue {
        /// Wavefronts in the pool (at least 1).
        queues: usize,
        /// Tile side in pixels.
        size: u32,
        /// Fraction of a full tile below which a queue merges in the next tile (0 disables
        /// it).
        merge_below: f32,
    },
}

impl Scheduler {
    /// Tile side of the default scheduler: the fastest measured for the path tracer on 2
    /// cores (`docs/schedulers.md`).
    pub const DEFAULT_TILE_SIZE: u32 = 32;
    /// Merge threshold of the default scheduler.
    pub const DEFAULT_MERGE_BELOW: f32 = 0.5;

    /// Queues of a [`Queue`](Self::Queue) scheduler when none are asked for: one per
    /// shading thread (the rayon pool's threads) and one more, so that one queue can be
    /// traversed while every shading thread has a queue of its own.
    pub fn default_queues() -> usize {
        rayon::current_num_threads().max(1) + 1
    }

    /// The most paths a pass over a `width × height` image with `samples` paths per pixel
    /// holds at once on the caller's rayon pool (an upper bound, for memory budgets): every
    /// wavefront with a full tile and the paths below which it merges in the next one, and
    /// never more than the whole image.
    pub fn most_paths_in_flight(&self, (width, height): (u32, u32), samples: u32) -> u64 {
        let all = u64::from(width) * u64::from(height) * u64::from(samples);
        let (size, merge_below, wavefronts) = match *self {
            Scheduler::None => return all,
            Scheduler::Tile { size, merge_below } => {
                (size, merge_below, rayon::current_num_threads())
            }
            Scheduler::Queue {
                queues,
                size,
                merge_below,
            } => (size, merge_below, queues),
        };
        let tile = u64::from(size).saturating_mul(u64::from(size));
        // As `TileCounter::merge_at` computes it; a float cast saturates.
        let merge_at = (f64::from(merge_below.max(0.0)) * tile as f64) as u64;
        let per_wavefront = merge_at.saturating_add(tile.saturating_mul(u64::from(samples)));
        per_wavefront
            .saturating_mul(wavefronts.max(1) as u64)
            .min(all)
    }
}

impl Default for Scheduler {
    /// Tiles of [`DEFAULT_TILE_SIZE`](Self::DEFAULT_TILE_SIZE) pixels, merging below
    /// [`DEFAULT_MERGE_BELOW`](Self::DEFAULT_MERGE_BELOW) of a tile.
    fn default() -> Self {
        Self::Tile {
            size: Self::DEFAULT_TILE_SIZE,
            merge_below: Self::DEFAULT_MERGE_BELOW,
        }
    }
}

/// Traces the camera paths of every pixel of a `width × height` image with wavefronts from
/// `new_wavefront` (one per worker or queue), as `scheduler` says. Returns each wavefront's
/// output, in no particular order, and what the pass measured. Once `stop` is raised no tile
/// starts and the workers end between passes: the outputs are then incomplete.
///
/// Call it from any thread, a rayon worker included: the work runs on the caller's rayon
/// pool (the global pool when the caller belongs to none).
pub fn run<W: Wavefront>(
    scheduler: Scheduler,
    (width, height): (u32, u32),
    traversal: &dyn Traversal,
    stop: &StopFlag,
    new_wavefront: impl Fn() -> W + Sync,
) -> (Vec<W::Output>, SchedulerStats) {
    let (size, merge_below) = match scheduler {
        Scheduler::None => (width.max(height), 0.0),
        Scheduler::Tile { size, merge_below } => (size, merge_below),
        Scheduler::Queue {
            queues,
            size,
            merge_below,
        } => {
            let tiles = TileCounter::new(TileGrid::new(width, height, size), stop);
            return crate::queue::run(queues, &tiles, merge_below, traversal, new_wavefront);
        }
    };
    let start = Instant::now();
    let tiles = TileCounter::new(TileGrid::new(width, height, size), stop);
    let workers = match scheduler {
        Scheduler::None => 1,
        _ => rayon::current_num_threads().min(tiles.len()).max(1),
    };
    let merge_at = tiles.merge_at(merge_below);
    let worker = |_| {
        let mut wave = new_wavefront();
        let mut stats = SchedulerStats::default();
        drive(&mut wave, traversal, &tiles, merge_at, &mut stats);
        (wave.finish(), stats)
    };
    // A single worker would run on the calling thread, which need not belong to the pool;
    // every parallel loop inside it (traversal, shading) would then hand its work to the
    // pool and sleep until it returns, two context switches per batch. `scope` moves the
    // workers onto the pool first.
    let results: Vec<_> = rayon::scope(|_| (0..workers).into_par_iter().map(worker).collect());
    let mut stats = SchedulerStats {
        workers,
        ..SchedulerStats::default()
    };
    let outputs = results
        .into_iter()
        .map(|(output, worker_stats)| {
            stats.accumulate(&worker_stats);
            output
        })
        .collect();
    stats.close(start, stats.traversal + stats.shading);
    (outputs, stats)
}

/// One worker's loop: start a tile whenever fewer than `merge_at` paths run (and when none
/// do), then advance all paths by one segment; until no path is left, or a stop is requested.
/// The stop flag is checked between the steps, not only between segments: a wavefront over
/// the whole image (the `none` scheduler) starts, traces or shades millions of paths in one
/// step, and its shading itself stops once asked to.
fn drive<W: Wavefront>(
    wave: &mut W,
    traversal: &dyn Traversal,
    tiles: &TileCounter,
    merge_at: usize,
    stats: &mut SchedulerStats,
) {
    let (mut rays, mut hits) = (RayBatch::default(), HitBatch::default());
    let (mut shadow_rays, mut occluded) = (RayBatch::default(), Vec::new());
    // Past a stop the pass is dropped whole: its paths are left where they are.
    while !tiles.stopped() && top_up(wave, tiles, merge_at, stats) && !tiles.stopped() {
        time(&mut stats.shading, || wave.extension_rays(&mut rays));
        time(&mut stats.traversal, || {
            traversal.intersect(&rays, &mut hits)
        });
        stats.closest_rays += rays.len() as u64;
        if tiles.stopped() {
            break;
        }
        time(&mut stats.shading, || wave.shade(&hits, &mut shadow_rays));
        if tiles.stopped() {
            break;
        }
        note_queue_memory(stats, wave, (&rays, &hits, &shadow_rays), &occluded);
        time(&mut stats.traversal, || {
            traversal.occluded(&shadow_rays, &mut occluded)
        });
        stats.shadow_rays += shadow_rays.len() as u64;
        time(&mut stats.shading, || wave.resolve(&occluded));
    }
}
