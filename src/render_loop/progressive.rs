//! The progressive render loop: frames until a sample count or a time budget is spent or a
//! stop is requested. `vcm render`, `vcm convergence`, `vcm experiment` and the Python
//! package run it, each watching the frames through its own callback (progress bars,
//! checkpoints, error reports).

use std::time::{Duration, Instant};

use vcm::{Film, FrameStats, Integrator, RenderError, StopFlag};

use super::frames::{FrameCounts, Frames};
use super::pacer::Remaining;

/// When to stop rendering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// This many samples per pixel.
    Samples(u32),
    /// This many seconds of wall-clock time, and at least one frame (what went before the
    /// render, such as choosing its algorithm, may have spent them).
    Seconds(f64),
}

impl Budget {
    /// Whether the budget is spent after `spp` samples per pixel and `elapsed`.
    pub fn done(&self, spp: u32, elapsed: Duration) -> bool {
        match *self {
            Budget::Samples(n) => spp >= n,
            Budget::Seconds(s) => spp > 0 && elapsed.as_secs_f64() >= s,
        }
    }

    /// What is left of the budget after `spp` samples per pixel and `elapsed`.
    pub fn remaining(&self, spp: u32, elapsed: Duration) -> Remaining {
        match *self {
            Budget::Samples(n) => Remaining {
                samples: Some(n.saturating_sub(spp)),
                time: None,
            },
            Budget::Seconds(s) => Remaining {
                samples: None,
                time: Some(Duration::from_secs_f64(s).saturating_sub(elapsed)),
            },
        }
    }
}

/// A whole frame just rendered, as the loop's callback sees it.
pub struct FrameDone<'a> {
    /// The film with the frame added.
    pub film: &'a Film,
    /// What the frame did.
    pub stats: &'a FrameStats,
    /// Samples per pixel rendered so far.
    pub spp: u32,
    /// Wall-clock time since the render started.
    pub elapsed: Duration,
}

/// What a progressive render did.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Samples per pixel rendered.
    pub spp: u32,
    /// The frames they came in.
    pub frames: FrameCounts,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Work summed over all frames.
    pub totals: FrameStats,
    /// Why the render ended early, if its device failed
    /// ([`Integrator::failure`](vcm::Integrator::failure)): the whole frames before the
    /// failure are in the film, for the caller to keep before it reports the failure.
    pub failure: Option<String>,
}

/// Renders `frames` into `film` until `budget` is spent, `stop` is raised (which also cuts
/// the frame in progress short, dropping it whole) or the integrator's device fails (which
/// drops that frame too: [`Rendered::failure`]), calling `after_frame` after each whole
/// frame; an error from it ends the render with that error. Time is counted from `start`
/// (now, or before the render's setup where that counts against the budget: choosing the
/// algorithm).
pub fn render(
    integrator: &mut dyn Integrator,
    frames: &mut Frames,
    film: &mut Film,
    (budget, start): (Budget, Instant),
    stop: &StopFlag,
    mut after_frame: impl FnMut(FrameDone<'_>) -> anyhow::Result<()>,
) -> anyhow::Result<Rendered> {
    integrator.set_stop(stop.clone());
    let mut totals = FrameStats::default();
    let mut failure = None;
    while !budget.done(frames.samples(), start.elapsed()) && !stop.is_raised() {
        let remaining = budget.remaining(frames.samples(), start.elapsed());
        let stats = match frames.render_next(integrator, film, remaining) {
            Err(RenderError::DeviceFailed(why)) => {
                failure = Some(why);
                break;
            }
            rendered => rendered?,
        };
        if stats.interrupted {
            break;
        }
        totals.accumulate(&stats);
        after_frame(FrameDone {
            film,
            stats: &stats,
            spp: frames.samples(),
            elapsed: start.elapsed(),
        })?;
    }
    Ok(Rendered {
        spp: frames.samples(),
        frames: frames.counts(),
        seconds: start.elapsed().as_secs_f64(),
        totals,
        failure,
    })
}

#[cfg(test)]
mod tests {
    use vcm::Schedule;

    use super::*;
    use crate::Backend;
    use crate::render_loop::ScheduleOptions;
    use crate::scene::Decision;

    /// Adds one white sample to its one pixel per frame; its device fails in its third.
    struct FailsInTheThirdFrame {
        frames: u32,
    }

    impl Integrator for FailsInTheThirdFrame {
        fn render_frame(&mut self, film: &mut Film, _first_sample: u32) -> FrameStats {
            self.frames += 1;
            if self.frames == 3 {
                return FrameStats::INTERRUPTED;
            }
            film.add(0, glam::Vec3::ONE);
            FrameStats::default()
        }

        fn set_stop(&mut self, _stop: StopFlag) {}

        fn image_size(&self) -> (u32, u32) {
            (1, 1)
        }

        fn set_schedule(&mut self, _schedule: Schedule) -> Result<(), RenderError> {
            Ok(())
        }

        fn decisions(&self) -> Vec<Decision> {
            Vec::new()
        }

        fn failure(&self) -> Option<String> {
            (self.frames >= 3).then(|| "the device fell over".to_owned())
        }
    }

    #[test]
    fn a_device_failure_ends_the_render_and_keeps_the_whole_frames_before_it() {
        let mut integrator = FailsInTheThirdFrame { frames: 0 };
        let mut frames = Frames::new(ScheduleOptions::default(), Backend::Cpu);
        let mut film = Film::new(1, 1);
        let start = (Budget::Samples(64), Instant::now());
        let result = render(
            &mut integrator,
            &mut frames,
            &mut film,
            start,
            &StopFlag::new(),
            |_| Ok(()),
        );
        let rendered = result.unwrap();
        assert_eq!(rendered.failure.as_deref(), Some("the device fell over"));
        assert_eq!(integrator.frames, 3);
        // Two whole frames of one sample each; the third added nothing.
        assert_eq!(rendered.spp, 2);
        assert_eq!(film.mean(), vec![glam::Vec3::ONE]);
    }

    #[test]
    fn sample_budgets_count_samples_and_time_budgets_seconds() {
        let budget = Budget::Samples(8);
        assert!(!budget.done(7, Duration::from_secs(1000)));
        assert!(budget.done(8, Duration::ZERO));
        assert_eq!(budget.remaining(3, Duration::ZERO).samples, Some(5));
        assert_eq!(budget.remaining(9, Duration::ZERO).samples, Some(0));
        let budget = Budget::Seconds(2.0);
        assert!(!budget.done(1000, Duration::from_millis(1999)));
        assert!(budget.done(1, Duration::from_secs(2)));
        // Not before a frame is rendered, however long the set-up took.
        assert!(!budget.done(0, Duration::from_secs(20)));
        let left = budget.remaining(0, Duration::from_millis(500));
        assert_eq!(left.time, Some(Duration::from_millis(1500)));
        assert_eq!(left.samples, None);
    }
}
