//! GPU ray traversal for vcm-rs: the [`Traversal`](vcm_traversal::Traversal) trait on WGSL
//! compute shaders dispatched through wgpu.
//!
//! The hierarchy is built on the CPU (obvhs's PLOC and reinsertion, as for the CPU backend),
//! laid out for the GPU ([`layout`]) and uploaded once; kernels come from the
//! crate's `shaders/*.wgsl`.

#![warn(missing_docs)]

mod alpha;
mod backend;
mod device;
mod error;
pub mod layout;
pub mod shader;
mod slot;
mod timing;

pub use alpha::{AlphaMasks, AlphaTexture, Filter, MaskedTriangle, Wrap};
pub use backend::{GpuBvh, GpuBvhOptions};
pub use device::{GpuDevice, REQUIRE_GPU, device_or_skip};
pub use error::{GpuError, NO_ADAPTER_HELP};
pub use layout::NodeLayout;
pub use slot::dispatch_shape;
pub use timing::PassTimer;
