//! Driving wavefronts: the scheduling modes and the per-worker loop.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use rayon::prelude::*;
use vcm_traversal::{HitBatch, RayBatch, Traversal};

use crate::stats::SchedulerStats;
use crate::tiles::{Tile, TileGrid};

/// The paths an integrator has in flight, advanced one segment per pass.
///
/// Each pass: [`extension_rays`](Self::extension_rays) → closest hits →
/// [`shade`](Self::shade) (which queues shadow rays) → occlusion →
/// [`resolve`](Self::resolve) (which also retires ended paths).
pub trait Wavefront: Send {
    /// What the wavefront hands back when the pass is over (e.g. its retired paths' results).
    type Output: Send;

    /// Adds the camera paths of `tile`'s pixels.
    fn start(&mut self, tile: Tile);

    /// Paths still running.
    fn active(&self) -> usize;

    /// Fills `rays` with the next segment of every active path, in path order.
    fn extension_rays(&self, rays: &mut RayBatch);

    /// Shades every active path at its hit (`hits[i]` for path `i`) and fills `shadow_rays`.
    fn shade(&mut self, hits: &HitBatch, shadow_rays: &mut RayBatch);

    /// Applies the occlusion of the shadow rays queued by [`shade`](Self::shade) and retires
    /// the paths that ended.
    fn resolve(&mut self, occluded: &[bool]);

    /// Everything the retired paths produced.
    fn finish(self) -> Self::Output;
}

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
}

impl Scheduler {
    /// Tile side of the default scheduler: the fastest measured for the path tracer on 2
    /// cores (`docs/schedulers.md`).
    pub const DEFAULT_TILE_SIZE: u32 = 32;
    /// Merge threshold of the default scheduler.
    pub const DEFAULT_MERGE_BELOW: f32 = 0.5;
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
/// `new_wavefront` (one per worker), as `scheduler` says. Returns each wavefront's output, in
/// no particular order, and what the pass measured.
pub fn run<W: Wavefront>(
    scheduler: Scheduler,
    (width, height): (u32, u32),
    traversal: &dyn Traversal,
    new_wavefront: impl Fn() -> W + Sync,
) -> (Vec<W::Output>, SchedulerStats) {
    let start = Instant::now();
    let (grid, workers, merge_below) = match scheduler {
        Scheduler::None => (TileGrid::new(width, height, width.max(height)), 1, 0.0),
        Scheduler::Tile { size, merge_below } => (
            TileGrid::new(width, height, size),
            rayon::current_num_threads()
                .min(TileGrid::new(width, height, size).len())
                .max(1),
            merge_below,
        ),
    };
    let next_tile = AtomicUsize::new(0);
    let worker = |_| {
        let mut wave = new_wavefront();
        let mut stats = SchedulerStats::default();
        let merge_at = (merge_below.max(0.0) * (grid.size * grid.size) as f32) as usize;
        let take = || {
            let index = next_tile.fetch_add(1, Ordering::Relaxed);
            (index < grid.len()).then(|| grid.tile(index))
        };
        drive(&mut wave, traversal, take, merge_at, &mut stats);
        (wave.finish(), stats)
    };
    let results: Vec<_> = (0..workers).into_par_iter().map(worker).collect();
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
    stats.wall = start.elapsed();
    let busy = stats.traversal + stats.shading;
    stats.idle = (stats.wall * workers as u32).saturating_sub(busy);
    (outputs, stats)
}

/// One worker's loop: start a tile whenever fewer than `merge_at` paths run (and when none
/// do), then advance all paths by one segment.
fn drive<W: Wavefront>(
    wave: &mut W,
    traversal: &dyn Traversal,
    mut take: impl FnMut() -> Option<Tile>,
    merge_at: usize,
    stats: &mut SchedulerStats,
) {
    let (mut rays, mut hits) = (RayBatch::default(), HitBatch::default());
    let (mut shadow_rays, mut occluded) = (RayBatch::default(), Vec::new());
    loop {
        if wave.active() == 0 || wave.active() < merge_at {
            let tile = take();
            if let Some(tile) = tile {
                time(&mut stats.shading, || wave.start(tile));
                stats.tiles += 1;
            }
            if tile.is_none() && wave.active() == 0 {
                return;
            }
        }
        stats.peak_paths = stats.peak_paths.max(wave.active());
        time(&mut stats.shading, || wave.extension_rays(&mut rays));
        time(&mut stats.traversal, || {
            traversal.intersect(&rays, &mut hits)
        });
        time(&mut stats.shading, || wave.shade(&hits, &mut shadow_rays));
        time(&mut stats.traversal, || {
            traversal.occluded(&shadow_rays, &mut occluded)
        });
        time(&mut stats.shading, || wave.resolve(&occluded));
        stats.closest_rays += rays.len() as u64;
        stats.shadow_rays += shadow_rays.len() as u64;
    }
}

/// Runs `f`, adding its duration to `total`.
fn time<T>(total: &mut Duration, f: impl FnOnce() -> T) -> T {
    let start = Instant::now();
    let result = f();
    *total += start.elapsed();
    result
}
