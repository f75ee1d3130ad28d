//! [`GpuLightTracer`]: the light tracing kernel as an [`Integrator`].

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use vcm::{Algorithm, Film, FrameStats, Integrator, VcmSettings};
use vcm_scene::{Decision, Scene};
use vcm_traversal_wgpu::GpuBvh;

use crate::error::GpuRenderError;
use crate::frames::{Dispatched, GpuFrames, integrator_methods_of_frames};
use crate::kernel::{Params, Sampling, SceneKernel, check_host_estimate, film_estimate};
use crate::path_tracer::{RADIANCE_BYTES, read_radiance};
use crate::shader::Kernel;

/// Bytes of the ray counts (camera, light, shadow) and the splat count.
const COUNT_BYTES: u64 = 16;
/// Bytes of one splat (`SplatOut` of `light_tracer.wgsl`).
const SPLAT_BYTES: u64 = size_of::<SplatOut>() as u64;
/// Light paths per dispatch on a hardware GPU.
const PATHS_PER_DISPATCH: u64 = 1 << 18;
/// Light paths per dispatch on a CPU implementation (lavapipe).
const PATHS_PER_SOFTWARE_DISPATCH: u64 = 1 << 15;
/// Splats the buffer holds per light path of a full dispatch. A dispatch whose paths make
/// more is rendered again in halves (the buffer keeps its size, so a path may make as many
/// splats as the whole buffer holds).
const SPLATS_PER_PATH: u64 = 4;

/// `SplatOut` of `light_tracer.wgsl`.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct SplatOut {
    contribution: [f32; 3],
    pixel: u32,
}

/// Light tracing with every path shaded on the GPU: each iteration (one sample per pixel)
/// traces one light path per pixel, whose vertices connect to the camera, and one camera
/// sample per pixel, which finds the lights seen directly. The same image as the CPU's
/// [`vcm::Vcm`] with [`Algorithm::LightTracing`] and the same settings, up to floating-point
/// rounding per path. Renders the scenes [`check_scene`](crate::check_scene) accepts.
pub struct GpuLightTracer {
    frames: GpuFrames,
    settings: VcmSettings,
    buffers: DispatchBuffers,
}

/// One dispatch's parameters, outputs and read-back copy.
struct DispatchBuffers {
    params: wgpu::Buffer,
    radiance: wgpu::Buffer,
    counts: wgpu::Buffer,
    splat_count: wgpu::Buffer,
    splats: wgpu::Buffer,
    readback: wgpu::Buffer,
    group: wgpu::BindGroup,
}

impl GpuLightTracer {
    /// A light tracer for `scene` on the hierarchy `bvh` (built over
    /// [`Scene::triangle_corners`]), with `settings`, whose algorithm must be
    /// [`Algorithm::LightTracing`] (`connections`, `radius`, `alpha` and `lambert_lanes` do
    /// not apply). Compiles the kernel and uploads the scene's shading data.
    pub fn new(
        scene: Arc<Scene>,
        bvh: &GpuBvh,
        settings: VcmSettings,
    ) -> Result<GpuLightTracer, GpuRenderError> {
        if settings.algorithm != Algorithm::LightTracing {
            return Err(GpuRenderError::Refused(format!(
                "traces light paths for light tracing only so far, not {}",
                settings.algorithm.name()
            )));
        }
        let gpu = bvh.device();
        let paths = if gpu.is_software() {
            PATHS_PER_SOFTWARE_DISPATCH
        } else {
            PATHS_PER_DISPATCH
        }
        .min(gpu.max_binding_bytes() / (SPLATS_PER_PATH * SPLAT_BYTES));
        Self::with_buffers(scene, bvh, settings, (paths, paths * SPLATS_PER_PATH))
    }

