//! Frame after frame: how many samples per pixel each frame renders, and the schedule it
//! renders with.
//!
//! A frame is the unit of progress, of `--time` budgets and of the viewer's refresh, so it
//! must stay short; but a GPU wants big batches, which several samples per pixel per frame
//! give. [`Frames`] therefore sizes each frame: a fixed number of samples where the options
//! name one (or the backend wants one), else, on the GPU, as many as keep a frame within
//! [`Frames::TARGET`] (up to [`Frames::MOST_PACED`]). Either way a frame never renders past a
//! sample budget and, once the time per sample is known, never far past a time budget. The
//! image does not depend on any of it: sample `s` is the same whatever frame renders it.

use std::sync::Arc;
use std::time::{Duration, Instant};

use vcm::{Film, FrameStats, Integrator, RenderError};
use vcm_gpu::GpuRenderError;
use vcm_scene::Scene;
use vcm_traversal::Traversal;

use super::pacer::{Pacer, Remaining};
use super::schedule::ScheduleOptions;
use crate::integrators::{self, Algorithm, IntegratorOptions};
use crate::{Backend, BuiltTraversal, Shading};

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

    /// The integrator of `algorithm` with `options` for `scene` at `size`, traced by
    /// `traversal` ([`integrators::build`]), set up with the schedule of the first of these
    /// frames (which checks it and the memory it needs), of at most `samples_left` samples
    /// per pixel where the render has no more to do.
    pub fn integrator(
        &self,
        algorithm: Algorithm,
        scene: &Arc<Scene>,
        traversal: Arc<dyn Traversal>,
        size: (u32, u32),
        options: &IntegratorOptions,
        samples_left: Option<u32>,
    ) -> Result<Box<dyn Integrator>, RenderError> {
        let mut integrator = integrators::build(algorithm, scene, traversal, size, options)?;
        let schedule = self.options.first_schedule_on(self.backend, samples_left);
        integrator.set_schedule(schedule)?;
        Ok(integrator)
    }

    /// [`integrator`](Self::integrator) with its paths shaded where `shading` says: on the
    /// GPU, every path shaded in kernels on the GPU backend's hierarchy in `built`
    /// ([`integrators::build_on_gpu`]). GPU shading on the CPU backend is
    /// [`GpuRenderError::Refused`].
    pub fn shaded_integrator(
        &self,
        (algorithm, shading): (Algorithm, Shading),
        scene: &Arc<Scene>,
        built: &BuiltTraversal,
        size: (u32, u32),
        options: &IntegratorOptions,
        samples_left: Option<u32>,
    ) -> Result<Box<dyn Integrator>, GpuRenderError> {
        let bvh = match (shading, &built.gpu) {
            (Shading::Cpu, _) => {
                return Ok(self.integrator(
                    algorithm,
                    scene,
                    Arc::clone(&built.traversal),
                    size,
                    options,
                    samples_left,
                )?);
            }
            (Shading::Gpu, None) => {
                return Err(GpuRenderError::Refused(
                    "needs the gpu backend, whose hierarchy it traces".into(),
                ));
            }
            (Shading::Gpu, Some(bvh)) => bvh,
        };
        let mut integrator = integrators::build_on_gpu(algorithm, scene, bvh, size, options)?;
        let schedule = self.options.first_schedule_on(self.backend, samples_left);
        integrator.set_schedule(schedule)?;
        Ok(integrator)
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
    /// cuts short adds nothing and counts for nothing ([`FrameStats::interrupted`]); one
    /// whose device failed adds nothing and ends in [`RenderError::DeviceFailed`].
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
        if let Some(failure) = integrator.failure() {
            return Err(RenderError::DeviceFailed(failure));
        }
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
