//! [`GpuLightTracer`]: the light tracing kernel as an [`Integrator`].

use std::sync::Arc;

use vcm::{Algorithm, Film, FrameStats, Integrator, VcmSettings};
use vcm_scene::{Decision, Scene};
use vcm_traversal_wgpu::GpuBvh;

use crate::error::GpuRenderError;
use crate::frames::{GpuFrames, integrator_methods_of_frames};
use crate::kernel::Sampling;
use crate::shader::Kernel;

/// Light tracing with every path shaded on the GPU: each iteration (one sample per pixel)
/// traces one light path per pixel, whose vertices connect to the camera, and one camera
/// sample per pixel, which finds the lights seen directly; both add to the film on the
/// device. The same image as the CPU's [`vcm::Vcm`] with [`Algorithm::LightTracing`] and the
/// same settings, up to floating-point rounding per path. Renders the scenes
/// [`check_scene`](crate::check_scene) accepts.
pub struct GpuLightTracer {
    frames: GpuFrames,
    settings: VcmSettings,
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
        let size = (settings.width, settings.height);
        let frames = GpuFrames::new(Kernel::LightTracer, scene, bvh, size)?;
        Ok(GpuLightTracer { frames, settings })
    }

    /// The settings this tracer renders with.
    pub fn settings(&self) -> &VcmSettings {
        &self.settings
    }
}

impl Integrator for GpuLightTracer {
    integrator_methods_of_frames!("light paths");

    /// Renders iterations `first_sample …` (`samples_per_frame` of them) on the GPU, in
    /// dispatches of consecutive invocations, and adds them to `film`.
    fn render_frame(&mut self, film: &mut Film, first_sample: u32) -> FrameStats {
        let sampling = Sampling::from(&self.settings);
        let stats = |[camera, light, shadow]: [u64; 3], _| FrameStats {
            camera_rays: camera,
            light_rays: light,
            shadow_rays: shadow,
            ..FrameStats::default()
        };
        let frames = &mut self.frames;
        frames.render(film, first_sample, ("light tracing", &sampling), stats)
    }

    fn decisions(&self) -> Vec<Decision> {
        let reason = "light tracing connects light vertices to the camera only";
        let kernel = &self.frames.kernel;
        vec![
            Decision::runs(
                "shading on the GPU",
                format!(
                    "one WGSL kernel follows each light path to its end, and each camera \
                     sample to its first hit, on {}, adding them to the film on the device; \
                     only the film comes back",
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
