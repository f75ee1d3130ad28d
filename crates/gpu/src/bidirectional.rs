//! [`GpuBidirectional`]: light tracing and bidirectional path tracing with their kernels, as
//! an [`Integrator`].

use std::sync::Arc;

use vcm::{Algorithm, Film, FrameStats, Integrator, VcmSettings};
use vcm_scene::{Decision, Scene};
use vcm_traversal_wgpu::GpuBvh;

use crate::error::GpuRenderError;
use crate::frames::{FramePlan, GpuFrames, integrator_methods_of_frames};
use crate::kernel::Sampling;
use crate::shader::Kernel;

/// Light tracing or bidirectional path tracing with every path shaded on the GPU: each
/// iteration (one sample per pixel) traces one light path per pixel, whose vertices connect
/// to the camera, and one camera sample per pixel — for light tracing its first hit, which
/// finds the lights seen directly; for BPT a whole path, which also samples lights and
/// connects to `connections` light vertices of its iteration picked uniformly, all weighted
/// by MIS. Everything is added to the film on the device. The same image as the CPU's
/// [`vcm::Vcm`] with the same settings, up to floating-point rounding per path. Renders the
/// scenes [`check_scene`](crate::check_scene) accepts.
pub struct GpuBidirectional {
    frames: GpuFrames,
    settings: VcmSettings,
}

impl GpuBidirectional {
    /// The algorithms it renders.
    pub const ALGORITHMS: [Algorithm; 2] = [Algorithm::LightTracing, Algorithm::Bpt];

    /// `settings.algorithm` (one of [`GpuBidirectional::ALGORITHMS`]) for `scene` on the
    /// hierarchy `bvh` (built over [`Scene::triangle_corners`]), with `settings` (`radius`,
    /// `alpha`, `prune` and `lambert_lanes` do not apply). Compiles the kernels and uploads
    /// the scene's shading data.
    pub fn new(
        scene: Arc<Scene>,
        bvh: &GpuBvh,
        settings: VcmSettings,
    ) -> Result<GpuBidirectional, GpuRenderError> {
        let plan = match settings.algorithm {
            Algorithm::LightTracing => FramePlan::OnePass(Kernel::LightTracer),
            Algorithm::Bpt => FramePlan::Bidirectional,
            other => {
                return Err(GpuRenderError::Refused(format!(
                    "renders light tracing and bpt of the bidirectional algorithms only so far, \
                     not {}",
                    other.name()
                )));
            }
        };
        let size = (settings.width, settings.height);
        let frames = GpuFrames::new(plan, scene, bvh, size)?;
        Ok(GpuBidirectional { frames, settings })
    }

    /// The settings it renders with.
    pub fn settings(&self) -> &VcmSettings {
        &self.settings
    }
}

impl Integrator for GpuBidirectional {
    integrator_methods_of_frames!("light paths");

    /// Renders iterations `first_sample …` (`samples_per_frame` of them) on the GPU, in
    /// dispatches of consecutive invocations, and adds them to `film`.
    fn render_frame(&mut self, film: &mut Film, first_sample: u32) -> FrameStats {
        let sampling = Sampling::from(&self.settings);
        let light_tracing = self.settings.algorithm == Algorithm::LightTracing;
        let stats = |[closest, light, shadow]: [u64; 3], paths: u64| {
            // Light tracing's camera samples stop at their first hit.
            let (camera, continuation) = if light_tracing {
                (closest, 0)
            } else {
                (paths, closest - paths)
            };
            FrameStats {
                camera_rays: camera,
                continuation_rays: continuation,
                light_rays: light,
                shadow_rays: shadow,
                ..FrameStats::default()
            }
        };
        let name = if light_tracing {
            "light tracing"
        } else {
            "bidirectional path tracing"
        };
        let frames = &mut self.frames;
        frames.render(film, first_sample, (name, &sampling), stats)
    }

    fn decisions(&self) -> Vec<Decision> {
        let kernel = &self.frames.kernels[0];
        let light_tracing = self.settings.algorithm == Algorithm::LightTracing;
        let mut decisions = if light_tracing {
            let reason = "light tracing connects light vertices to the camera only";
            vec![
                Decision::runs(
                    "shading on the GPU",
                    format!(
                        "one WGSL kernel follows each light path to its end, and each camera \
                         sample to its first hit, on {}, adding them to the film on the \
                         device; only the film comes back",
                        kernel.gpu.describe()
                    ),
                ),
                Decision::left_out("light vertex cache", reason),
            ]
        } else {
            vec![
                Decision::runs(
                    "shading on the GPU",
                    format!(
                        "WGSL kernels on {}: the light paths, traced twice (counting their \
                         vertices, then storing them in the cache in the CPU's order), then \
                         the camera paths, adding to the film on the device; only the film \
                         and the vertex counts come back",
                        kernel.gpu.describe()
                    ),
                ),
                Decision::runs("light vertex cache", "camera vertices connect to it"),
            ]
        };
        decisions.push(Decision::runs(
            "light tracing splats",
            "light vertices connect to the camera",
        ));
        let reason = format!("{} does not merge", self.settings.algorithm.name());
        decisions.push(Decision::left_out("merging and hash grid", reason));
        decisions.extend(kernel.plan.decisions());
        decisions
    }
}