    /// [`GpuLightTracer::new`] with dispatches of up to `paths` invocations and `splats`
    /// splats.
    fn with_buffers(
        scene: Arc<Scene>,
        bvh: &GpuBvh,
        settings: VcmSettings,
        (paths, splats): (u64, u64),
    ) -> Result<GpuLightTracer, GpuRenderError> {
        vcm::check_image_size(settings.width, settings.height)?;
        let estimate = film_estimate((settings.width, settings.height))
            .with("camera samples", paths * RADIANCE_BYTES)
            .with("splats", splats * SPLAT_BYTES);
        check_host_estimate(estimate)?;
        let kernel = SceneKernel::new(Kernel::LightTracer, scene, bvh)?;
        let buffers = DispatchBuffers::new(&kernel, (paths, splats));
        let size = (settings.width, settings.height);
        Ok(GpuLightTracer {
            frames: GpuFrames::new(kernel, size, paths),
            settings,
            buffers,
        })
    }

    /// The settings this tracer renders with.
    pub fn settings(&self) -> &VcmSettings {
        &self.settings
    }
}

impl DispatchBuffers {
    /// Buffers for dispatches of up to `paths` invocations of `kernel` and `splats` splats.
    fn new(kernel: &SceneKernel, (paths, splats): (u64, u64)) -> Self {
        use wgpu::BufferUsages as U;
        let radiance_bytes = paths * RADIANCE_BYTES;
        let splat_bytes = splats * SPLAT_BYTES;
        let output = U::STORAGE | U::COPY_SRC | U::COPY_DST;
        let params = kernel.buffer(
            "light tracer parameters",
            size_of::<Params>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let radiance = kernel.buffer("camera sample radiance", radiance_bytes, output);
        let counts = kernel.buffer("ray counts", COUNT_BYTES - 4, output);
        let splat_count = kernel.buffer("splat count", 4, output);
        let splats = kernel.buffer("splats", splat_bytes, output);
        let readback = kernel.buffer(
            "light tracer read-back",
            radiance_bytes + COUNT_BYTES + splat_bytes,
            U::MAP_READ | U::COPY_DST,
        );
        let group = kernel.bind(
            0,
            [&params, &radiance, &counts, &splats, &splat_count].into_iter(),
        );
        DispatchBuffers {
            params,
            radiance,
            counts,
            splat_count,
            splats,
            readback,
            group,
        }
    }

    /// Renders invocations `first_path …` (`count` of them) of the frame `frame` (first
    /// sample, samples per pixel): their camera samples' radiance, their splats and the rays
    /// traced (camera, light, shadow); `None` where the splats overflowed their buffer.
    fn dispatch(
        &self,
        kernel: &SceneKernel,
        sampling: &Sampling,
        frame: (u32, u32),
        (first_path, count): (u64, u64),
    ) -> Result<Option<Dispatched>, String> {
        let dispatch = (&self.params, &self.group);
        let outputs = [&self.counts, &self.splat_count];
        let range = (first_path, count);
        let mut encoder = kernel.encode(dispatch, sampling, frame, range, &outputs);
        let radiance_bytes = count * RADIANCE_BYTES;
        let splat_bytes = self.splats.size();
        let mut at = 0;
        for (buffer, bytes) in [
            (&self.radiance, radiance_bytes),
            (&self.counts, self.counts.size()),
            (&self.splat_count, self.splat_count.size()),
            (&self.splats, splat_bytes),
        ] {
            encoder.copy_buffer_to_buffer(buffer, 0, &self.readback, at, bytes);
            at += bytes;
        }
        let capacity = splat_bytes / SPLAT_BYTES;
        let read = |bytes: &[u8]| {
            let (radiance, rest) = bytes.split_at(radiance_bytes as usize);
            let (counts, splats) = rest.split_at(COUNT_BYTES as usize);
            let counts: Vec<u32> = bytemuck::pod_collect_to_vec(counts);
            let made = u64::from(counts[3]);
            let splats: Vec<SplatOut> = bytemuck::pod_collect_to_vec(
                &splats[..(made.min(capacity) * SPLAT_BYTES) as usize],
            );
            (made <= capacity).then(|| Dispatched {
                radiance: read_radiance(radiance),
                splats: splats
                    .iter()
                    .map(|s| (s.pixel, Vec3::from(s.contribution)))
                    .collect(),
                rays: [counts[0], counts[1], counts[2]].map(u64::from),
            })
        };
        kernel.gpu.read_back(encoder, (&self.readback, at), read)
    }
}

impl Integrator for GpuLightTracer {
    integrator_methods_of_frames!("light paths");

