//! Why a GPU render cannot start.

use vcm::RenderError;
use vcm_traversal_wgpu::GpuError;

/// Why a [`GpuPathTracer`](crate::GpuPathTracer) cannot render a scene.
#[derive(Debug, thiserror::Error)]
pub enum GpuRenderError {
    /// The scene (or the hierarchy given) is one the GPU kernel cannot shade.
    #[error("the GPU path tracer cannot shade this scene: {0} (render it with the CPU shading)")]
    Unsupported(String),
    /// GPU shading was asked of what it does not render: another algorithm than path
    /// tracing, or a traversal backend other than the GPU's.
    #[error("shading on the GPU {0}")]
    Refused(String),
    /// The settings are invalid (image size, memory).
    #[error(transparent)]
    Render(#[from] RenderError),
    /// The device refused a buffer (too large for its bindings).
    #[error(transparent)]
    Gpu(#[from] GpuError),
}
