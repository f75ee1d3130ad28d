//! [`SceneKernel`]: one of this crate's kernels compiled for a scene, with the scene's
//! shading data uploaded and bound, and the parameters of its dispatches.

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use vcm::memory::{AvailableMemory, MemoryEstimate, check_budget};
use vcm::{Algorithm, BidirPlan, Film, RenderError};
use vcm_scene::Scene;
use vcm_scene::sampling::SampleSequence;
use vcm_traversal_wgpu::{GpuBvh, GpuDevice, GpuError, PassTimer, dispatch_shape};

use crate::compute::DeclaredLayout;
use crate::error::GpuRenderError;
use crate::plan::KernelPlan;
use crate::scene_data::{SceneData, check_scene};
use crate::shader::{Kernel, kernel_module, shading_group};

/// `Params` of `scene.wgsl`.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct Params {
    camera_position: [f32; 3],
    width: u32,
    camera_forward: [f32; 3],
    height: u32,
    camera_right: [f32; 3],
    first_sample: u32,
    camera_up: [f32; 3],
    samples: u32,
    half_extent: [f32; 2],
    size: [f32; 2],
    seed: [u32; 2],
    first_path: u32,
    path_count: u32,
    row_threads: u32,
    max_segments: u32,
    independent: u32,
    light_count: u32,
    environment: u32,
    environment_rows: u32,
    environment_columns: u32,
    pixel_area: f32,
    light_paths: f32,
    connections: u32,
    light_pass: u32,
    plan: u32,
    kept_vertices: u32,
    light_path_count: u32,
    padding: [u32; 2],
}

const _: () = assert!(
    size_of::<Params>() == 160,
    "the size of Params in scene.wgsl"
);

/// Bytes of a dispatch's workgroup counts (x, y, z) read from a buffer.
pub(crate) const INDIRECT_BYTES: u64 = 12;

/// What the light pass does (`light_pass` and `kept_vertices` of `Params`, bidir.wgsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum LightPass {
    /// Light tracing alone, with the camera's first hits (and for kernels without a light
    /// pass).
    LightTracing,
    /// Splat with the bidirectional weights, count each light path's cacheable vertices and
    /// keep the first `kept` of them in the scratch buffer.
    FirstVertices { kept: u32 },
    /// Copy the kept vertices into the cache, and trace again the paths with more than
    /// `kept` to store the rest.
    LaterVertices { kept: u32 },
}

impl LightPass {
    /// `light_pass` and `kept_vertices` of `Params`.
    fn parameters(self) -> (u32, u32) {
        match self {
            LightPass::LightTracing => (0, 0),
            LightPass::FirstVertices { kept } => (1, kept),
            LightPass::LaterVertices { kept } => (2, kept),
        }
    }
}

/// What a dispatch's parameters take from an integrator's settings.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sampling {
    pub width: u32,
    pub height: u32,
    pub seed: u64,
    pub sequence: SampleSequence,
    pub max_depth: Option<u32>,
    /// N_c: light vertices each camera vertex connects to.
    pub connections: u32,
    /// The parts of a bidirectional algorithm that run (`plan` of bidir.wgsl).
    pub plan: u32,
}

impl Sampling {
    /// What every integrator's settings say: the image, the numbers, the path length; without
    /// connections.
    fn of_image(
        (width, height): (u32, u32),
        (seed, sequence): (u64, SampleSequence),
        max_depth: Option<u32>,
    ) -> Sampling {
        Sampling {
            width,
            height,
            seed,
            sequence,
            max_depth,
            connections: 0,
            plan: 0,
        }
    }
}

/// What a pass's dispatches are given: the settings' part, which pass of the light kernel
/// runs, and N_p, the light paths per iteration (the frame plan's).
pub(crate) type Pass<'a> = (&'a Sampling, LightPass, u32);

impl From<&vcm::PtSettings> for Sampling {
    fn from(s: &vcm::PtSettings) -> Sampling {
        Sampling::of_image((s.width, s.height), (s.seed, s.sequence), s.max_depth)
    }
}

impl Sampling {
    /// What the settings of a bidirectional algorithm that runs `plan` say.
    pub fn of_bidir(s: &vcm::VcmSettings, plan: &BidirPlan) -> Sampling {
        let mut parts = 0;
        for (part, runs) in [
            (SPLATS, plan.splats),
            (CONNECTS, plan.connects),
            (MERGES, plan.merges),
            (PPM, s.algorithm == Algorithm::Ppm),
        ] {
            if runs {
                parts |= part;
            }
        }
        Sampling {
            connections: s.connections,
            plan: parts,
            ..Sampling::of_image((s.width, s.height), (s.seed, s.sequence), s.max_depth)
        }
    }
}

