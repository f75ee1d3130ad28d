//! [`GpuPathTracer`]: the path tracing kernel as an [`Integrator`].

use std::sync::Arc;
use std::time::Instant;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use vcm::memory::{AvailableMemory, MemoryEstimate, check_budget};
use vcm::{Film, FrameStats, Integrator, PtSettings, RenderError, Schedule, StopFlag};
use vcm_scene::sampling::SampleSequence;
use vcm_scene::{Decision, Scene};
use vcm_traversal_wgpu::{GpuBvh, GpuDevice, GpuError, dispatch_shape};

use crate::error::GpuRenderError;
use crate::plan::KernelPlan;
use crate::scene_data::{SceneData, check_scene};
use crate::shader::{PATH_TRACER_ENTRY, path_tracer_module, shading_group};

/// `Params` of `path_tracer.wgsl`.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct Params {
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
    unused: u32,
}

const _: () = assert!(
    size_of::<Params>() == 128,
    "the size of Params in path_tracer.wgsl"
);

/// Bytes of one path's radiance in the kernel's output (`vec4<f32>`).
const RADIANCE_BYTES: u64 = 16;
/// Bytes of the ray counts (closest hit, shadow).
const COUNT_BYTES: u64 = 8;
/// Paths per dispatch on a hardware GPU: enough to fill one, few enough that a frame can
/// stop between dispatches.
const PATHS_PER_DISPATCH: u64 = 1 << 20;
/// Paths per dispatch on a CPU implementation (lavapipe), which runs them on a few cores.
const PATHS_PER_SOFTWARE_DISPATCH: u64 = 1 << 15;

/// The path tracer with every path shaded on the GPU: the same image as the CPU's
/// [`vcm::PathTracer`] with the same settings, up to floating-point rounding per path.
/// Renders the scenes [`check_scene`] accepts.
pub struct GpuPathTracer {
    gpu: Arc<GpuDevice>,
    scene: Arc<Scene>,
    settings: PtSettings,
    pipeline: wgpu::ComputePipeline,
    /// The scene's bind groups with their indices: 1 the hierarchy, 2 the alpha masks where
    /// there are any, then the shading data ([`shading_group`]).
    scene_groups: Vec<(u32, wgpu::BindGroup)>,
    buffers: DispatchBuffers,
    light_count: u32,
    environment: u32,
    /// Where the environment map's rows and its rows' texels start in the picks buffer.
    environment_offsets: [u32; 2],
    /// The parts of the kernel the scene needs.
    plan: KernelPlan,
    samples_per_frame: u32,
    stop: StopFlag,
    /// What failed on the GPU, once something has: no frame renders after it.
    failure: Option<String>,
}

/// One dispatch's parameters, output and read-back copy.
struct DispatchBuffers {
    paths: u64,
    params: wgpu::Buffer,
    radiance: wgpu::Buffer,
    counts: wgpu::Buffer,
    readback: wgpu::Buffer,
    group: wgpu::BindGroup,
}

