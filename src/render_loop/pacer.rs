//! Frame sizes from the time the frames so far took: fixed, or paced to a target duration,
//! and never past what a budget leaves.

use std::time::Duration;

use super::schedule::FrameSizes;

/// What a frame may still use: samples per pixel and wall-clock time (`None`: no limit).
#[derive(Clone, Copy, Debug, Default)]
pub struct Remaining {
    /// Samples per pixel left in the budget.
    pub samples: Option<u32>,
    /// Time left in the budget.
    pub time: Option<Duration>,
}

/// Picks frame sizes from the time the frames so far took per sample.
#[derive(Clone, Debug)]
pub(super) struct Pacer {
    sizes: FrameSizes,
    target: Duration,
    /// The size of the next frame before the budget has its say.
    next: u32,
    /// Time per sample per pixel in the last frame (`None` before the first).
    per_sample: Option<Duration>,
}

impl Pacer {
    pub(super) fn new(sizes: FrameSizes, target: Duration) -> Pacer {
        Pacer {
            sizes,
            target,
            next: sizes.first(),
            per_sample: None,
        }
    }

    /// Samples per pixel of the next frame: the chosen size, cut to what `remaining` allows.
    pub(super) fn next(&self, remaining: Remaining) -> u32 {
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
    pub(super) fn record(&mut self, samples: u32, took: Duration) {
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
    use crate::render_loop::Frames;

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
