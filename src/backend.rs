//! The ray traversal backends a render can run on, chosen at run time: the one place where a
//! backend is named and built, shared by `vcm render` and the viewer.

use std::sync::Arc;

use vcm_scene::Scene;
use vcm_traversal::{BuildError, Traversal};

/// Ray traversal backends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Backend {
    /// obvhs 8-wide BVH on rayon threads.
    Cpu,
    // The GPU backend (crates/traversal-wgpu) is added here and in `Backend::traversal`.
}

impl Backend {
    /// Every backend, in the order user interfaces list them.
    pub const ALL: &'static [Backend] = &[Backend::Cpu];

    /// The lower-case name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
        }
    }

    /// Builds this backend's traversal over `scene` (its BVH, once per scene).
    pub fn traversal(self, scene: &Arc<Scene>) -> Result<Arc<dyn Traversal>, BuildError> {
        match self {
            Backend::Cpu => Ok(Arc::new(crate::cpu_traversal(scene)?)),
        }
    }
}