impl GpuPathTracer {
    /// A path tracer for `scene` on the hierarchy `bvh` (built over
    /// [`Scene::triangle_corners`]), with `settings` (`lambert_lanes` does not apply).
    /// Compiles the kernel and uploads the scene's shading data.
    pub fn new(
        scene: Arc<Scene>,
        bvh: &GpuBvh,
        settings: PtSettings,
    ) -> Result<GpuPathTracer, GpuRenderError> {
        vcm::check_image_size(settings.width, settings.height)?;
        check_host_memory((settings.width, settings.height))?;
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
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("path tracer"),
            source: wgpu::ShaderSource::Wgsl(
                path_tracer_module(&bvh.traversal_functions(), bvh.has_alpha_masks()).into(),
            ),
        });
        let plan = KernelPlan::for_scene(&scene);
        let constants = plan.constants();
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(PATH_TRACER_ENTRY),
            layout: None,
            module: &module,
            entry_point: Some(PATH_TRACER_ENTRY),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: &constants,
                ..Default::default()
            },
            cache: None,
        });
        let data = SceneData::new(&scene, &plan);
        let shading = [
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
        let mut scene_groups = vec![(1, bind(device, &pipeline, 1, hierarchy.iter()))];
        if let Some(masks) = bvh.alpha_mask_buffers() {
            scene_groups.push((2, bind(device, &pipeline, 2, masks.iter())));
        }
        let group = shading_group(bvh.has_alpha_masks());
        scene_groups.push((group, bind(device, &pipeline, group, shading.iter())));
        let paths = if gpu.is_software() {
            PATHS_PER_SOFTWARE_DISPATCH
        } else {
            PATHS_PER_DISPATCH
        }
        .min(gpu.max_binding_bytes() / RADIANCE_BYTES);
        let buffers = DispatchBuffers::new(device, &pipeline, paths);
        Ok(GpuPathTracer {
            gpu,
            scene,
            settings,
            pipeline,
            scene_groups,
            buffers,
            light_count: data.light_count,
            environment: data.environment,
            environment_offsets: data.environment_offsets,
            plan,
            samples_per_frame: 1,
            stop: StopFlag::new(),
            failure: None,
        })
    }

    /// The settings this tracer renders with.
    pub fn settings(&self) -> &PtSettings {
        &self.settings
    }

    /// The kernel's parameters for paths `first_path …` (`count` of them) of the frame
    /// starting at sample `first_sample`.
    fn params(&self, first_sample: u32, (first_path, count): (u64, u64)) -> (Params, (u32, u32)) {
        let PtSettings {
            width,
            height,
            seed,
            sequence,
            max_depth,
            ..
        } = self.settings;
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
            samples: self.samples_per_frame,
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
            unused: 0,
        };
        (params, (x, y))
    }

    /// Renders paths `first_path …` (`count` of them) and returns their radiances and the
    /// closest-hit and shadow rays they traced.
    fn dispatch(
        &self,
        first_sample: u32,
        (first_path, count): (u64, u64),
    ) -> Result<(Vec<Vec3>, [u64; 2]), String> {
        let (params, (x, y)) = self.params(first_sample, (first_path, count));
        let b = &self.buffers;
        let queue = &self.gpu.queue;
        queue.write_buffer(&b.params, 0, bytemuck::bytes_of(&params));
        let device = &self.gpu.device;
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&b.counts, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("path tracer"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &b.group, &[]);
            for (index, group) in &self.scene_groups {
                pass.set_bind_group(*index, group, &[]);
            }
            pass.dispatch_workgroups(x, y, 1);
        }
        let radiance_bytes = count * RADIANCE_BYTES;
        encoder.copy_buffer_to_buffer(&b.radiance, 0, &b.readback, 0, radiance_bytes);
        encoder.copy_buffer_to_buffer(&b.counts, 0, &b.readback, radiance_bytes, COUNT_BYTES);
        let read = |bytes: &[u8]| {
            let (radiance, counts) = bytes.split_at(radiance_bytes as usize);
            let radiance: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(radiance);
            let counts: Vec<u32> = bytemuck::pod_collect_to_vec(counts);
            let radiance = radiance
                .iter()
                .map(|r| Vec3::new(r[0], r[1], r[2]))
                .collect();
            (radiance, [u64::from(counts[0]), u64::from(counts[1])])
        };
        let bytes = radiance_bytes + COUNT_BYTES;
        self.gpu.read_back(encoder, (&b.readback, bytes), read)
    }
}

impl DispatchBuffers {
    /// Buffers for dispatches of up to `paths` paths.
    fn new(device: &wgpu::Device, pipeline: &wgpu::ComputePipeline, paths: u64) -> Self {
        use wgpu::BufferUsages as U;
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let radiance_bytes = paths * RADIANCE_BYTES;
        let params = buffer(
            "path tracer parameters",
            size_of::<Params>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let radiance = buffer("path radiance", radiance_bytes, U::STORAGE | U::COPY_SRC);
        let counts = buffer(
            "ray counts",
            COUNT_BYTES,
            U::STORAGE | U::COPY_SRC | U::COPY_DST,
        );
        let readback = buffer(
            "path radiance read-back",
            radiance_bytes + COUNT_BYTES,
            U::MAP_READ | U::COPY_DST,
        );
        let group = bind(
            device,
            pipeline,
            0,
            [&params, &radiance, &counts].into_iter(),
        );
        DispatchBuffers {
            paths,
            params,
            radiance,
            counts,
            readback,
            group,
        }
    }
}

/// Fails when a render of `width` × `height` pixels needs more host memory than this process
/// may allocate: the film, the frame's film and one dispatch's radiances (at most
/// [`PATHS_PER_DISPATCH`]), whatever the samples per frame.
fn check_host_memory((width, height): (u32, u32)) -> Result<(), RenderError> {
    let pixels = u64::from(width) * u64::from(height);
    let films = pixels.saturating_mul(Film::BYTES_PER_PIXEL);
    let estimate = MemoryEstimate::default()
        .with("film", films)
        .with("frame film", films)
        .with("path radiances", PATHS_PER_DISPATCH * RADIANCE_BYTES);
    // Only the image size changes it.
    let shortfall = check_budget(
        |cause| cause.is_none().then(|| estimate.clone()),
        AvailableMemory::of_this_process(),
        0,
    );
    Ok(shortfall?)
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
    let entries: Vec<_> = (0u32..)
        .zip(buffers)
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("path tracer"),
        layout: &pipeline.get_bind_group_layout(group),
        entries: &entries,
    })
}

