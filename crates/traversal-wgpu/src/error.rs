//! Errors of the GPU backend: no usable adapter, a device request the adapter refused, or a
//! scene that does not fit the device.

use vcm_traversal::BuildError;

/// What to tell a user who has no adapter at all.
pub const NO_ADAPTER_HELP: &str = "no GPU adapter found: install a Vulkan driver for your GPU, \
or Mesa's software rasterizer lavapipe (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers`), \
or use `--backend cpu`";

/// Why the GPU backend could not be created.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// wgpu found no adapter (no Vulkan, Metal or DX12 driver).
    #[error("{NO_ADAPTER_HELP}")]
    NoAdapter,
    /// The adapter refused to create a device with the requested limits.
    #[error("the GPU adapter {adapter} could not create a device: {reason}")]
    RequestDevice {
        /// The adapter's name.
        adapter: String,
        /// wgpu's message.
        reason: String,
    },
    /// The triangles are invalid (see [`BuildError`]).
    #[error(transparent)]
    Build(#[from] BuildError),
    /// A scene buffer is larger than the device allows in one storage binding.
    #[error(
        "the scene's {buffer} need {bytes} bytes, more than the GPU adapter {adapter} allows in \
         one storage buffer ({limit} bytes)"
    )]
    SceneTooLarge {
        /// Which buffer (nodes, triangles, ids).
        buffer: &'static str,
        /// Its size.
        bytes: u64,
        /// The device's storage binding limit.
        limit: u64,
        /// The adapter's name.
        adapter: String,
    },
}
