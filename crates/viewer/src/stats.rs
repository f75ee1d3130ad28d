//! Live statistics of the render shown: throughput derived from a [`Snapshot`], and the
//! relMSE-over-time history of the current render.

use std::time::Duration;

use crate::renderer::Snapshot;

/// Throughput and counts of a render so far.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiveStats {
    /// Samples per pixel accumulated, those of a continued render state included.
    pub spp: u64,
    /// Frames per second of render time.
    pub frames_per_second: f64,
    /// Rays of every kind per second of render time.
    pub rays_per_second: f64,
    /// Render time since the accumulation (re)started.
    pub elapsed: Duration,
    /// Non-finite samples dropped.
    pub dropped: u64,
}

impl LiveStats {
    /// The statistics of `snapshot`.
    pub fn of(snapshot: &Snapshot) -> LiveStats {
        let seconds = snapshot.elapsed.as_secs_f64().max(1e-9);
        LiveStats {
            spp: snapshot.resumed_spp + u64::from(snapshot.spp),
            frames_per_second: f64::from(snapshot.spp) / seconds,
            rays_per_second: snapshot.totals.rays() as f64 / seconds,
            elapsed: snapshot.elapsed,
            dropped: snapshot.dropped,
        }
    }
}

/// (seconds, relMSE) of the render of one generation, in the order they were measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ErrorHistory {
    generation: u64,
    points: Vec<(f64, f64)>,
}

impl ErrorHistory {
    /// Adds the snapshot's relMSE (if it has one); a snapshot of a newer render clears the
    /// history first.
    pub fn record(&mut self, snapshot: &Snapshot) {
        if snapshot.generation != self.generation {
            self.generation = snapshot.generation;
            self.points.clear();
        }
        if let Some(relmse) = snapshot.relmse {
            self.points.push((snapshot.elapsed.as_secs_f64(), relmse));
        }
    }

    /// The points: (seconds of render time, relMSE).
    pub fn points(&self) -> &[(f64, f64)] {
        &self.points
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vcm::FrameStats;
    use vcm_rs::integrators::Algorithm;

    fn snapshot(generation: u64, spp: u32, seconds: f64, relmse: Option<f64>) -> Snapshot {
        Snapshot {
            generation,
            algorithm: Algorithm::Pt,
            chosen: None,
            size: (2, 1),
            mean: vec![glam::Vec3::ZERO; 2],
            spp,
            resumed_spp: 0,
            elapsed: Duration::from_secs_f64(seconds),
            totals: FrameStats {
                camera_rays: 2 * u64::from(spp),
                shadow_rays: 3 * u64::from(spp),
                ..FrameStats::default()
            },
            dropped: 1,
            relmse,
        }
    }

    #[test]
    fn rates_are_per_second_of_render_time() {
        let stats = LiveStats::of(&snapshot(1, 8, 2.0, None));
        assert_eq!(stats.spp, 8);
        assert_eq!(stats.frames_per_second, 4.0);
        assert_eq!(stats.rays_per_second, 20.0);
        assert_eq!(stats.dropped, 1);
        let resumed = Snapshot {
            resumed_spp: 100,
            ..snapshot(1, 8, 2.0, None)
        };
        let stats = LiveStats::of(&resumed);
        assert_eq!(stats.spp, 108, "the samples continued count");
        assert_eq!(
            stats.frames_per_second, 4.0,
            "the samples continued took no time"
        );
    }

    #[test]
    fn history_follows_the_current_render_only() {
        let mut history = ErrorHistory::default();
        history.record(&snapshot(1, 1, 0.5, Some(0.2)));
        history.record(&snapshot(1, 2, 1.0, Some(0.1)));
        history.record(&snapshot(1, 3, 1.5, None));
        assert_eq!(history.points(), &[(0.5, 0.2), (1.0, 0.1)]);
        history.record(&snapshot(2, 1, 0.25, Some(0.3)));
        assert_eq!(history.points(), &[(0.25, 0.3)]);
    }
}
