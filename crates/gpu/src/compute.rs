//! [`Kernels`]: a module of helper kernels (no scene) over one bind group of buffers, for
//! what the frames build on the device (the light vertex index, the hash grids); and
//! [`DeclaredLayout`], the pipeline layout of every buffer a module declares, which lets the
//! kernels of one module share bind groups.

use vcm_traversal_wgpu::GpuDevice;
use vcm_traversal_wgpu::shader::buffer_layouts;

use crate::kernel::bind_entries;

/// The bind group layouts of every buffer a WGSL module declares, group by group
/// ([`buffer_layouts`]: storage buffers read-only unless declared `read_write`), and the
/// pipeline layout of them: pipelines made with it share bind groups (the layouts wgpu
/// derives belong to one pipeline each).
pub(crate) struct DeclaredLayout {
    pub groups: Vec<wgpu::BindGroupLayout>,
    pub pipeline: wgpu::PipelineLayout,
}

impl DeclaredLayout {
    /// The layout of `source`, which must parse (the crate's sources are validated by tests).
    pub fn new(device: &wgpu::Device, label: &str, source: &str) -> DeclaredLayout {
        let entries = buffer_layouts(source).expect("the crate's WGSL modules parse");
        let groups: Vec<wgpu::BindGroupLayout> = entries
            .iter()
            .map(|entries| {
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(label),
                    entries,
                })
            })
            .collect();
        let pipeline = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &groups.iter().map(Some).collect::<Vec<_>>(),
            immediate_size: 0,
        });
        DeclaredLayout { groups, pipeline }
    }
}

/// Compute pipelines of one module, sharing bind group 0 of every buffer it declares.
pub(crate) struct Kernels {
    layout: DeclaredLayout,
    pub pipelines: Vec<wgpu::ComputePipeline>,
}

impl Kernels {
    /// The kernels `entries` of `source`, whose buffers are all in bind group 0.
    pub fn new(gpu: &GpuDevice, label: &str, source: String, entries: &[&str]) -> Kernels {
        let device = &gpu.device;
        let layout = DeclaredLayout::new(device, label, &source);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let pipelines = entries
            .iter()
            .map(|entry| {
                device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&layout.pipeline),
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
        bind_entries(&gpu.device, &self.layout.groups[0], buffers)
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
