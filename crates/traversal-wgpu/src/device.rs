//! Headless device selection: the best hardware adapter when there is one, else a software
//! one (Mesa lavapipe), with the adapter's own limits rather than WebGPU's defaults.

use std::sync::{Arc, Mutex, mpsc};

use wgpu::util::DeviceExt;

use crate::error::GpuError;

/// A wgpu device and queue with the adapter they came from.
#[derive(Debug)]
pub struct GpuDevice {
    /// The logical device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter's name, driver and kind.
    pub info: wgpu::AdapterInfo,
    /// The first error the device reported outside any call's result (a validation or
    /// out-of-memory error, or the device's loss), kept so that later calls fail with it.
    failure: Arc<Mutex<Option<String>>>,
}

impl GpuDevice {
    /// Opens the preferred adapter among those of the Vulkan, Metal and DX12 backends
    /// (`WGPU_BACKEND` narrows them): a discrete GPU, else an integrated one, else a virtual
    /// one, else a CPU implementation. Needs no window or display.
    ///
    /// Requests the adapter's own limits: lavapipe, for one, allows storage bindings far
    /// above the 128 MiB default, which a million-triangle scene needs.
    pub fn open() -> Result<Self, GpuError> {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        descriptor.backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY);
        let instance = wgpu::Instance::new(descriptor);
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        let adapter = adapters
            .into_iter()
            .filter(|adapter| adapter.get_downlevel_capabilities().is_webgpu_compliant())
            .min_by_key(|adapter| preference(adapter.get_info().device_type))
            .ok_or(GpuError::NoAdapter)?;
        let info = adapter.get_info();
        let descriptor = wgpu::DeviceDescriptor {
            label: Some("vcm traversal"),
            // Timestamps only time kernels for the benchmarks; traversal works without them.
            required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
            required_limits: adapter.limits(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        };
        let (device, queue) =
            pollster::block_on(adapter.request_device(&descriptor)).map_err(|error| {
                GpuError::RequestDevice {
                    adapter: info.name.clone(),
                    reason: error.to_string(),
                }
            })?;
        let failure = Arc::new(Mutex::new(None));
        keep_failures(&device, &failure);
        Ok(Self {
            device,
            queue,
            info,
            failure,
        })
    }

    /// The first error the device reported outside a call's result, or its loss, if any
    /// (wgpu reports those to a handler whose default panics).
    pub fn failure(&self) -> Option<String> {
        self.failure.lock().ok().and_then(|failure| failure.clone())
    }

    /// Records `message` as the device's failure, unless one is kept already (a read-back
    /// that failed: what [`GpuDevice::failure`] then returns).
    pub fn fail(&self, message: String) {
        keep(&self.failure, message);
    }

    /// A one-line description: adapter name, kind and backend.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?}, driver {} {})",
            self.info.name,
            self.info.device_type,
            self.info.backend,
            self.info.driver,
            self.info.driver_info
        )
    }

    /// Whether the adapter is a CPU implementation such as lavapipe. llvmpipe, lavapipe's
    /// compiler, stops every loop of a kernel invocation after 65,535 iterations in all
    /// (`LP_MAX_TGSI_LOOP_ITERATIONS`), so there a ray that needs more node visits and
    /// triangle tests than that (tens of thousands of coincident triangles) is cut short;
    /// real scenes need a few hundred at most.
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Whether compute passes can be timed with GPU timestamp queries.
    pub fn has_timestamps(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// Uploads `bytes` as a read-only storage buffer (at least 4 bytes: empty bindings are
    /// invalid), checking the device's binding limit.
    pub fn storage_buffer(
        &self,
        label: &'static str,
        bytes: &[u8],
    ) -> Result<wgpu::Buffer, GpuError> {
        let limit = self.max_binding_bytes();
        if bytes.len() as u64 > limit {
            return Err(GpuError::SceneTooLarge {
                buffer: label,
                bytes: bytes.len() as u64,
                limit,
                adapter: self.info.name.clone(),
            });
        }
        let contents = if bytes.is_empty() { &[0; 4][..] } else { bytes };
        Ok(self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            }))
    }

    /// Submits `encoder`, whose commands copy results into the first `bytes` of `buffer`
    /// (`MAP_READ`), waits for them, and returns what `read` makes of those bytes; the buffer
    /// is unmapped again. Fails, saying why, where the device is lost, reported an error
    /// since it opened ([`GpuDevice::failure`]) or the mapping fails.
    pub fn read_back<T>(
        &self,
        encoder: wgpu::CommandEncoder,
        (buffer, bytes): (&wgpu::Buffer, u64),
        read: impl FnOnce(&[u8]) -> T,
    ) -> Result<T, String> {
        let submission = self.queue.submit([encoder.finish()]);
        let slice = buffer.slice(..bytes);
        let (sender, mapped) = mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |result| {
            // The receiver waits below.
            let _ = sender.send(result);
        });
        self.wait(submission)?;
        let result = read_mapped(slice, &mapped, read)?;
        buffer.unmap();
        Ok(result)
    }

    /// Waits until the commands of `submission` are done. Fails, saying why, where the
    /// device is lost or reported an error since it opened ([`GpuDevice::failure`]).
    pub fn wait(&self, submission: wgpu::SubmissionIndex) -> Result<(), String> {
        let poll = wgpu::PollType::Wait {
            submission_index: Some(submission),
            timeout: None,
        };
        self.device
            .poll(poll)
            .map_err(|e| format!("the GPU device was lost: {e}"))?;
        self.failure().map_or(Ok(()), Err)
    }

    /// The largest storage buffer binding the device accepts, in bytes.
    pub fn max_binding_bytes(&self) -> u64 {
        let limits = self.device.limits();
        limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
    }
}

