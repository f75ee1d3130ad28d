//! Ray traversal for vcm-rs: batched closest-hit and occlusion queries against triangles.
//!
//! - [`RayBatch`] / [`HitBatch`]: structure-of-arrays buffers reused across calls.
//! - [`Traversal`]: the backend interface, synchronous or via [`Traversal::submit`] and
//!   [`PendingTraversal::wait`] for backends that overlap work.
//! - [`CpuBvh`]: the CPU backend (an obvhs-built 8-wide BVH with exact child boxes, watertight
//!   triangle test, rayon).
//!
//! Backends are built from plain triangles (`&[[Vec3; 3]]`, index = primitive id) and an
//! optional [`AlphaTest`], independent of any scene representation.

#![warn(missing_docs)]

mod alpha;
mod batch;
pub mod build;
pub mod contract;
mod cpu;
mod error;
mod traversal;

pub use alpha::AlphaTest;
pub use batch::{HitBatch, NO_HIT, RayBatch};
pub use build::{BEST_BUILD_UP_TO, BuildPreset};
pub use cpu::{CpuBvh, CpuBvhOptions, CpuKernel, INTERLEAVE_ABOVE_BYTES, Interleave};
pub use error::BuildError;
pub use traversal::{CompletedTraversal, PendingTraversal, Traversal, TraversalJob};
