//! [`GpuFrames`]: what every GPU integrator does with a frame — dispatches of consecutive
//! invocations of its kernel, their radiances and splats added to a frame's film, merged into
//! the render's film once the frame is whole — and the state that goes with it.

use std::time::Instant;

use glam::Vec3;
use vcm::{Film, FrameStats, RenderError, Schedule, StopFlag};

use crate::kernel::SceneKernel;

/// What one dispatch brought back.
pub(crate) struct Dispatched {
    /// One radiance per invocation, added to pixel invocation / samples per frame.
    pub radiance: Vec<Vec3>,
    /// (pixel, contribution) of each light tracing splat.
    pub splats: Vec<(u32, Vec3)>,
    /// Rays traced, by the integrator's own three kinds.
    pub rays: [u64; 3],
}

/// A GPU integrator's kernel and frames.
pub(crate) struct GpuFrames {
    pub kernel: SceneKernel,
    /// The image size.
    pub size: (u32, u32),
    /// Invocations per dispatch: the buffers' capacity, halved for good when a dispatch's
    /// output overflows.
    paths_per_dispatch: u64,
    samples_per_frame: u32,
    stop: StopFlag,
    /// What failed on the GPU, once something has: no frame renders after it.
    failure: Option<String>,
}

impl GpuFrames {
    /// Frames of `kernel` at `size`, dispatching up to `paths_per_dispatch` invocations.
    pub fn new(kernel: SceneKernel, size: (u32, u32), paths_per_dispatch: u64) -> GpuFrames {
        GpuFrames {
            kernel,
            size,
            paths_per_dispatch,
            samples_per_frame: 1,
            stop: StopFlag::new(),
            failure: None,
        }
    }

    /// Invocations per dispatch now.
    #[cfg(test)]
    pub fn paths_per_dispatch(&self) -> u64 {
        self.paths_per_dispatch
    }

    /// Renders the frame starting at sample `first_sample`: one invocation per pixel and
    /// sample, in dispatches that `dispatch` renders (`(first_sample, samples per frame)`,
    /// `(first invocation, count)`; `Ok(None)` where its output overflowed: those
    /// invocations are rendered again, half as many at a time from then on), and adds them
    /// to `film`. Returns the statistics `stats` makes of the rays traced and the
    /// invocations, with the time it took, or [`FrameStats::INTERRUPTED`] where the frame
    /// was stopped or failed (`algorithm` names it in the failure), leaving `film` as it was.
    pub fn render(
        &mut self,
        film: &mut Film,
        first_sample: u32,
        algorithm: &str,
        mut dispatch: impl FnMut(
            &SceneKernel,
            (u32, u32),
            (u64, u64),
        ) -> Result<Option<Dispatched>, String>,
        stats: impl FnOnce([u64; 3], u64) -> FrameStats,
    ) -> FrameStats {
        let start = Instant::now();
        let (width, height) = self.size;
        assert_eq!(
            (film.width(), film.height()),
            self.size,
            "film size differs from the settings"
        );
        let samples = u64::from(self.samples_per_frame);
        let invocations = u64::from(width) * u64::from(height) * samples;
        // The frame's samples, added to `film` once the frame is whole (an interrupted one
        // leaves it as it was); the host holds one dispatch's output at a time.
        let mut frame = Film::new(width, height);
        let mut rays = [0u64; 3];
        let mut first = 0;
        while first < invocations {
            if self.stop.is_raised() || self.failure.is_some() {
                return FrameStats::INTERRUPTED;
            }
            let count = self.paths_per_dispatch.min(invocations - first);
            let frame_samples = (first_sample, self.samples_per_frame);
            let dispatched = match dispatch(&self.kernel, frame_samples, (first, count)) {
                Ok(Some(dispatched)) => dispatched,
                Ok(None) if count > 1 => {
                    self.paths_per_dispatch = count / 2;
                    continue;
                }
                Ok(None) => {
                    let error = "one invocation's output overflows the dispatch's buffer";
                    self.failure = Some(format!("{algorithm} on the GPU: {error}"));
                    return FrameStats::INTERRUPTED;
                }
                Err(error) => {
                    self.failure = Some(format!("{algorithm} on the GPU: {error}"));
                    return FrameStats::INTERRUPTED;
                }
            };
            for (invocation, rgb) in (first..).zip(dispatched.radiance) {
                frame.add((invocation / samples) as usize, rgb);
            }
            for (pixel, contribution) in dispatched.splats {
                frame.add_splat(pixel as usize, contribution);
            }
            for (total, traced) in rays.iter_mut().zip(dispatched.rays) {
                *total += traced;
            }
            first += count;
        }
        // Exact sums: the same film as adding each sample and splat to `film` directly.
        film.merge(&frame);
        FrameStats {
            shading_time: start.elapsed(),
            ..stats(rays, invocations)
        }
    }

    /// Takes the samples per pixel per frame of `schedule` (its scheduler, a CPU matter,
    /// does not apply), which must number a frame's invocations (`what`) in 32 bits.
    pub fn set_schedule(&mut self, schedule: Schedule, what: &str) -> Result<(), RenderError> {
        let schedule = schedule.validated()?;
        let (width, height) = self.size;
        let count = u64::from(width) * u64::from(height) * u64::from(schedule.samples_per_frame);
        if count > u64::from(u32::MAX) {
            return Err(RenderError::InvalidSetting(format!(
                "{} samples per pixel per frame make {count} {what}, more than a GPU kernel \
                 numbers in one frame (2³² − 1)",
                schedule.samples_per_frame
            )));
        }
        self.samples_per_frame = schedule.samples_per_frame;
        Ok(())
    }

    /// The samples per pixel per frame.
    pub fn samples_per_frame(&self) -> u32 {
        self.samples_per_frame
    }

    /// Sets the flag that stops a frame between dispatches.
    pub fn set_stop(&mut self, stop: StopFlag) {
        self.stop = stop;
    }

    /// What failed on the GPU, if anything has.
    pub fn failure(&self) -> Option<String> {
        self.failure.clone()
    }
}

/// The [`Integrator`](vcm::Integrator) methods that a GPU integrator leaves to its
/// [`GpuFrames`] (field `frames`), whose frames number `$what` (one per pixel and sample).
macro_rules! integrator_methods_of_frames {
    ($what:literal) => {
        fn image_size(&self) -> (u32, u32) {
            self.frames.size
        }

        fn set_schedule(&mut self, schedule: vcm::Schedule) -> Result<(), vcm::RenderError> {
            self.frames.set_schedule(schedule, $what)
        }

        fn set_stop(&mut self, stop: vcm::StopFlag) {
            self.frames.set_stop(stop);
        }

        fn samples_per_frame(&self) -> u32 {
            self.frames.samples_per_frame()
        }

        fn failure(&self) -> Option<String> {
            self.frames.failure()
        }
    };
}
pub(crate) use integrator_methods_of_frames;
