//! What a scheduler measured while running a pass.

use std::time::{Duration, Instant};

/// Time and work of one [`run`](crate::run), summed over its workers.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SchedulerStats {
    /// Wall-clock time of the whole pass.
    pub wall: Duration,
    /// Time in closest-hit and occlusion queries. `none` and `tile`: the workers' total
    /// (each traverses its own batches). `queue`: the wall-clock time during which the
    /// traversal thread had at least one job in flight, from the moment its submission began
    /// to the return of its `wait`; it overlaps the shading threads' work.
    pub traversal: Duration,
    /// Worker time starting, shading and retiring paths.
    pub shading: Duration,
    /// Worker time spent doing none of the above (waiting for work or for the others to
    /// finish). `none` and `tile`: workers × wall − traversal − shading; `queue`: the shading
    /// threads' workers × wall − shading (waiting for a queue to come back from traversal).
    pub idle: Duration,
    /// Worker threads: one per batch being traced (`none`, `tile`), or the shading threads
    /// beside the one traversal thread (`queue`).
    pub workers: usize,
    /// Queues in the pool of the `queue` scheduler; 0 for the others.
    pub queues: usize,
    /// Closest-hit rays traced.
    pub closest_rays: u64,
    /// Occlusion rays traced.
    pub shadow_rays: u64,
    /// Tiles started.
    pub tiles: u64,
    /// The most paths one wavefront held at once (sizes its queues).
    pub peak_paths: usize,
    /// The most memory one wavefront's queue held at once: its paths' states and its ray, hit
    /// and shadow buffers (see [`queue_memory`](Self::queue_memory) for the whole pass).
    pub peak_queue_bytes: usize,
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
        self.peak_queue_bytes = self.peak_queue_bytes.max(other.peak_queue_bytes);
    }

    /// High-water mark of the pass's queues: [`peak_queue_bytes`](Self::peak_queue_bytes)
    /// times the wavefronts that held paths at once (the workers, or the queue scheduler's
    /// pool, but no more than the tiles started: a wavefront that never started a tile holds
    /// no paths), an upper bound since the wavefronts need not peak together.
    pub fn queue_memory(&self) -> usize {
        let wavefronts = if self.queues > 0 {
            self.queues
        } else {
            self.workers
        };
        let holding_paths = (wavefronts as u64).min(self.tiles).max(1);
        self.peak_queue_bytes * holding_paths as usize
    }

    /// The wall-clock time traversal accounts for: the workers' [`traversal`](Self::traversal)
    /// shared among them (`none`, `tile`), or the traversal thread's busy time as it is
    /// (`queue`).
    pub fn traversal_share(&self) -> Duration {
        if self.queues > 0 {
            self.traversal
        } else {
            self.traversal / self.workers.max(1) as u32
        }
    }

    /// Fraction of the workers' time not [`idle`](Self::idle).
    pub fn utilization(&self) -> f64 {
        let total = self.wall.as_secs_f64() * self.workers as f64;
        if total == 0.0 {
            return 0.0;
        }
        (1.0 - self.idle.as_secs_f64() / total).clamp(0.0, 1.0)
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
