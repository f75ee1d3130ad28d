//! [`PassTimer`]: the time the GPU spends in compute passes, from timestamps the device
//! writes at the beginning and end of each pass, where it has them.

use std::cell::Cell;
use std::time::Duration;

use crate::GpuDevice;

/// Timestamps around the compute passes of the submissions between two
/// [`collect`](PassTimer::collect)s.
pub struct PassTimer {
    stamps: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// Passes the query set has room for.
    capacity: u32,
    /// Passes given timestamps since the last resolve.
    passes: Cell<u32>,
    /// Passes resolved into `resolved` and copied to `readback`, not collected yet.
    resolved_passes: Cell<u32>,
}

impl PassTimer {
    /// A timer of up to `passes` passes between collections on `gpu` (at most half of
    /// [`wgpu::QUERY_SET_MAX_QUERIES`]), `None` where the device writes no timestamps.
    pub fn new(gpu: &GpuDevice, passes: u32) -> Option<PassTimer> {
        if !gpu.has_timestamps() || passes == 0 {
            return None;
        }
        let capacity = passes.min(wgpu::QUERY_SET_MAX_QUERIES / 2);
        let device = &gpu.device;
        let stamps = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2 * capacity,
        });
        let bytes = u64::from(2 * capacity) * size_of::<u64>() as u64;
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
            capacity,
            passes: Cell::new(0),
            resolved_passes: Cell::new(0),
        })
    }

    /// The timestamp writes of the next pass, `None` once the query set is full (that pass
    /// goes untimed).
    pub fn writes(&self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let pass = self.passes.get();
        if pass == self.capacity {
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

    /// The time of each pass resolved by a submitted encoder, once the device is done with
    /// them.
    pub fn collect(&self, gpu: &GpuDevice) -> Result<Vec<Duration>, String> {
        let passes = self.resolved_passes.replace(0);
        if passes == 0 {
            return Ok(Vec::new());
        }
        let bytes = u64::from(2 * passes) * size_of::<u64>() as u64;
        let encoder = gpu.device.create_command_encoder(&Default::default());
        let ticks: Vec<u64> = gpu.read_back(
            encoder,
            (&self.readback, bytes),
            bytemuck::pod_collect_to_vec,
        )?;
        let period_ns = f64::from(gpu.queue.get_timestamp_period());
        let time = |pair: &[u64]| pair[1].saturating_sub(pair[0]) as f64 * period_ns;
        Ok(ticks
            .chunks_exact(2)
            .map(|pair| Duration::from_nanos(time(pair) as u64))
            .collect())
    }
}