impl Integrator for GpuPathTracer {
    /// Renders samples `first_sample …` (`samples_per_frame` per pixel) on the GPU, in
    /// dispatches of consecutive paths, and adds them to `film`.
    fn render_frame(&mut self, film: &mut Film, first_sample: u32) -> FrameStats {
        let PtSettings { width, height, .. } = self.settings;
        assert_eq!(
            (film.width(), film.height()),
            (width, height),
            "film size differs from the settings"
        );
        let start = Instant::now();
        let samples = u64::from(self.samples_per_frame);
        let paths = u64::from(width) * u64::from(height) * samples;
        // The frame's samples, added to `film` once the frame is whole (an interrupted one
        // leaves it as it was); the host holds one dispatch's radiances at a time.
        let mut frame = Film::new(width, height);
        let mut rays = [0u64; 2];
        for first in (0..paths).step_by(self.buffers.paths as usize) {
            if self.stop.is_raised() || self.failure.is_some() {
                return FrameStats::INTERRUPTED;
            }
            let count = self.buffers.paths.min(paths - first);
            let (radiance, counts) = match self.dispatch(first_sample, (first, count)) {
                Ok(dispatched) => dispatched,
                Err(error) => {
                    self.failure = Some(format!("path tracing on the GPU: {error}"));
                    return FrameStats::INTERRUPTED;
                }
            };
            for (path, rgb) in (first..).zip(radiance) {
                frame.add((path / samples) as usize, rgb);
            }
            rays[0] += counts[0];
            rays[1] += counts[1];
        }
        // Exact sums: the same film as adding each sample to `film` directly.
        film.merge(&frame);
        let camera_rays = paths;
        FrameStats {
            camera_rays,
            continuation_rays: rays[0] - camera_rays,
            shadow_rays: rays[1],
            shading_time: start.elapsed(),
            ..FrameStats::default()
        }
    }

    fn image_size(&self) -> (u32, u32) {
        (self.settings.width, self.settings.height)
    }

    /// Takes the samples per pixel per frame; the scheduler, a CPU matter, does not apply.
    fn set_schedule(&mut self, schedule: Schedule) -> Result<(), RenderError> {
        let schedule = schedule.validated()?;
        let paths = u64::from(self.settings.width)
            * u64::from(self.settings.height)
            * u64::from(schedule.samples_per_frame);
        if paths > u64::from(u32::MAX) {
            return Err(RenderError::InvalidSetting(format!(
                "{} samples per pixel per frame make {paths} paths, more than the GPU path \
                 tracer numbers in one frame (2³² − 1)",
                schedule.samples_per_frame
            )));
        }
        self.samples_per_frame = schedule.samples_per_frame;
        Ok(())
    }

    fn set_stop(&mut self, stop: StopFlag) {
        self.stop = stop;
    }

    fn samples_per_frame(&self) -> u32 {
        self.samples_per_frame
    }

    fn decisions(&self) -> Vec<Decision> {
        let reason = "path tracing neither connects nor merges";
        vec![
            Decision::runs(
                "shading on the GPU",
                format!(
                    "one WGSL kernel follows each path to its end on {}; only radiances come back",
                    self.gpu.describe()
                ),
            ),
            Decision::left_out("light paths", reason),
            Decision::left_out("merging and hash grid", reason),
        ]
        .into_iter()
        .chain(self.plan.decisions())
        .collect()
    }

    fn failure(&self) -> Option<String> {
        self.failure.clone()
    }
}
