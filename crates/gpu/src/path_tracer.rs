//! [`GpuPathTracer`]: the path tracing kernel as an [`Integrator`].

use std::sync::Arc;

use vcm::{Film, FrameStats, Integrator, PtSettings};
use vcm_scene::{Decision, Scene};
use vcm_traversal_wgpu::GpuBvh;

use crate::error::GpuRenderError;
use crate::frames::{FramePlan, GpuFrames, integrator_methods_of_frames};
use crate::kernel::Sampling;

/// The path tracer with every path shaded on the GPU: the same image as the CPU's
/// [`vcm::PathTracer`] with the same settings, up to floating-point rounding per path.
/// Renders the scenes [`check_scene`](crate::check_scene) accepts.
pub struct GpuPathTracer {
    frames: GpuFrames,
    settings: PtSettings,
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
        let frames = GpuFrames::new(FramePlan::PathTracing, scene, bvh, size)?;
        Ok(GpuPathTracer { frames, settings })
    }

    /// The settings this tracer renders with.
    pub fn settings(&self) -> &PtSettings {
        &self.settings
    }
}

impl Integrator for GpuPathTracer {
    integrator_methods_of_frames!("paths");

    /// Renders samples `first_sample …` (`samples_per_frame` per pixel) on the GPU, in
    /// dispatches of consecutive paths, and adds them to `film`.
    fn render_frame(&mut self, film: &mut Film, first_sample: u32) -> FrameStats {
        let sampling = Sampling::from(&self.settings);
        let stats = |[closest, shadow, _]: [u64; 3], paths| FrameStats {
            camera_rays: paths,
            continuation_rays: closest - paths,
            shadow_rays: shadow,
            ..FrameStats::default()
        };
        let frames = &mut self.frames;
        frames.render(film, first_sample, ("path tracing", &sampling), stats)
    }

    fn decisions(&self) -> Vec<Decision> {
        let reason = "path tracing neither connects nor merges";
        let kernel = &self.frames.kernels[0];
        vec![
            Decision::runs(
                "shading on the GPU",
                format!(
                    "a wavefront of WGSL kernels on {} takes the paths vertex by vertex \
                     (queues in storage buffers, shadow rays in a kernel of their own), adding \
                     them to the film on the device; only the film comes back",
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
