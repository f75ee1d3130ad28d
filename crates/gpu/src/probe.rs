//! For tests: runs a probe kernel, which answers a batch of queries from its inputs — each
//! input a storage buffer bound in order from binding 0, the answers one `T` per query in the
//! binding after them — and reads the answers back.

use bytemuck::Pod;
use vcm_traversal_wgpu::GpuDevice;
use wgpu::util::DeviceExt;

/// Invocations per workgroup of a probe's entry point.
const PROBE_WORKGROUP: u32 = 64;

/// The answers of `entry` in WGSL `source` to `queries` queries over `inputs`.
pub(crate) fn run_probe<T: Pod>(
    gpu: &GpuDevice,
    (source, entry): (String, &str),
    inputs: &[&[u8]],
    queries: usize,
) -> Vec<T> {
    let device = &gpu.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(entry),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: None,
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    });
    let output_bytes = (queries * size_of::<T>()) as u64;
    let buffer = |usage| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(entry),
            size: output_bytes,
            usage,
            mapped_at_creation: false,
        })
    };
    use wgpu::BufferUsages as U;
    let mut buffers: Vec<wgpu::Buffer> = inputs
        .iter()
        .map(|bytes| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(entry),
                contents: bytes,
                usage: U::STORAGE,
            })
        })
        .collect();
    buffers.push(buffer(U::STORAGE | U::COPY_SRC));
    let readback = buffer(U::MAP_READ | U::COPY_DST);
    let entries: Vec<_> = (0u32..)
        .zip(&buffers)
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(entry),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups((queries as u32).div_ceil(PROBE_WORKGROUP), 1, 1);
    }
    let answers = buffers.last().expect("the answers' buffer");
    encoder.copy_buffer_to_buffer(answers, 0, &readback, 0, output_bytes);
    gpu.read_back(
        encoder,
        (&readback, output_bytes),
        bytemuck::pod_collect_to_vec,
    )
    .expect("the probe's answers come back")
}