    /// Renders iterations `first_sample …` (`samples_per_frame` of them) on the GPU, in
    /// dispatches of consecutive invocations, and adds them to `film`.
    fn render_frame(&mut self, film: &mut Film, first_sample: u32) -> FrameStats {
        let sampling = Sampling::from(&self.settings);
        let buffers = &self.buffers;
        let dispatch =
            |kernel: &SceneKernel, frame, range| buffers.dispatch(kernel, &sampling, frame, range);
        let stats = |[camera, light, shadow]: [u64; 3], _| FrameStats {
            camera_rays: camera,
            light_rays: light,
            shadow_rays: shadow,
            ..FrameStats::default()
        };
        self.frames
            .render(film, first_sample, "light tracing", dispatch, stats)
    }

    fn decisions(&self) -> Vec<Decision> {
        let reason = "light tracing connects light vertices to the camera only";
        let kernel = &self.frames.kernel;
        vec![
            Decision::runs(
                "shading on the GPU",
                format!(
                    "one WGSL kernel follows each light path to its end, and each camera \
                     sample to its first hit, on {}; only radiances and splats come back",
                    kernel.gpu.describe()
                ),
            ),
            Decision::runs(
                "light tracing splats",
                "light vertices connect to the camera",
            ),
            Decision::left_out("light vertex cache", reason),
            Decision::left_out("merging and hash grid", reason),
        ]
        .into_iter()
        .chain(kernel.plan.decisions())
        .collect()
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use vcm::Schedule;
    use vcm_traversal_wgpu::{GpuBvhOptions, GpuDevice, device_or_skip};

    use super::*;

    /// Renders two frames of 2 samples per pixel of the Cornell box at 24 × 18 with `tracer`.
    fn render(tracer: &mut GpuLightTracer) -> (Film, Option<String>) {
        let schedule = Schedule {
            samples_per_frame: 2,
            ..Schedule::ONE_BATCH
        };
        tracer.set_schedule(schedule).unwrap();
        let mut film = Film::new(24, 18);
        for frame in 0..2 {
            tracer.render_frame(&mut film, 2 * frame);
        }
        (film, tracer.failure())
    }

    /// A light tracer of the Cornell box with dispatches of `paths` invocations and `splats`
    /// splats.
    fn tracer(gpu: &Arc<GpuDevice>, (paths, splats): (u64, u64)) -> GpuLightTracer {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.gltf");
        let scene = Arc::new(Scene::load(&path).unwrap());
        let corners = scene.triangle_corners();
        let bvh = GpuBvh::new(Arc::clone(gpu), &corners, GpuBvhOptions::default()).unwrap();
        let settings = VcmSettings::new(Algorithm::LightTracing, 24, 18);
        GpuLightTracer::with_buffers(scene, &bvh, settings, (paths, splats)).unwrap()
    }

    /// Dispatches whose splats overflow their buffer are rendered again in halves: the film is
    /// bit for bit that of dispatches with room to spare; a path that alone overflows it is
    /// a failure that says so.
    #[test]
    fn overflowing_splats_are_rendered_again_in_smaller_dispatches() {
        let Some(gpu) = device_or_skip().map(Arc::new) else {
            return;
        };
        let (roomy, no_failure) = render(&mut tracer(&gpu, (1 << 12, 1 << 16)));
        assert_eq!(no_failure, None);
        let mut cramped = tracer(&gpu, (256, 16));
        let (halved, no_failure) = render(&mut cramped);
        assert_eq!(no_failure, None);
        assert!(
            cramped.frames.paths_per_dispatch() < 256,
            "the splats never overflowed"
        );
        assert_eq!(halved, roomy);
        assert!(roomy.mean().iter().any(|p| p.max_element() > 0.0));
        let (_, failure) = render(&mut tracer(&gpu, (256, 1)));
        let failure = failure.expect("some path of the box makes two splats");
        assert!(
            failure.contains("overflows the dispatch's buffer"),
            "{failure}"
        );
    }
}