/// The parts of a bidirectional algorithm, as `plan` of bidir.wgsl has them.
const SPLATS: u32 = 1;
const CONNECTS: u32 = 2;
const MERGES: u32 = 4;
const PPM: u32 = 8;

/// A kernel compiled for one scene, with the scene's shading data on the device.
pub(crate) struct SceneKernel {
    /// Which kernel it is.
    pub kind: Kernel,
    pub gpu: Arc<GpuDevice>,
    pub scene: Arc<Scene>,
    pub pipeline: wgpu::ComputePipeline,
    /// The pipelines of its stages ([`Kernel::stages`]), which share its bind groups.
    stages: Vec<wgpu::ComputePipeline>,
    /// The scene's buffers by bind group: 1 the hierarchy, 2 the alpha masks where there are
    /// any, then the shading data ([`shading_group`]).
    scene_buffers: Vec<(u32, Vec<wgpu::Buffer>)>,
    /// Their bind groups for this kernel's pipeline.
    scene_groups: Vec<(u32, wgpu::BindGroup)>,
    /// The WGSL of the traversal functions and whether they test alpha masks.
    traversal: (String, bool),
    light_count: u32,
    environment: u32,
    /// Where the environment map's rows and its rows' texels start in the picks buffer.
    environment_offsets: [u32; 2],
    /// The parts of the kernel the scene needs.
    pub plan: KernelPlan,
}

impl SceneKernel {
    /// `kernel` for `scene` on the hierarchy `bvh` (built over
    /// [`Scene::triangle_corners`]): compiles it and uploads the scene's shading data.
    pub fn new(kernel: Kernel, scene: Arc<Scene>, bvh: &GpuBvh) -> Result<Self, GpuRenderError> {
        check_scene(&scene).map_err(GpuRenderError::Unsupported)?;
        if scene.features.alpha_masks && !bvh.has_alpha_masks() {
            return Err(GpuRenderError::Unsupported(
                "a hierarchy built without the scene's alpha masks".into(),
            ));
        }
        let hierarchy = bvh
            .hierarchy_buffers()
            .ok_or_else(|| GpuRenderError::Unsupported("a scene without triangles".into()))?;
        let gpu = Arc::clone(bvh.device());
        let plan = KernelPlan::for_scene(&scene);
        let data = SceneData::new(&scene, &plan);
        let shading = vec![
            upload(&gpu, "shading triangles", &data.triangles)?,
            upload(&gpu, "materials", &data.materials)?,
            upload(&gpu, "lights", &data.lights)?,
            upload(&gpu, "picks", &data.picks)?,
            upload(&gpu, "lookup tables", &data.tables)?,
            upload(&gpu, "textures", &data.textures)?,
            upload(&gpu, "texels", &data.texels)?,
            upload(&gpu, "texture references", &data.texture_refs)?,
            upload(&gpu, "material inputs", &data.material_inputs)?,
            upload(&gpu, "triangle attributes", &data.attributes)?,
            upload(&gpu, "environment texels", &data.environment_texels)?,
        ];
        let mut scene_buffers = vec![(1, hierarchy.to_vec())];
        if let Some(masks) = bvh.alpha_mask_buffers() {
            scene_buffers.push((2, masks.to_vec()));
        }
        scene_buffers.push((shading_group(bvh.has_alpha_masks()), shading));
        let traversal = (bvh.traversal_functions(), bvh.has_alpha_masks());
        let (pipeline, stages) = compile(&gpu.device, kernel, &traversal, &plan);
        let scene_groups = bind_scene(&gpu.device, &pipeline, &scene_buffers);
        Ok(SceneKernel {
            kind: kernel,
            gpu,
            scene,
            pipeline,
            stages,
            scene_buffers,
            scene_groups,
            traversal,
            light_count: data.light_count,
            environment: data.environment,
            environment_offsets: data.environment_offsets,
            plan,
        })
    }

    /// `kernel` for the same scene, on the same buffers.
    pub fn sibling(&self, kernel: Kernel) -> SceneKernel {
        let device = &self.gpu.device;
        let (pipeline, stages) = compile(device, kernel, &self.traversal, &self.plan);
        let scene_groups = bind_scene(device, &pipeline, &self.scene_buffers);
        SceneKernel {
            kind: kernel,
            gpu: Arc::clone(&self.gpu),
            scene: Arc::clone(&self.scene),
            pipeline,
            stages,
            scene_buffers: self.scene_buffers.clone(),
            scene_groups,
            traversal: self.traversal.clone(),
            light_count: self.light_count,
            environment: self.environment,
            environment_offsets: self.environment_offsets,
            plan: self.plan,
        }
    }

