//! What the user picks for a render besides the camera: algorithm, backend, integrator options
//! and samples per frame. Any change restarts the accumulation (see [`crate::session`]).

use vcm_rs::Backend;
use vcm_rs::integrators::{Algorithm, IntegratorOptions};

/// Every algorithm, in the order the algorithm menu lists them.
pub const ALGORITHMS: [Algorithm; 6] = [
    Algorithm::Pt,
    Algorithm::Lt,
    Algorithm::Bpt,
    Algorithm::Ppm,
    Algorithm::Bpm,
    Algorithm::Vcm,
];

/// The render settings the viewer's controls edit.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// The light transport algorithm.
    pub algorithm: Algorithm,
    /// The ray traversal backend.
    pub backend: Backend,
    /// Seed, maximum path length, connections, merge radius and its reduction.
    pub integrator: IntegratorOptions,
    /// Frames (one sample per pixel each) rendered between two updates of the displayed
    /// image (≥ 1).
    pub samples_per_frame: u32,
}
