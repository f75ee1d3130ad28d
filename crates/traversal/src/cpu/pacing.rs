//! Choosing, by measuring both, whether a thread traces one ray at a time or several in
//! turn ([`Interleave::Auto`](super::Interleave::Auto)).
//!
//! Which is faster depends on the CPU's caches, the hierarchy's size and how coherent the
//! rays are, so no threshold fits all: on one Zen 4 machine, eight rays in turn made the path
//! tracer 1.10× faster on the 1.0 M-triangle `large` scene but 0.87× as fast on the
//! 18k-triangle `cornell-water`, and camera rays on a 1.0 M-triangle terrain 0.77× as fast.
//! So most chunks run the way that has been faster so far, and every [`PROBE_EVERY`]th chunk
//! (counted over all batches, so that small batches are measured too; every
//! [`PROBE_EVERY_CLEAR`]th once one way is clearly faster) the other way; the time per ray
//! of both ways over a window of chunks (total time over total rays, which weighs chunks
//! by their rays as the render's time does) updates a running estimate of their ratio, one
//! per query kind. Both ways report the same hits, so the choice never changes a result,
//! only the time it takes.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// One chunk in this many runs the way not preferred while neither is clearly faster.
pub(crate) const PROBE_EVERY: usize = 32;

/// One chunk in this many runs the way not preferred once one is clearly faster.
pub(crate) const PROBE_EVERY_CLEAR: usize = 256;

/// The estimated log ratio beyond which one way is clearly faster (by 10.5%).
const CLEAR: f64 = 0.1;

/// Rays traced each way between two updates of the estimate: chunks differ in their rays
/// (depth, region, kind), so the time per ray of fewer varies by tens of percent.
const RAYS_PER_UPDATE: usize = 4096;

/// A chunk slower per ray than this many times its way's median in the window is left out
/// (its thread lost its core while it ran).
const OUTLIER: f64 = 8.0;

/// Weight of the latest window of chunks in the running estimate.
const UPDATE_WEIGHT: f64 = 0.25;

/// The running estimate for one query kind.
#[derive(Debug)]
pub(crate) struct Pacing {
    /// Chunks started so far: every [`PROBE_EVERY`]th (or [`PROBE_EVERY_CLEAR`]th) runs the
    /// other way.
    tickets: AtomicUsize,
    window: Mutex<Window>,
}

/// Chunk times since the last update, and the estimate.
#[derive(Debug, Default)]
struct Window {
    /// Chunks run in turn, and one at a time.
    in_turn: Chunks,
    one_at_a_time: Chunks,
    /// The natural log of (time per ray in turn) / (time per ray one at a time); `None`
    /// until measured.
    log_ratio: Option<f64>,
}

impl Window {
    /// Rays in turn until measured: this runs only on hierarchies larger than the caches.
    fn prefers_interleaved(&self) -> bool {
        self.log_ratio.is_none_or(|log_ratio| log_ratio < 0.0)
    }
}

impl Pacing {
    /// An estimate that prefers rays in turn until it has measured.
    pub fn new() -> Self {
        Self {
            tickets: AtomicUsize::new(0),
            window: Mutex::new(Window::default()),
        }
    }

    fn window(&self) -> std::sync::MutexGuard<'_, Window> {
        self.window.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Whether the next chunk runs in turn: the preferred way, or the other for every
    /// [`PROBE_EVERY`]th chunk ([`PROBE_EVERY_CLEAR`]th once one way is clearly faster).
    pub fn next_chunk(&self) -> bool {
        let window = self.window();
        let clear = window.log_ratio.is_some_and(|r| r.abs() > CLEAR);
        let every = if clear {
            PROBE_EVERY_CLEAR
        } else {
            PROBE_EVERY
        };
        let probe = (self.tickets.fetch_add(1, Ordering::Relaxed)).is_multiple_of(every);
        window.prefers_interleaved() != probe
    }

    /// Takes in the time of a chunk of `rays` rays, run in turn or not. Once
    /// [`RAYS_PER_UPDATE`] rays ran each way, the ratio of their times per ray updates the
    /// estimate.
    pub fn record(&self, interleaved: bool, rays: usize, nanos: f64) {
        let mut window = self.window();
        let chunks = match interleaved {
            true => &mut window.in_turn,
            false => &mut window.one_at_a_time,
        };
        chunks.times.push((nanos, rays as f64));
        chunks.rays += rays;
        if window.in_turn.rays.min(window.one_at_a_time.rays) < RAYS_PER_UPDATE {
            return;
        }
        let latest = (window.in_turn.per_ray() / window.one_at_a_time.per_ray()).ln();
        window.in_turn = Chunks::default();
        window.one_at_a_time = Chunks::default();
        if latest.is_finite() {
            window.log_ratio = Some(match window.log_ratio {
                Some(old) => old + UPDATE_WEIGHT * (latest - old),
                None => latest,
            });
        }
    }
}

