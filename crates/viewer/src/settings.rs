//! What the user picks for a render besides the camera: algorithm, backend, shading,
//! integrator options and the schedule (scheduler, tile size, samples per pixel per frame). Any change restarts the accumulation (see [`crate::session`]).

use vcm_rs::integrators::{AlgorithmOption, IntegratorOptions};
use vcm_rs::render_loop::ScheduleOptions;
use vcm_rs::{Backend, Shading};

/// The render settings the viewer's controls edit.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// The light transport algorithm, or `auto`: the one pilot renders find the most
    /// efficient for the scene (`vcm_rs::integrators::choice`).
    pub algorithm: AlgorithmOption,
    /// The ray traversal backend.
    pub backend: Backend,
    /// Where paths are shaded (on the GPU: with the GPU backend only).
    pub shading: Shading,
    /// Seed, maximum path length, connections, merge radius and its reduction.
    pub integrator: IntegratorOptions,
    /// Scheduler, tile size and samples per pixel per frame (the displayed image is updated
    /// after every frame); options left out take the backend's defaults.
    pub schedule: ScheduleOptions,
}
