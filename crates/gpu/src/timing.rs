//! [`PassTimer`]: the time the GPU spends in compute passes, from timestamps the device
//! writes at the beginning and end of each pass, where it has them.

use std::cell::Cell;
use std::time::Duration;

use vcm_traversal_wgpu::GpuDevice;

/// Passes timed between two collections (a query set of twice as many timestamps).
const PASSES: u32 = 64;

/// Timestamps around the compute passes of the submissions between two [`collect`]s, and
/// the time of the passes collected so far.
///
/// [`collect`]: PassTimer::collect
pub(crate) struct PassTimer {
    stamps: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// Passes given timestamps since the last resolve.
    passes: Cell<u32>,
    /// Passes resolved into `resolved` and copied to `readback`, not collected yet.
    resolved_passes: Cell<u32>,
    /// The time of the passes collected.
    total: Cell<Duration>,
}

impl PassTimer {
    /// A timer on `gpu`, `None` where the device writes no timestamps.
    pub fn new(gpu: &GpuDevice) -> Option<PassTimer> {
        if !gpu.has_timestamps() {
            return None;
        }
        let device = &gpu.device;
        let stamps = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2 * PASSES,
        });
        let bytes = u64::from(2 * PASSES) * size_of::<u64>() as u64;
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        Some(PassTimer {
            stamps,
            resolved: buffer("resolved timestamps", U::QUERY_RESOLVE | U::COPY_SRC),
            readback: buffer("timestamp read-back", U::MAP_READ | U::COPY_DST),
            passes: Cell::new(0),
            resolved_passes: Cell::new(0),
            total: Cell::new(Duration::ZERO),
        })
    }

    /// The timestamp writes of the next pass, `None` once the query set is full (that pass
    /// goes untimed).
    pub fn writes(&self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let pass = self.passes.get();
        if pass == PASSES {
            return None;
        }
        self.passes.set(pass + 1);
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &self.stamps,
            beginning_of_pass_write_index: Some(2 * pass),
            end_of_pass_write_index: Some(2 * pass + 1),
        })
    }

    /// Records on `encoder`, after its passes, the copy of their timestamps to where
    /// [`collect`](Self::collect) reads them.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let passes = self.passes.replace(0);
        if passes == 0 {
            return;
        }
        let bytes = u64::from(2 * passes) * size_of::<u64>() as u64;
        encoder.resolve_query_set(&self.stamps, 0..2 * passes, &self.resolved, 0);
        encoder.copy_buffer_to_buffer(&self.resolved, 0, &self.readback, 0, bytes);
        self.resolved_passes.set(passes);
    }

    /// Adds the time of the passes resolved by a submitted encoder to the total, once the
    /// device is done with them.
    pub fn collect(&self, gpu: &GpuDevice) -> Result<(), String> {
        let passes = self.resolved_passes.replace(0);
        if passes == 0 {
            return Ok(());
        }
        let bytes = u64::from(2 * passes) * size_of::<u64>() as u64;
        let encoder = gpu.device.create_command_encoder(&Default::default());
        let ticks: Vec<u64> = gpu.read_back(
            encoder,
            (&self.readback, bytes),
            bytemuck::pod_collect_to_vec,
        )?;
        let period_ns = f64::from(gpu.queue.get_timestamp_period());
        let ns: f64 = ticks
            .chunks_exact(2)
            .map(|pair| pair[1].saturating_sub(pair[0]) as f64 * period_ns)
            .sum();
        self.total
            .set(self.total.get() + Duration::from_nanos(ns as u64));
        Ok(())
    }

    /// The time of the passes collected since the last call.
    pub fn take(&self) -> Duration {
        self.total.replace(Duration::ZERO)
    }
}
