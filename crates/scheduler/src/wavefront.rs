//! What a scheduler drives: a wavefront of paths, advanced one segment per pass.

use vcm_traversal::{HitBatch, RayBatch};

use crate::stats::{SchedulerStats, time};
use crate::tiles::{Tile, TileCounter};

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

    /// Bytes held for the paths in flight: their states and per-path buffers, not the
    /// results of the paths that ended.
    fn memory_bytes(&self) -> usize;

    /// Fills `rays` with the next segment of every active path, in path order.
    fn extension_rays(&self, rays: &mut RayBatch);

    /// Shades every active path at its hit (`hits[i]` for path `i`) and fills `shadow_rays`.
    /// Once the pass's stop flag is raised it may leave paths unshaded: the scheduler then
    /// ends the pass without resolving them.
    fn shade(&mut self, hits: &HitBatch, shadow_rays: &mut RayBatch);

    /// Applies the occlusion of the shadow rays queued by [`shade`](Self::shade) and retires
    /// the paths that ended.
    fn resolve(&mut self, occluded: &[bool]);

    /// Everything the retired paths produced.
    fn finish(self) -> Self::Output;
}

/// Notes the memory of a wavefront's queue after shading, when it holds the most: the
/// wavefront's paths and its ray, hit and shadow buffers.
pub(crate) fn note_queue_memory<W: Wavefront>(
    stats: &mut SchedulerStats,
    wave: &W,
    (rays, hits, shadow_rays): (&RayBatch, &HitBatch, &RayBatch),
    occluded: &[bool],
) {
    let bytes = wave.memory_bytes()
        + rays.memory_bytes()
        + hits.memory_bytes()
        + shadow_rays.memory_bytes()
        + std::mem::size_of_val(occluded);
    stats.peak_queue_bytes = stats.peak_queue_bytes.max(bytes);
}

/// Starts the next tile of `tiles` in `wave` when none of its paths runs or fewer than
/// `merge_at` do (tile merging), timing it as shading. Returns whether `wave` has paths to
/// trace; `false` means it is done: no path runs and no tile is left.
pub(crate) fn top_up<W: Wavefront>(
    wave: &mut W,
    tiles: &TileCounter,
    merge_at: usize,
    stats: &mut SchedulerStats,
) -> bool {
    if wave.active() < merge_at.max(1) {
        // One tile, or more while the tiles taken start no path at all.
        while let Some(tile) = tiles.take() {
            time(&mut stats.shading, || wave.start(tile));
            stats.tiles += 1;
            if wave.active() > 0 {
                break;
            }
        }
    }
    stats.peak_paths = stats.peak_paths.max(wave.active());
    wave.active() > 0
}
