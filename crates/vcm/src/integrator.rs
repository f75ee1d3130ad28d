//! What every integrator offers: rendering one frame into a film, and its statistics.

use std::time::Duration;

use vcm_scene::Decision;
use vcm_scheduler::{Scheduler, StopFlag};
use vcm_traversal::Traversal;

use crate::error::RenderError;
use crate::film::Film;

/// A progressive renderer: frame after frame, each adding [`samples_per_frame`] samples per
/// pixel (and, for algorithms with light tracing, splats) to a [`Film`].
///
/// [`samples_per_frame`]: Integrator::samples_per_frame
pub trait Integrator: Send {
    /// Renders samples `first_sample`, `first_sample + 1`, … (`samples_per_frame` of them,
    /// for every pixel) into `film`. Sample `s` is iteration `s` of algorithms that iterate
    /// (the merge radius shrinks with it); a render that covers samples 0 … n − 1 adds the
    /// same film whatever frames they came in.
    ///
    /// The result depends only on the scene, the settings and the samples, not on the number
    /// of threads or the schedule. Panics if `film` does not have the integrator's image size.
    ///
    /// When the [stop flag](Integrator::set_stop) is raised during the frame, the frame ends
    /// early and is dropped whole: the film is left as it was, and the stats say
    /// [`interrupted`](FrameStats::interrupted).
    fn render_frame(&mut self, film: &mut Film, first_sample: u32) -> FrameStats;

    /// Ends frames early once `stop` is raised (checked between tiles and between passes,
    /// so within a fraction of a second on any frame size). No flag is raised by default.
    fn set_stop(&mut self, stop: StopFlag);

    /// (width, height) of the image in pixels: the size of the films it renders into.
    fn image_size(&self) -> (u32, u32);

    /// Renders with `schedule` from the next frame on. Integrators that only run
    /// [`Schedule::ONE_BATCH`] reject any other with [`RenderError::InvalidSetting`].
    fn set_schedule(&mut self, schedule: Schedule) -> Result<(), RenderError> {
        if schedule == Schedule::ONE_BATCH {
            Ok(())
        } else {
            Err(RenderError::InvalidSetting(
                "this algorithm runs only one batch per pass and one sample per pixel per \
                 frame so far"
                    .into(),
            ))
        }
    }

    /// Samples per pixel each frame adds to the film.
    fn samples_per_frame(&self) -> u32 {
        1
    }

    /// The integrator's parts and why each runs or is left out for its scene (what
    /// `vcm render --explain` prints besides the scene's [`vcm_scene::ShadingPlan`]).
    fn decisions(&self) -> Vec<Decision>;

    /// Why the integrator can render no more frames, once the device it renders on has
    /// failed: the frame that met the failure was dropped whole (its stats say
    /// [`interrupted`](FrameStats::interrupted)), as a stopped one is. `None` for integrators
    /// that cannot fail, the default.
    fn failure(&self) -> Option<String> {
        None
    }
}

/// How a frame's paths are scheduled: the grouping into batches and the samples per pixel
/// each frame renders. Neither changes the image a seed gives, only how fast it comes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// How paths are grouped into batches.
    pub scheduler: Scheduler,
    /// Samples per pixel per frame (at least 1).
    pub samples_per_frame: u32,
}

impl Schedule {
    /// One batch of all active paths per pass, one sample per pixel per frame: what every
    /// integrator runs.
    pub const ONE_BATCH: Schedule = Schedule {
        scheduler: Scheduler::None,
        samples_per_frame: 1,
    };

    /// The schedule, or why it cannot run.
    pub fn validated(self) -> Result<Schedule, RenderError> {
        if self.samples_per_frame == 0 {
            return Err(RenderError::InvalidSetting(
                "samples per frame must be at least 1".into(),
            ));
        }
        match self.scheduler {
            Scheduler::Tile { size: 0, .. } | Scheduler::Queue { size: 0, .. } => Err(
                RenderError::InvalidSetting("the tile size must be at least 1".into()),
            ),
            Scheduler::Queue { queues: 0, .. } => Err(RenderError::InvalidSetting(
                "the queue scheduler needs at least 1 queue".into(),
            )),
            Scheduler::Tile { merge_below, .. } | Scheduler::Queue { merge_below, .. }
                if !(0.0..=1.0).contains(&merge_below) =>
            {
                Err(RenderError::InvalidSetting(format!(
                    "the tile merge threshold must be a fraction from 0 to 1 (asked for \
                     {merge_below})"
                )))
            }
            _ => Ok(self),
        }
    }
}

