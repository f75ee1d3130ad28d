//! What a scheduler measured while running a pass.

use std::time::{Duration, Instant};

/// Time and work of one [`run`](crate::run), summed over its workers.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SchedulerStats {
    /// Wall-clock time of the whole pass.
    pub wall: Duration,
    /// Worker time in closest-hit and occlusion queries.
    pub traversal: Duration,
    /// Worker time starting, shading and retiring paths.
    pub shading: Duration,
    /// Worker time spent neither traversing nor shading (waiting for work or for the others
    /// to finish): workers × wall − traversal − shading.
    pub idle: Duration,
    /// Worker threads.
    pub workers: usize,
    /// Closest-hit rays traced.
    pub closest_rays: u64,
    /// Occlusion rays traced.
    pub shadow_rays: u64,
    /// Tiles started.
    pub tiles: u64,
    /// The most paths one wavefront held at once (sizes its queues).
    pub peak_paths: usize,
}

impl SchedulerStats {
    /// Adds the counts and busy times of `other` (another worker, or another pass).
    pub fn accumulate(&mut self, other: &SchedulerStats) {
        self.traversal += other.traversal;
        self.shading += other.shading;
        self.closest_rays += other.closest_rays;
        self.shadow_rays += other.shadow_rays;
        self.tiles += other.tiles;
        self.peak_paths = self.peak_paths.max(other.peak_paths);
    }

    /// Fraction of the workers' time spent traversing or shading.
    pub fn utilization(&self) -> f64 {
        let total = self.wall.as_secs_f64() * self.workers as f64;
        if total == 0.0 {
            return 0.0;
        }
        ((self.traversal + self.shading).as_secs_f64() / total).min(1.0)
    }

    /// Sets the wall-clock time of a pass that began at `start` and the idle time of its
    /// [`workers`](Self::workers), who were busy for `busy` in all.
    pub(crate) fn close(&mut self, start: Instant, busy: Duration) {
        self.wall = start.elapsed();
        self.idle = (self.wall * self.workers as u32).saturating_sub(busy);
    }
}

/// Runs `f`, adding its duration to `total`.
pub(crate) fn time<T>(total: &mut Duration, f: impl FnOnce() -> T) -> T {
    let start = Instant::now();
    let result = f();
    *total += start.elapsed();
    result
}
