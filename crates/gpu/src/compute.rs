//! [`Kernels`]: a module of helper kernels (no scene) over one explicit bind group of buffers,
//! for what the frames build on the device (the light vertex index, the hash grids).

use vcm_traversal_wgpu::GpuDevice;
use vcm_traversal_wgpu::shader::buffer_layout;

use crate::kernel::bind_entries;

/// Compute pipelines of one module, sharing bind group 0's layout: storage buffers (read-only
/// where asked) and a uniform buffer last.
pub(crate) struct Kernels {
    layout: wgpu::BindGroupLayout,
    pub pipelines: Vec<wgpu::ComputePipeline>,
}

impl Kernels {
    /// The kernels `entries` of `source`, whose group 0 binds one storage buffer per entry of
    /// `read_only` (read-only where true), then a uniform buffer.
    pub fn new(
        gpu: &GpuDevice,
        label: &str,
        source: String,
        entries: &[&str],
        read_only: &[bool],
    ) -> Kernels {
        let device = &gpu.device;
        let mut bindings: Vec<_> = (0u32..)
            .zip(read_only)
            .map(|(binding, &read_only)| {
                buffer_layout(binding, wgpu::BufferBindingType::Storage { read_only })
            })
            .collect();
        bindings.push(buffer_layout(
            read_only.len() as u32,
            wgpu::BufferBindingType::Uniform,
        ));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &bindings,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let pipelines = entries
            .iter()
            .map(|entry| {
                device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                })
            })
            .collect();
        Kernels { layout, pipelines }
    }

    /// Bind group 0 of `buffers`, in binding order (the uniform last).
    pub fn group(&self, gpu: &GpuDevice, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
        let buffers = (0u32..).zip(buffers.iter().copied());
        bind_entries(&gpu.device, &self.layout, buffers)
    }
}

/// Records pipeline `pipeline` over `group` in `(x, y)` workgroups on `encoder`.
pub(crate) fn record(
    encoder: &mut wgpu::CommandEncoder,
    (pipeline, group): (&wgpu::ComputePipeline, &wgpu::BindGroup),
    (x, y): (u32, u32),
) {
    let mut pass = encoder.begin_compute_pass(&Default::default());
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(x, y, 1);
}