impl Default for Schedule {
    /// The default [`Scheduler`] (tiles), one sample per pixel per frame.
    fn default() -> Self {
        Self {
            scheduler: Scheduler::default(),
            samples_per_frame: 1,
        }
    }
}

/// Work done by one [`Integrator::render_frame`] call.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// Rays from the camera (one per pixel).
    pub camera_rays: u64,
    /// Rays that continue a camera path after a BSDF sample.
    pub continuation_rays: u64,
    /// Segments of light paths (emitted rays and their continuations).
    pub light_rays: u64,
    /// Occlusion rays: light samples, connections between vertices, and light vertices
    /// connected to the camera.
    pub shadow_rays: u64,
    /// Light vertices stored in the light vertex cache.
    pub light_vertices: u64,
    /// Light vertices discarded because the cache was full.
    pub discarded_light_vertices: u64,
    /// Wall-clock time in closest-hit and occlusion queries (with [`Scheduler::Queue`]: the
    /// time a traversal job was in flight, which overlaps shading).
    pub traversal_time: Duration,
    /// Wall-clock time building the hash grid over the light vertices.
    pub grid_build_time: Duration,
    /// Wall-clock time in everything else: ray generation, shading, connections, merging,
    /// queue compaction and accumulation.
    pub shading_time: Duration,
    /// Time the GPU spent running the frame's shading kernels, from timestamps around their
    /// passes (with GPU shading on a device that has timestamps; zero elsewhere): part of
    /// `shading_time`, which also holds the submissions, waits and read-backs.
    pub device_time: Duration,
    /// High-water mark of the scheduler's queues (paths in flight and their ray buffers) in
    /// bytes, over the frame's passes ([`vcm_scheduler::SchedulerStats::queue_memory`]).
    pub queue_memory: usize,
    /// The frame was cut short by a stop request and dropped: it added nothing to the film.
    pub interrupted: bool,
}

impl FrameStats {
    /// What a frame that a stop request cut short reports.
    pub const INTERRUPTED: FrameStats = FrameStats {
        camera_rays: 0,
        continuation_rays: 0,
        light_rays: 0,
        shadow_rays: 0,
        light_vertices: 0,
        discarded_light_vertices: 0,
        traversal_time: Duration::ZERO,
        grid_build_time: Duration::ZERO,
        shading_time: Duration::ZERO,
        device_time: Duration::ZERO,
        queue_memory: 0,
        interrupted: true,
    };

    /// Adds the counts and times of `other`.
    pub fn accumulate(&mut self, other: &FrameStats) {
        self.camera_rays += other.camera_rays;
        self.continuation_rays += other.continuation_rays;
        self.light_rays += other.light_rays;
        self.shadow_rays += other.shadow_rays;
        self.light_vertices += other.light_vertices;
        self.discarded_light_vertices += other.discarded_light_vertices;
        self.traversal_time += other.traversal_time;
        self.grid_build_time += other.grid_build_time;
        self.shading_time += other.shading_time;
        self.device_time += other.device_time;
        self.queue_memory = self.queue_memory.max(other.queue_memory);
    }

    /// All rays traced.
    pub fn rays(&self) -> u64 {
        self.camera_rays + self.continuation_rays + self.light_rays + self.shadow_rays
    }
}

/// Checks that a `width` × `height` image has pixels and that a 32-bit index reaches them all.
pub fn check_image_size(width: u32, height: u32) -> Result<(), RenderError> {
    if width == 0 || height == 0 {
        return Err(RenderError::EmptyImage { width, height });
    }
    if u64::from(width) * u64::from(height) > u64::from(u32::MAX) {
        return Err(RenderError::ImageTooLarge { width, height });
    }
    Ok(())
}

/// Whether a frame traced with `traversal` must be dropped whole: a stop request cut it
/// short, or the traversal failed during it (its rays since then all missed).
pub(crate) fn frame_cut_short(stop: &StopFlag, traversal: &dyn Traversal) -> bool {
    stop.is_raised() || traversal.failure().is_some()
}

/// [`Integrator::failure`] of an integrator that shades on the CPU and traces with
/// `traversal`: the traversal's failure.
pub(crate) fn traversal_failure(traversal: &dyn Traversal) -> Option<String> {
    traversal
        .failure()
        .map(|failure| format!("ray traversal failed: {failure}"))
}
