//! The render loop, the one owner of frames: the schedule of each frame (which scheduler
//! groups its paths into batches, [`ScheduleOptions`]), how many samples per pixel it renders
//! (fixed or paced to a target duration, [`Frames`]), and frames until a sample or time
//! budget is spent or a stop is requested ([`render`]).
//!
//! Integrators only supply their steps ([`vcm::Integrator`]: take a schedule, render a frame
//! of global samples); this module decides which frames they render and with what schedule.
//! It depends on [`crate::integrators`] (to build the integrator a render starts with,
//! [`Frames::integrator`]), never the other way round. Shared by `vcm render`,
//! `vcm convergence`, `vcm experiment`, the viewer and the Python package.

mod frames;
mod pacer;
mod progressive;
mod schedule;

pub use frames::{FrameCounts, Frames};
pub use pacer::Remaining;
pub use progressive::{Budget, FrameDone, Rendered, render};
pub use schedule::{
    FrameSizes, GPU_TILE_SAMPLES, ScheduleOptions, SchedulerKind, preferred_frame_sizes,
    preferred_scheduler,
};
