//! [`GpuPathTracer`]: the path tracing kernel as an [`Integrator`].

use std::sync::Arc;

use vcm::{Film, FrameStats, Integrator, PtSettings};
use vcm_scene::{Decision, Scene};
use vcm_traversal_wgpu::GpuBvh;

use crate::error::GpuRenderError;
use crate::frames::{Dispatched, GpuFrames, integrator_methods_of_frames};
use crate::kernel::{Params, Sampling, SceneKernel, check_host_estimate, film_estimate};
use crate::shader::Kernel;

/// Bytes of one path's radiance in the kernel's output (`vec4<f32>`).
pub(crate) const RADIANCE_BYTES: u64 = 16;
/// Bytes of the ray counts (closest hit, shadow).
const COUNT_BYTES: u64 = 8;
/// Paths per dispatch on a hardware GPU: enough to fill one, few enough that a frame can
/// stop between dispatches.
const PATHS_PER_DISPATCH: u64 = 1 << 20;
/// Paths per dispatch on a CPU implementation (lavapipe), which runs them on a few cores.
const PATHS_PER_SOFTWARE_DISPATCH: u64 = 1 << 15;

/// The path tracer with every path shaded on the GPU: the same image as the CPU's
/// [`vcm::PathTracer`] with the same settings, up to floating-point rounding per path.
/// Renders the scenes [`check_scene`](crate::check_scene) accepts.
pub struct GpuPathTracer {
    frames: GpuFrames,
    settings: PtSettings,
    buffers: DispatchBuffers,
}

/// One dispatch's parameters, output and read-back copy.
struct DispatchBuffers {
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
        let size = (settings.width, settings.height);
        vcm::check_image_size(size.0, size.1)?;
        // The host holds one dispatch's radiances, whatever the samples per frame.
        let estimate =
            film_estimate(size).with("path radiances", PATHS_PER_DISPATCH * RADIANCE_BYTES);
        check_host_estimate(estimate)?;
        let kernel = SceneKernel::new(Kernel::PathTracer, scene, bvh)?;
        let paths = if kernel.gpu.is_software() {
            PATHS_PER_SOFTWARE_DISPATCH
        } else {
            PATHS_PER_DISPATCH
        }
        .min(kernel.gpu.max_binding_bytes() / RADIANCE_BYTES);
        let buffers = DispatchBuffers::new(&kernel, paths);
        Ok(GpuPathTracer {
            frames: GpuFrames::new(kernel, size, paths),
            settings,
            buffers,
        })
    }

    /// The settings this tracer renders with.
    pub fn settings(&self) -> &PtSettings {
        &self.settings
    }
}

impl DispatchBuffers {
    /// Buffers for dispatches of up to `paths` paths of `kernel`.
    fn new(kernel: &SceneKernel, paths: u64) -> Self {
        use wgpu::BufferUsages as U;
        let radiance_bytes = paths * RADIANCE_BYTES;
        let params = kernel.buffer(
            "path tracer parameters",
            size_of::<Params>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let radiance = kernel.buffer("path radiance", radiance_bytes, U::STORAGE | U::COPY_SRC);
        let counts = kernel.buffer(
            "ray counts",
            COUNT_BYTES,
            U::STORAGE | U::COPY_SRC | U::COPY_DST,
        );
        let readback = kernel.buffer(
            "path radiance read-back",
            radiance_bytes + COUNT_BYTES,
            U::MAP_READ | U::COPY_DST,
        );
        let group = kernel.bind(0, [&params, &radiance, &counts].into_iter());
        DispatchBuffers {
            params,
            radiance,
            counts,
            readback,
            group,
        }
    }

    /// Renders paths `first_path …` (`count` of them) of the frame `frame` (first sample,
    /// samples per pixel): their radiances, and the closest-hit and shadow rays they traced.
    fn dispatch(
        &self,
        kernel: &SceneKernel,
        sampling: &Sampling,
        frame: (u32, u32),
        (first_path, count): (u64, u64),
    ) -> Result<Option<Dispatched>, String> {
        let dispatch = (&self.params, &self.group);
        let range = (first_path, count);
        let mut encoder = kernel.encode(dispatch, sampling, frame, range, &[&self.counts]);
        let radiance_bytes = count * RADIANCE_BYTES;
        encoder.copy_buffer_to_buffer(&self.radiance, 0, &self.readback, 0, radiance_bytes);
        encoder.copy_buffer_to_buffer(&self.counts, 0, &self.readback, radiance_bytes, COUNT_BYTES);
        let read = |bytes: &[u8]| {
            let (radiance, counts) = bytes.split_at(radiance_bytes as usize);
            let counts: Vec<u32> = bytemuck::pod_collect_to_vec(counts);
            Some(Dispatched {
                radiance: read_radiance(radiance),
                splats: Vec::new(),
                rays: [u64::from(counts[0]), u64::from(counts[1]), 0],
            })
        };
        kernel.gpu.read_back(
            encoder,
            (&self.readback, radiance_bytes + COUNT_BYTES),
            read,
        )
    }
}

/// The radiances a kernel wrote (`vec4<f32>` each).
pub(crate) fn read_radiance(bytes: &[u8]) -> Vec<glam::Vec3> {
    let radiance: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(bytes);
    radiance
        .iter()
        .map(|r| glam::Vec3::new(r[0], r[1], r[2]))
        .collect()
}

impl Integrator for GpuPathTracer {
    integrator_methods_of_frames!("paths");

    /// Renders samples `first_sample …` (`samples_per_frame` per pixel) on the GPU, in
    /// dispatches of consecutive paths, and adds them to `film`.
    fn render_frame(&mut self, film: &mut Film, first_sample: u32) -> FrameStats {
        let sampling = Sampling::from(&self.settings);
        let buffers = &self.buffers;
        let dispatch =
            |kernel: &SceneKernel, frame, range| buffers.dispatch(kernel, &sampling, frame, range);
        let stats = |[closest, shadow, _]: [u64; 3], paths| FrameStats {
            camera_rays: paths,
            continuation_rays: closest - paths,
            shadow_rays: shadow,
            ..FrameStats::default()
        };
        self.frames
            .render(film, first_sample, "path tracing", dispatch, stats)
    }

    fn decisions(&self) -> Vec<Decision> {
        let reason = "path tracing neither connects nor merges";
        let kernel = &self.frames.kernel;
        vec![
            Decision::runs(
                "shading on the GPU",
                format!(
                    "one WGSL kernel follows each path to its end on {}; only radiances come back",
                    kernel.gpu.describe()
                ),
            ),
            Decision::left_out("light paths", reason),
            Decision::left_out("merging and hash grid", reason),
        ]
        .into_iter()
        .chain(kernel.plan.decisions())
        .collect()
    }
}