    /// The parameters of invocations `first_path …` (`count` of them) of a frame of
    /// `samples` samples per pixel starting at sample `first_sample`, with `light_paths`
    /// light paths per iteration (N_p), and the workgroups to dispatch for them in x and y.
    fn params(
        &self,
        (sampling, light_pass, light_paths): Pass<'_>,
        (first_sample, samples): (u32, u32),
        (first_path, count): (u64, u64),
    ) -> (Params, (u32, u32)) {
        let Sampling {
            width,
            height,
            seed,
            sequence,
            max_depth,
            connections,
            plan,
        } = *sampling;
        let camera = &self.scene.camera;
        let projection = camera.projection(width, height);
        let max_per_dimension = self
            .gpu
            .device
            .limits()
            .max_compute_workgroups_per_dimension;
        let (x, y, row_threads) = dispatch_shape(count, max_per_dimension);
        let params = Params {
            camera_position: camera.position.to_array(),
            width,
            camera_forward: camera.forward.to_array(),
            height,
            camera_right: camera.right.to_array(),
            first_sample,
            camera_up: camera.up.to_array(),
            samples,
            half_extent: projection.half_extent().to_array(),
            size: [width as f32, height as f32],
            seed: [seed as u32, (seed >> 32) as u32],
            first_path: first_path as u32,
            path_count: count as u32,
            row_threads,
            max_segments: max_depth.unwrap_or(u32::MAX),
            independent: u32::from(sequence == SampleSequence::Independent),
            light_count: self.light_count,
            environment: self.environment,
            environment_rows: self.environment_offsets[0],
            environment_columns: self.environment_offsets[1],
            pixel_area: projection.pixel_area(),
            light_paths: light_paths as f32,
            connections,
            light_pass: light_pass.parameters().0,
            plan,
            kept_vertices: light_pass.parameters().1,
            light_path_count: light_paths,
            padding: [0; 2],
        };
        (params, (x, y))
    }

    /// A command encoder that writes the parameters of invocations `range` (first, count) of
    /// the frame `frame` (first sample, samples per pixel) and `light_pass` into `params`,
    /// clears `outputs` and dispatches the kernel's first stage with `dispatch` as bind
    /// group 0.
    pub fn encode(
        &self,
        (params, dispatch, timer): (&wgpu::Buffer, &wgpu::BindGroup, Option<&PassTimer>),
        pass: Pass<'_>,
        frame: (u32, u32),
        range: (u64, u64),
        outputs: &[&wgpu::Buffer],
    ) -> wgpu::CommandEncoder {
        let (values, (x, y)) = self.params(pass, frame, range);
        self.gpu
            .queue
            .write_buffer(params, 0, bytemuck::bytes_of(&values));
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        for output in outputs {
            encoder.clear_buffer(output, 0, None);
        }
        {
            let mut pass = self.pass(&mut encoder, dispatch, timer);
            pass.set_pipeline(&self.stages[0]);
            pass.dispatch_workgroups(x, y, 1);
        }
        encoder
    }

    /// Records `rounds` rounds of the path tracer's wavefront on `encoder` with `dispatch`
    /// as bind group 0: each takes the queued paths one vertex further and traces their
    /// shadow rays, in the workgroups `indirect` holds, advances the queues (one
    /// invocation), and copies the next round's workgroups from the start of `wave` (a
    /// buffer bound as storage cannot also give a dispatch its arguments).
    pub fn record_rounds(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (dispatch, timer): (&wgpu::BindGroup, Option<&PassTimer>),
        (wave, indirect): (&wgpu::Buffer, &wgpu::Buffer),
        rounds: u32,
    ) {
        for _ in 0..rounds {
            {
                let mut pass = self.pass(encoder, dispatch, timer);
                for stage in ["extend_paths", "trace_shadows"] {
                    pass.set_pipeline(self.stage(stage));
                    pass.dispatch_workgroups_indirect(indirect, 0);
                }
                pass.set_pipeline(self.stage("advance_paths"));
                pass.dispatch_workgroups(1, 1, 1);
            }
            encoder.copy_buffer_to_buffer(wave, 0, indirect, 0, INDIRECT_BYTES);
        }
    }

    /// Records the wavefront's tail on `encoder`: the queued paths taken to their end, in
    /// the workgroups `indirect` holds.
    pub fn record_tail(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (dispatch, timer): (&wgpu::BindGroup, Option<&PassTimer>),
        indirect: &wgpu::Buffer,
    ) {
        let mut pass = self.pass(encoder, dispatch, timer);
        pass.set_pipeline(self.stage("finish_paths"));
        pass.dispatch_workgroups_indirect(indirect, 0);
    }

    /// The pipeline of stage `entry`.
    fn stage(&self, entry: &str) -> &wgpu::ComputePipeline {
        let index = self.kind.stages().iter().position(|&stage| stage == entry);
        &self.stages[index.expect("a stage of the kernel")]
    }

