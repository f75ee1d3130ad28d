//! [`IndexBuilder`]: the light vertex index built on the device (`index.wgsl`) from the
//! vertices each light path counted: each path's first vertex in its iteration, and each
//! iteration's part of the cache, in the CPU cache's order.

use bytemuck::{Pod, Zeroable};
use vcm_traversal_wgpu::GpuDevice;

use crate::compute::{Kernels, record};
use crate::shader::{CACHE_WGSL, INDEX_WGSL};

/// `IndexParams` of `index.wgsl`.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct IndexParams {
    paths: u32,
    samples: u32,
    unused: [u32; 2],
}

/// The index-building kernels.
pub(crate) struct IndexBuilder {
    kernels: Kernels,
    params: wgpu::Buffer,
}

impl IndexBuilder {
    /// The kernels compiled on `gpu`.
    pub fn new(gpu: &GpuDevice) -> IndexBuilder {
        let source = format!("{CACHE_WGSL}\n{INDEX_WGSL}");
        let entries = ["index_scan", "index_starts"];
        let kernels = Kernels::new(gpu, "light vertex index", source, &entries);
        let params = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("index parameters"),
            size: size_of::<IndexParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        IndexBuilder { kernels, params }
    }

    /// Records, on `encoder`, the index of a frame of `paths` light paths per iteration and
    /// `samples` iterations over the counts in `index`, with each iteration's part in
    /// `iterations`.
    pub fn record(
        &self,
        gpu: &GpuDevice,
        encoder: &mut wgpu::CommandEncoder,
        (index, iterations): (&wgpu::Buffer, &wgpu::Buffer),
        (paths, samples): (u32, u32),
    ) {
        let params = IndexParams {
            paths,
            samples,
            unused: [0; 2],
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let group = self.kernels.group(gpu, &[index, iterations, &self.params]);
        let [scan, starts] = [0, 1].map(|k| &self.kernels.pipelines[k]);
        // A workgroup per iteration, then one invocation.
        record(encoder, (scan, &group), (samples, 1));
        record(encoder, (starts, &group), (1, 1));
    }
}
