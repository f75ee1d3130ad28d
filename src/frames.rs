//! Frame after frame: how many samples per pixel each frame renders, and the schedule it
//! renders with. Shared by `vcm render`, `vcm convergence` and the viewer.
//!
//! A frame is the unit of progress, of `--time` budgets and of the viewer's refresh, so it
//! must stay short; but a GPU wants big batches, which several samples per pixel per frame
//! give. [`Frames`] therefore sizes each frame: a fixed number of samples where the options
//! name one (or the backend wants one), else, on the GPU, as many as keep a frame within
//! [`Frames::TARGET`] (up to [`Frames::MOST_PACED`]). Either way a frame never renders past a
//! sample budget and, once the time per sample is known, never far past a time budget. The
//! image does not depend on any of it: sample `s` is the same whatever frame renders it.

use std::time::{Duration, Instant};

use vcm::{Film, FrameStats, Integrator, RenderError};

use crate::Backend;
use crate::integrators::ScheduleOptions;

/// How the samples per pixel of each frame are chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FrameSizes {
    /// This many in every frame (fewer in a last frame that reaches a budget).
    Fixed(u32),
    /// As many as fit [`Frames::TARGET`], a power of two from 1 up to this many.
    Paced(u32),
}

impl FrameSizes {
    /// Samples per pixel of the first frame (for `Fixed(0)` 0, which every integrator rejects).
    pub fn first(self) -> u32 {
        match self {
            FrameSizes::Fixed(samples) => samples,
            FrameSizes::Paced(_) => 1,
        }
    }
}

/// Renders an integrator frame by frame, choosing each frame's size and schedule.
pub struct Frames {
    options: ScheduleOptions,
    backend: Backend,
    pacer: Pacer,
    /// The global index of the first sample rendered.
    first: u32,
    samples: u32,
    counts: FrameCounts,
}

/// How many frames a render took and the range of their sizes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameCounts {
    /// Frames rendered.
    pub count: u32,
    /// Samples per pixel of the smallest frame (0 before any).
    pub fewest: u32,
    /// Samples per pixel of the largest frame.
    pub most: u32,
}

/// What a frame may still use: samples per pixel and wall-clock time (`None`: no limit).
#[derive(Clone, Copy, Debug, Default)]
pub struct Remaining {
    /// Samples per pixel left in the budget.
    pub samples: Option<u32>,
    /// Time left in the budget.
    pub time: Option<Duration>,
}

impl Frames {
    /// Longest frame a paced render aims at: short enough for `--time` checkpoints at 1 s
    /// and an interactive refresh, long enough for a GPU's batches to fill it.
    pub const TARGET: Duration = Duration::from_secs(1);
    /// Most samples per pixel in a paced frame: the largest measured
    /// (`docs/schedulers.md`, 16 samples per frame on an H100).
    pub const MOST_PACED: u32 = 16;

    /// Frames as `options` ask for on `backend` (see [`ScheduleOptions::frame_sizes`]).
    pub fn new(options: ScheduleOptions, backend: Backend) -> Frames {
        Frames {
            options,
            backend,
            pacer: Pacer::new(options.frame_sizes(backend), Self::TARGET),
            first: 0,
            samples: 0,
            counts: FrameCounts::default(),
        }
    }

    /// These frames, rendering global samples from `first` on (a resumed render or a shard)
    /// instead of from 0.
    pub fn starting_at(self, first: u32) -> Frames {
        Frames { first, ..self }
    }

    /// The global index of the next sample to render.
    pub fn next_sample(&self) -> u32 {
        self.first + self.samples
    }

    /// The frames rendered so far.
    pub fn counts(&self) -> FrameCounts {
        self.counts
    }

    /// Samples per pixel rendered so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Renders the next frame into `film` within `remaining` (which must leave at least one
    /// sample), with the schedule its size asks for, and returns what it did; an invalid
    /// schedule (a frame size or tile size of 0) is an error. A frame that a stop request
    /// cuts short adds nothing and counts for nothing ([`FrameStats::interrupted`]).
    pub fn render_next(
        &mut self,
        integrator: &mut dyn Integrator,
        film: &mut Film,
        remaining: Remaining,
    ) -> Result<FrameStats, RenderError> {
        let samples = self.pacer.next(remaining);
        let schedule = self.options.schedule_on(self.backend, samples);
        if integrator.samples_per_frame() != samples || self.samples == 0 {
            integrator.set_schedule(schedule)?;
        }
        let start = Instant::now();
        let stats = integrator.render_frame(film, self.next_sample());
        if stats.interrupted {
            return Ok(stats);
        }
        self.pacer.record(samples, start.elapsed());
        self.samples += samples;
        let counts = &mut self.counts;
        counts.fewest = if counts.count == 0 {
            samples
        } else {
            counts.fewest.min(samples)
        };
        counts.most = counts.most.max(samples);
        counts.count += 1;
        Ok(stats)
    }
}

/// Picks frame sizes from the time the frames so far took per sample.
#[derive(Clone, Debug)]
struct Pacer {
    sizes: FrameSizes,
    target: Duration,
    /// The size of the next frame before the budget has its say.
    next: u32,
    /// Time per sample per pixel in the last frame (`None` before the first).
    per_sample: Option<Duration>,
}

impl Pacer {
    fn new(sizes: FrameSizes, target: Duration) -> Pacer {
        Pacer {
            sizes,
            target,
            next: sizes.first(),
            per_sample: None,
        }
    }

