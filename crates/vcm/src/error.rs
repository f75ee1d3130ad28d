//! Errors reported when an integrator is set up.

use thiserror::Error;

use crate::memory::MemoryShortfall;

/// Settings an integrator cannot render with.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum RenderError {
    /// The image has no pixels.
    #[error("the image size {width}×{height} has no pixels")]
    EmptyImage {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
    },
    /// The image has more pixels than a path's 32-bit pixel index can address.
    #[error("the image size {width}×{height} has more than 2³² − 1 pixels")]
    ImageTooLarge {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
    },
    /// A setting outside its valid range.
    #[error("invalid setting: {0}")]
    InvalidSetting(String),
    /// The render's largest buffers would need more memory than the process may allocate.
    #[error(transparent)]
    OutOfMemory(#[from] MemoryShortfall),
    /// The device the integrator renders on failed ([`Integrator::failure`](crate::Integrator::failure)).
    #[error("{0}")]
    DeviceFailed(String),
}