/// The chunks of one way in a window.
#[derive(Debug, Default)]
struct Chunks {
    /// Per chunk, nanoseconds and rays.
    times: Vec<(f64, f64)>,
    /// Their rays.
    rays: usize,
}

impl Chunks {
    /// Nanoseconds per ray over the chunks, [`OUTLIER`]s left out.
    fn per_ray(&mut self) -> f64 {
        let per_ray = |&(nanos, rays): &(f64, f64)| nanos / rays;
        self.times.sort_by(|a, b| per_ray(a).total_cmp(&per_ray(b)));
        let limit = OUTLIER * per_ray(&self.times[self.times.len() / 2]);
        let kept = self.times.iter().filter(|chunk| per_ray(chunk) <= limit);
        let (nanos, rays) = kept.fold((0.0, 0.0), |(n, r), &(nanos, rays)| (n + nanos, r + rays));
        nanos / rays
    }
}

#[cfg(test)]
mod tests {
    use super::{PROBE_EVERY, PROBE_EVERY_CLEAR, Pacing, RAYS_PER_UPDATE};

    /// Rays per chunk in these tests.
    const RAYS: usize = 256;

    /// `chunks` chunks of [`RAYS`] rays run as [`Pacing::next_chunk`] says, each taking
    /// `in_turn` or `one_at_a_time` ns per ray.
    fn run(pacing: &Pacing, chunks: usize, in_turn: f64, one_at_a_time: f64) {
        for _ in 0..chunks {
            let way = pacing.next_chunk();
            let per_ray = if way { in_turn } else { one_at_a_time };
            pacing.record(way, RAYS, per_ray * RAYS as f64);
        }
    }

    /// Chunks enough for one update of the estimate.
    const UPDATE: usize = PROBE_EVERY_CLEAR * RAYS_PER_UPDATE / RAYS;

    #[test]
    fn the_faster_way_wins_and_a_change_of_speed_is_followed() {
        let pacing = Pacing::new();
        assert!(pacing.window().prefers_interleaved());
        run(&pacing, UPDATE, 120.0, 100.0);
        assert!(!pacing.window().prefers_interleaved());
        // The rays become slower one at a time: a few windows turn the preference back.
        run(&pacing, 4 * UPDATE, 100.0, 130.0);
        assert!(pacing.window().prefers_interleaved());
    }

    #[test]
    fn one_slow_chunk_does_not_turn_the_preference() {
        let pacing = Pacing::new();
        run(&pacing, UPDATE, 110.0, 100.0);
        assert!(!pacing.window().prefers_interleaved());
        // A probe delayed 1000-fold (its thread lost the core) among unchanged chunks.
        pacing.record(true, RAYS, 110_000.0 * RAYS as f64);
        run(&pacing, UPDATE, 110.0, 100.0);
        assert!(!pacing.window().prefers_interleaved());
    }

    /// How many of `chunks` chunks run the way not preferred.
    fn probes(pacing: &Pacing, chunks: usize) -> usize {
        let preferred = pacing.window().prefers_interleaved();
        (0..chunks)
            .filter(|_| pacing.next_chunk() != preferred)
            .count()
    }

    #[test]
    fn the_other_way_is_probed_less_once_one_is_clearly_faster() {
        let pacing = Pacing::new();
        assert_eq!(probes(&pacing, 16 * PROBE_EVERY), 16);
        // Nothing recorded: the preference stands.
        assert!(pacing.window().prefers_interleaved());
        // Nearly even: still probed as often.
        run(&pacing, UPDATE, 100.0, 105.0);
        assert!(pacing.window().prefers_interleaved());
        assert_eq!(probes(&pacing, 16 * PROBE_EVERY), 16);
        // Clearly faster one at a time: probed less.
        run(&pacing, 2 * UPDATE, 150.0, 100.0);
        assert!(!pacing.window().prefers_interleaved());
        assert_eq!(probes(&pacing, 16 * PROBE_EVERY_CLEAR), 16);
    }
}