/// What `read` makes of the bytes of `slice`, once the mapping that `mapped` reports on (the
/// channel its `map_async` callback sends to) is done, after [`GpuDevice::wait`]. Fails,
/// saying why, where the mapping fails; the caller unmaps the buffer.
pub(crate) fn read_mapped<T>(
    slice: wgpu::BufferSlice<'_>,
    mapped: &mpsc::Receiver<Result<(), wgpu::BufferAsyncError>>,
    read: impl FnOnce(&[u8]) -> T,
) -> Result<T, String> {
    mapped
        .recv()
        .map_err(|_| "wgpu dropped a buffer mapping callback".to_owned())?
        .map_err(|e| format!("mapping a read-back buffer failed: {e}"))?;
    let view = slice
        .get_mapped_range()
        .map_err(|e| format!("reading a mapped buffer failed: {e}"))?;
    Ok(read(&view))
}

/// Set to `1` (as `.ci/run` does) to make a missing adapter fail the tests that need one
/// instead of skipping them.
pub const REQUIRE_GPU: &str = "VCM_REQUIRE_GPU";

/// For test suites: the preferred adapter ([`GpuDevice::open`]), or `None` with a note on
/// stderr when there is none; with [`REQUIRE_GPU`] set to `1` a missing adapter panics.
pub fn device_or_skip() -> Option<GpuDevice> {
    match GpuDevice::open() {
        Ok(gpu) => Some(gpu),
        Err(error) if std::env::var(REQUIRE_GPU).is_ok_and(|v| v == "1") => {
            panic!("{REQUIRE_GPU}=1 but no GPU adapter: {error}")
        }
        Err(error) => {
            eprintln!("skipping GPU test ({error}); set {REQUIRE_GPU}=1 to make this an error");
            None
        }
    }
}

/// Keeps `message` in `failure` unless a failure is kept already.
fn keep(failure: &Mutex<Option<String>>, message: String) {
    if let Ok(mut failure) = failure.lock() {
        failure.get_or_insert(message);
    }
}

/// Keeps in `failure` the first error `device` reports outside a call's result and its loss,
/// instead of wgpu's default, which panics.
fn keep_failures(device: &wgpu::Device, failure: &Arc<Mutex<Option<String>>>) {
    let slot = Arc::clone(failure);
    device.on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
        keep(&slot, format!("the GPU reported an error: {error}"));
    }));
    let slot = Arc::clone(failure);
    device.set_device_lost_callback(move |reason, message| {
        keep(
            &slot,
            format!("the GPU device was lost ({reason:?}): {message}"),
        );
    });
}

/// Lower is preferred: real GPUs first, software rasterizers last.
fn preference(kind: wgpu::DeviceType) -> u8 {
    match kind {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4-byte buffer to read back into.
    fn readback(gpu: &GpuDevice) -> wgpu::Buffer {
        gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: 4,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    #[test]
    fn an_error_of_the_device_fails_later_read_backs_instead_of_panicking() {
        let Some(gpu) = device_or_skip() else {
            return;
        };
        assert_eq!(gpu.failure(), None);
        let buffer = readback(&gpu);
        let encoder = gpu.device.create_command_encoder(&Default::default());
        assert_eq!(gpu.read_back(encoder, (&buffer, 4), <[u8]>::len), Ok(4));
        // Larger than the device allows: an error no call returns.
        let too_large = gpu.device.limits().max_buffer_size.saturating_add(4) & !3;
        let _ = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("too large"),
            size: too_large,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let failure = gpu.failure().expect("the error is kept");
        assert!(
            failure.starts_with("the GPU reported an error"),
            "{failure}"
        );
        let encoder = gpu.device.create_command_encoder(&Default::default());
        let result = gpu.read_back(encoder, (&buffer, 4), <[u8]>::len);
        assert_eq!(result, Err(failure));
    }

    #[test]
    fn a_destroyed_device_fails_read_backs_instead_of_panicking() {
        let Some(gpu) = device_or_skip() else {
            return;
        };
        let buffer = readback(&gpu);
        gpu.device.destroy();
        let encoder = gpu.device.create_command_encoder(&Default::default());
        let result = gpu.read_back(encoder, (&buffer, 4), <[u8]>::len);
        assert!(result.is_err(), "{result:?}");
    }
}
