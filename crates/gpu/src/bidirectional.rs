//! [`GpuBidirectional`]: the bidirectional algorithms (light tracing, BPT, PPM, BPM, VCM)
//! with their kernels, as an [`Integrator`].

use std::sync::Arc;

use glam::Vec2;
use vcm::{Algorithm, BidirPlan, Film, FrameStats, Integrator, VcmSettings};
use vcm_scene::{Decision, Scene};
use vcm_traversal_wgpu::GpuBvh;

use crate::error::GpuRenderError;
use crate::frames::{BidirFrames, FramePlan, GpuFrames, integrator_methods_of_frames};
use crate::kernel::Sampling;

/// A bidirectional algorithm with every path shaded on the GPU: each iteration (one sample per
/// pixel) traces one light path per pixel and one camera sample per pixel — for light tracing
/// its first hit, which finds the lights seen directly, and the light vertices connect to the
/// camera; for the others a whole camera path, which samples lights and connects to
/// `connections` light vertices of its iteration picked uniformly (BPT, VCM) and merges with
/// those within the iteration's radius (PPM, BPM, VCM), all weighted by MIS. Everything is
/// added to the film on the device. The same image as the CPU's [`vcm::Vcm`] with the same
/// settings, up to floating-point rounding per path. Renders the scenes
/// [`check_scene`](crate::check_scene) accepts.
pub struct GpuBidirectional {
    frames: GpuFrames,
    settings: VcmSettings,
    /// The parts that run on this scene.
    plan: BidirPlan,
    /// r₀ and how it was found, where the frames merge.
    first_radius: Option<(f32, String)>,
}

impl GpuBidirectional {
    /// The algorithms it renders: every bidirectional one.
    pub const ALGORITHMS: [Algorithm; 5] = [
        Algorithm::LightTracing,
        Algorithm::Bpt,
        Algorithm::Ppm,
        Algorithm::Bpm,
        Algorithm::Vcm,
    ];

    /// `settings.algorithm` (one of [`GpuBidirectional::ALGORITHMS`]) for `scene` on the
    /// hierarchy `bvh` (built over [`Scene::triangle_corners`]), with `settings`
    /// (`lambert_lanes` does not apply). Finds the first merge radius as the CPU does,
    /// compiles the kernels and uploads the scene's shading data.
    pub fn new(
        scene: Arc<Scene>,
        bvh: &GpuBvh,
        settings: VcmSettings,
    ) -> Result<GpuBidirectional, GpuRenderError> {
        settings.check()?;
        let algorithm = settings.algorithm;
        let (width, height) = (settings.width, settings.height);
        vcm::check_image_size(width, height)?;
        let plan = BidirPlan::new(algorithm, &scene.features, settings.prune);
        // r₀ as the CPU finds it, from camera rays through the GPU backend's hierarchy.
        let first_radius = plan.merges.then(|| {
            let projection = scene.camera.projection(width, height);
            let size = Vec2::new(width as f32, height as f32);
            settings.radius.initial(&scene, bvh, (&projection, size))
        });
        let bidir = BidirFrames {
            algorithm,
            plan,
            first_radius: first_radius.as_ref().map_or(0.0, |(r0, _)| *r0),
            alpha: settings.alpha,
            // Checked to fit 32 bits (`VcmSettings::check`).
            light_paths: settings.light_paths() as u32,
        };
        let frames = GpuFrames::new(FramePlan::Bidirectional(bidir), scene, bvh, (width, height))?;
        Ok(GpuBidirectional {
            frames,
            settings,
            plan,
            first_radius,
        })
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
        let sampling = Sampling::of_bidir(&self.settings, &self.plan);
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

    /// Where the paths are shaded, then the CPU's decisions of the algorithm's parts.
    fn decisions(&self) -> Vec<Decision> {
        let kernel = &self.frames.kernels[0];
        let algorithm = self.settings.algorithm;
        let how = if algorithm == Algorithm::LightTracing {
            "one WGSL kernel follows each light path to its end, and each camera sample to its \
             first hit"
                .to_string()
        } else {
            let grids = if self.plan.merges {
                ", the hash grids built over it"
            } else {
                ""
            };
            format!(
                "WGSL kernels trace the light paths (counting their vertices and keeping \
                 the first few), store them in the cache in the CPU's order, tracing again \
                 the paths with more{grids}, then the camera paths"
            )
        };
        let mut decisions = vec![Decision::runs(
            "shading on the GPU",
            format!(
                "{how} on {}, adding to the film on the device; only the film and each \
                 iteration's vertex count come back",
                kernel.gpu.describe()
            ),
        )];
        decisions.extend(self.plan.decisions(algorithm, &kernel.scene.features));
        if let Some((r0, how)) = &self.first_radius {
            let reason = format!("r₀ = {r0} world units: {how}");
            decisions.push(Decision::runs("merge radius", reason));
        }
        decisions.extend(kernel.plan.decisions());
        decisions
    }
}