    /// A compute pass on `encoder` with `dispatch` as bind group 0 and the scene's groups,
    /// timed by `timer` where given.
    fn pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        dispatch: &wgpu::BindGroup,
        timer: Option<&PassTimer>,
    ) -> wgpu::ComputePass<'e> {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(self.kind.entry()),
            timestamp_writes: timer.and_then(PassTimer::writes),
        });
        pass.set_bind_group(0, dispatch, &[]);
        for (index, group) in &self.scene_groups {
            pass.set_bind_group(*index, group, &[]);
        }
        pass
    }

    /// Binds each of `buffers` (binding, buffer) in the kernel's bind group `group`.
    pub fn bind_at<'a>(
        &self,
        group: u32,
        buffers: impl Iterator<Item = (u32, &'a wgpu::Buffer)>,
    ) -> wgpu::BindGroup {
        let layout = self.pipeline.get_bind_group_layout(group);
        bind_entries(&self.gpu.device, &layout, buffers)
    }

    /// A buffer of `size` bytes with `usage`.
    pub fn buffer(&self, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage,
            mapped_at_creation: false,
        })
    }
}

/// The pipeline of `kernel` over `traversal` (its WGSL, and whether it tests alpha masks),
/// specialised by `plan`, and those of its stages. A kernel of one stage has the layout its
/// bindings give it; the stages of one of several share a layout of every buffer the module
/// declares, so that one set of bind groups serves them all.
fn compile(
    device: &wgpu::Device,
    kernel: Kernel,
    (traversal, alpha_masks): &(String, bool),
    plan: &KernelPlan,
) -> (wgpu::ComputePipeline, Vec<wgpu::ComputePipeline>) {
    let source = kernel_module(kernel, traversal, *alpha_masks);
    let shared_layout = (kernel.stages().len() > 1)
        .then(|| DeclaredLayout::new(device, kernel.entry(), &source).pipeline);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(kernel.entry()),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let constants = plan.constants();
    let pipeline = |entry| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: shared_layout.as_ref(),
            module: &module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: &constants,
                ..Default::default()
            },
            cache: None,
        })
    };
    let stages: Vec<_> = kernel
        .stages()
        .iter()
        .map(|&entry| pipeline(entry))
        .collect();
    let main = kernel
        .stages()
        .iter()
        .position(|&entry| entry == kernel.entry());
    (
        stages[main.expect("the entry point is a stage")].clone(),
        stages,
    )
}

/// The bind groups of `pipeline` over the scene's `buffers` (by group).
fn bind_scene(
    device: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    buffers: &[(u32, Vec<wgpu::Buffer>)],
) -> Vec<(u32, wgpu::BindGroup)> {
    buffers
        .iter()
        .map(|(group, buffers)| (*group, bind(device, pipeline, *group, buffers.iter())))
        .collect()
}

/// Uploads `items` as a read-only storage buffer, one zeroed item if there are none (a
/// binding holds at least one element of its array).
fn upload<T: Pod>(
    gpu: &GpuDevice,
    label: &'static str,
    items: &[T],
) -> Result<wgpu::Buffer, GpuError> {
    let zero = [T::zeroed()];
    let items = if items.is_empty() { &zero[..] } else { items };
    gpu.storage_buffer(label, bytemuck::cast_slice(items))
}

/// Binds `buffers` to bindings 0, 1, … of bind group `group` of `pipeline`.
fn bind<'a>(
    device: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    group: u32,
    buffers: impl Iterator<Item = &'a wgpu::Buffer>,
) -> wgpu::BindGroup {
    bind_entries(
        device,
        &pipeline.get_bind_group_layout(group),
        (0u32..).zip(buffers),
    )
}

/// A bind group of `layout` binding each of `buffers` (binding, whole buffer).
pub(crate) fn bind_entries<'a>(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    buffers: impl Iterator<Item = (u32, &'a wgpu::Buffer)>,
) -> wgpu::BindGroup {
    let entries: Vec<_> = buffers
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout,
        entries: &entries,
    })
}

/// The host memory of the two films of a `width` × `height` render: the render's and the
/// frame's, to which a frame's dispatches add before it is whole.
pub(crate) fn film_estimate((width, height): (u32, u32)) -> MemoryEstimate {
    let pixels = u64::from(width) * u64::from(height);
    let films = pixels.saturating_mul(Film::BYTES_PER_PIXEL);
    MemoryEstimate::default()
        .with("film", films)
        .with("frame film", films)
}

/// Fails when `estimate` (which only the image size changes) needs more host memory than
/// this process may allocate.
pub(crate) fn check_host_estimate(estimate: MemoryEstimate) -> Result<(), RenderError> {
    let shortfall = check_budget(
        |cause| cause.is_none().then(|| estimate.clone()),
        AvailableMemory::of_this_process(),
        0,
    );
    Ok(shortfall?)
}