    /// Samples per pixel of the next frame: the chosen size, cut to what `remaining` allows.
    fn next(&self, remaining: Remaining) -> u32 {
        let mut samples = self.next;
        if let Some(left) = remaining.samples {
            samples = samples.min(left);
        }
        if let (Some(left), Some(per_sample)) = (remaining.time, self.per_sample) {
            samples = samples.min(fitting(left, per_sample));
        }
        samples
    }

    /// Notes that a frame of `samples` took `took`; a paced pacer grows the next frame by
    /// powers of two while it fits the target, and shrinks it once a frame takes more than
    /// 1.5 times the target (so that sizes do not flap from frame to frame).
    fn record(&mut self, samples: u32, took: Duration) {
        let per_sample = took / samples.max(1);
        self.per_sample = Some(per_sample);
        let FrameSizes::Paced(most) = self.sizes else {
            return;
        };
        let most = most.max(1);
        let fits = fitting(self.target, per_sample);
        if per_sample * self.next > self.target.mul_f64(1.5) {
            self.next = largest_power_of_two_up_to(fits.min(most));
        } else {
            while self.next * 2 <= most && self.next * 2 <= fits {
                self.next *= 2;
            }
        }
    }
}

/// Whole samples that fit in `time` at `per_sample` each (at least 1).
fn fitting(time: Duration, per_sample: Duration) -> u32 {
    if per_sample.is_zero() {
        return u32::MAX;
    }
    (time.as_secs_f64() / per_sample.as_secs_f64()).clamp(1.0, f64::from(u32::MAX)) as u32
}

/// The largest power of two ≤ `n` (1 for 0).
fn largest_power_of_two_up_to(n: u32) -> u32 {
    if n <= 1 {
        1
    } else {
        1 << (31 - n.leading_zeros())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);

    /// Runs frames of `per_sample` each until `samples` are rendered; the frame sizes.
    fn sizes(pacer: &mut Pacer, per_sample: Duration, samples: u32) -> Vec<u32> {
        let mut done = 0;
        let mut sizes = Vec::new();
        while done < samples {
            let remaining = Remaining {
                samples: Some(samples - done),
                time: None,
            };
            let n = pacer.next(remaining);
            pacer.record(n, per_sample * n);
            sizes.push(n);
            done += n;
        }
        sizes
    }

    #[test]
    fn fixed_frames_stop_at_the_sample_budget() {
        let mut pacer = Pacer::new(FrameSizes::Fixed(4), Frames::TARGET);
        assert_eq!(sizes(&mut pacer, 10 * MS, 10), [4, 4, 2]);
        // Fixed sizes ignore how long frames take.
        assert_eq!(sizes(&mut pacer, 5000 * MS, 8), [4, 4]);
    }

    #[test]
    fn paced_frames_grow_by_powers_of_two_to_the_target_and_the_cap() {
        let mut pacer = Pacer::new(FrameSizes::Paced(16), Frames::TARGET);
        // 150 ms per sample: 6 fit in a second, so frames grow 1, 4 (the largest power of
        // two that fits), then stay.
        assert_eq!(sizes(&mut pacer, 150 * MS, 13), [1, 4, 4, 4]);
        let mut fast = Pacer::new(FrameSizes::Paced(16), Frames::TARGET);
        assert_eq!(sizes(&mut fast, MS, 50), [1, 16, 16, 16, 1]);
        let mut slow = Pacer::new(FrameSizes::Paced(16), Frames::TARGET);
        assert_eq!(sizes(&mut slow, 2000 * MS, 3), [1, 1, 1]);
    }

    #[test]
    fn paced_frames_shrink_only_well_past_the_target() {
        let mut pacer = Pacer::new(FrameSizes::Paced(16), Frames::TARGET);
        pacer.record(1, 100 * MS);
        assert_eq!(pacer.next, 8);
        // 8 × 140 ms = 1.12 s: over the target but within 1.5 times it, so the size stays.
        pacer.record(8, 8 * 140 * MS);
        assert_eq!(pacer.next, 8);
        // 8 × 250 ms = 2 s: shrink to the 4 that fit.
        pacer.record(8, 8 * 250 * MS);
        assert_eq!(pacer.next, 4);
    }

    #[test]
    fn a_time_budget_cuts_the_frame_once_the_time_per_sample_is_known() {
        let mut pacer = Pacer::new(FrameSizes::Fixed(16), Frames::TARGET);
        let half_a_second = Remaining {
            samples: None,
            time: Some(500 * MS),
        };
        // Nothing measured yet: the frame keeps its size.
        assert_eq!(pacer.next(half_a_second), 16);
        pacer.record(16, 16 * 100 * MS);
        assert_eq!(pacer.next(half_a_second), 5);
        // Never below one sample.
        let none_left = Remaining {
            samples: None,
            time: Some(Duration::ZERO),
        };
        assert_eq!(pacer.next(none_left), 1);
    }

    #[test]
    fn powers_of_two() {
        let cases = [
            (0, 1),
            (1, 1),
            (2, 2),
            (3, 2),
            (16, 16),
            (17, 16),
            (u32::MAX, 1 << 31),
        ];
        for (n, expected) in cases {
            assert_eq!(largest_power_of_two_up_to(n), expected, "{n}");
        }
    }
}
