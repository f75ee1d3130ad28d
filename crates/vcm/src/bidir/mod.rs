//! Vertex connection and merging (Georgiev et al. 2012) and the algorithms it contains:
//! light tracing, bidirectional path tracing, progressive photon mapping and bidirectional
//! photon mapping, all from one integrator.
//!
//! An iteration of the algorithm renders one sample per pixel; a frame renders
//! `samples_per_frame` iterations side by side (iteration `first + s` for its sample `s`),
//! each with its own merge radius, light vertex cache and hash grid, in two passes run as
//! waves of ray batches over a [`Traversal`]:
//! 1. **Light pass**: one light path per pixel and sample. Every non-specular vertex is stored
//!    in its iteration's [`LightVertexCache`] and, for the algorithms that use it, connected to
//!    the camera (a light tracing splat). Merging algorithms then build one [`HashGrid`] per
//!    iteration over its cache, the grids in parallel.
//! 2. **Camera pass**: one path per pixel and sample. Each non-specular vertex takes a light
//!    sample, connects to `connections` vertices picked uniformly from its iteration's whole
//!    cache (the contribution scaled by c = N_v / (N_c · N_p), so that it estimates the same
//!    sum as connecting to all vertices of one light path) and merges with that cache's
//!    vertices within the iteration's radius.
//!
//! The film receives each iteration's splats and then its camera samples, iteration after
//! iteration, so a frame of S samples adds exactly what S frames of one sample would.
//!
//! Every technique is weighted by the balance heuristic through the recursive quantities of
//! [`mis`]. Connections to cache vertices are weighted as bidirectional path tracing weights
//! its connections (one per light path); with N_c ≠ N_v / N_p this is still a partition of
//! unity, hence unbiased.

mod camera_pass;
mod light_pass;
mod memory;
pub(crate) mod mis;
pub mod mis_paths;
mod path_order;
mod plan;
mod radius;

use std::sync::Arc;
use std::time::Instant;

use glam::Vec2;
use rayon::prelude::*;

use vcm_scene::sampling::SampleSequence;
use vcm_scene::{Decision, Projection, Scene};
use vcm_scheduler::{SchedulerStats, StopFlag};
use vcm_traversal::Traversal;

use crate::algorithm::Algorithm;
use crate::error::RenderError;
use crate::film::Film;
use crate::hash_grid::HashGrid;
use crate::integrator::{FrameStats, Integrator, Schedule, frame_cut_short, traversal_failure};
use crate::lambert::{LANES_PART, LANES_RUN, LambertLanes};
use crate::light_vertex_cache::LightVertexCache;
use light_pass::ResultBuffers;
use mis::MisFactors;
pub use plan::BidirPlan;
pub use radius::{DEFAULT_RADIUS_FRACTION, DEFAULT_RADIUS_PIXELS, MergeRadius, merge_radius};

/// Light paths traced by the preprocess that sizes the light vertex cache.
const PREPROCESS_LIGHT_PATHS: u32 = 10_000;

/// Most light vertices a camera vertex may connect to (N_c): each connection is a shadow ray
/// held with its path, and a pass's waves must stay short enough to honour a stop request
/// within about a second.
pub const MAX_CONNECTIONS: u32 = 1024;

/// Most light paths per pixel an iteration traces ([`VcmSettings::light_paths_per_pixel`]);
/// the fewest is its inverse.
pub const MAX_LIGHT_PATHS_PER_PIXEL: f32 = 16.0;

/// `n`, where it is a number of light paths per pixel an iteration can trace (1 /
/// [`MAX_LIGHT_PATHS_PER_PIXEL`] to [`MAX_LIGHT_PATHS_PER_PIXEL`]); else why not.
pub fn light_paths_per_pixel(n: f32) -> Result<f32, String> {
    let most = MAX_LIGHT_PATHS_PER_PIXEL;
    if (1.0 / most..=most).contains(&n) {
        Ok(n)
    } else {
        Err(format!(
            "expected a number of light paths per pixel from 1/{most} to {most}, not {n}"
        ))
    }
}

/// Default radius reduction exponent α of progressive photon mapping.
pub const DEFAULT_ALPHA: f32 = 0.75;

/// What a [`Vcm`] integrator renders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VcmSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Seed of every path's random stream.
    pub seed: u64,
    /// How the iterations' camera paths through a pixel, and an iteration's light paths,
    /// relate (default: stratified, [`SampleSequence::Sobol`]).
    pub sequence: SampleSequence,
    /// Longest path in segments (a directly seen light is 1); `None`: unlimited.
    pub max_depth: Option<u32>,
    /// Which techniques are used: any algorithm but [`Algorithm::Pt`].
    pub algorithm: Algorithm,
    /// N_c, light vertices each camera vertex connects to (1 to [`MAX_CONNECTIONS`]).
    pub connections: u32,
    /// Light paths each iteration traces per pixel of the image (1 / [`MAX_LIGHT_PATHS_PER_PIXEL`]
    /// to [`MAX_LIGHT_PATHS_PER_PIXEL`]; default 1): N_p = width · round(height · this),
    /// at least one row ([`VcmSettings::light_paths`]). More light paths per camera path
    /// lower relMSE where merging carries dim parts of the image, at a cost in the bright
    /// ones (docs/algorithms.md, "Light paths per iteration").
    pub light_paths_per_pixel: f32,
    /// How the first iteration's merge radius is chosen.
    pub radius: MergeRadius,
    /// Radius reduction: frame i (from 1) merges within r₀ · i^((α − 1) / 2).
    pub alpha: f32,
    /// Leave out what the scene does not need (see [`Integrator::decisions`]); `false` runs every
    /// part of the algorithm, for comparisons.
    pub prune: bool,
    /// Shade light vertices, and the camera vertices of BPT and VCM, on plain Lambertian
    /// surfaces in SIMD lanes where the scene allows it (where no volume absorbs; the same
    /// image bit for bit, faster); `false`: every vertex goes through the general BSDF, for
    /// comparisons.
    pub lambert_lanes: bool,
}

impl VcmSettings {
    /// Default settings of `algorithm` for a `width` × `height` image.
    pub fn new(algorithm: Algorithm, width: u32, height: u32) -> VcmSettings {
        VcmSettings {
            width,
            height,
            seed: 0,
            sequence: SampleSequence::default(),
            max_depth: None,
            algorithm,
            connections: 1,
            light_paths_per_pixel: 1.0,
            radius: MergeRadius::default(),
            alpha: DEFAULT_ALPHA,
            prune: true,
            lambert_lanes: true,
        }
    }

    /// The grid whose cells name an iteration's light paths (path index = y · width + x):
    /// the image's width by round(height · [`VcmSettings::light_paths_per_pixel`]) rows, at
    /// least one.
    pub fn light_path_grid(&self) -> (u32, u32) {
        let rows = (self.height as f32 * self.light_paths_per_pixel).round();
        (self.width, (rows as u32).max(1))
    }

    /// N_p, the light paths each iteration traces.
    pub fn light_paths(&self) -> u64 {
        let (width, rows) = self.light_path_grid();
        u64::from(width) * u64::from(rows)
    }

    /// Fails, saying why, where the settings name no bidirectional algorithm or an invalid
    /// number of connections or of light paths, merge radius or α.
    pub fn check(&self) -> Result<(), RenderError> {
        if !self.algorithm.is_bidirectional() {
            return Err(RenderError::InvalidSetting(
                "path tracing is the path tracer's (`PathTracer`), not the VCM integrator's".into(),
            ));
        }
        if !(1..=MAX_CONNECTIONS).contains(&self.connections) {
            return Err(RenderError::InvalidSetting(format!(
                "connections per camera vertex must be 1 to {MAX_CONNECTIONS} (asked for {})",
                self.connections
            )));
        }
        light_paths_per_pixel(self.light_paths_per_pixel).map_err(RenderError::InvalidSetting)?;
        if self.light_paths() > u64::from(u32::MAX) {
            return Err(RenderError::InvalidSetting(format!(
                "{} light paths per iteration are more than 2³² − 1: fewer per pixel, or a \
                 smaller image",
                self.light_paths()
            )));
        }
        self.radius
            .validated()
            .map_err(RenderError::InvalidSetting)?;
        if !(self.alpha > 0.0 && self.alpha <= 1.0) {
            return Err(RenderError::InvalidSetting(
                "alpha must be in (0, 1]".into(),
            ));
        }
        Ok(())
    }
}

/// What both passes read about one iteration (one sample per pixel) of a frame.
pub(crate) struct FrameContext<'a> {
    pub scene: &'a Scene,
    pub traversal: &'a dyn Traversal,
    pub settings: &'a VcmSettings,
    /// The camera's projection onto the image.
    pub projection: &'a Projection,
    /// The iteration, counted over the whole render (seeds the paths).
    pub iteration: u64,
    /// The iteration's merge radius.
    pub radius: f32,
    pub factors: MisFactors,
    /// The parts of the frame that run.
    pub plan: &'a BidirPlan,
    /// Shading in SIMD lanes at plain Lambert vertices, where the scene allows it.
    pub lanes: Option<&'a LambertLanes>,
    /// Ends the passes early when raised (the frame is then dropped).
    pub stop: &'a StopFlag,
}

impl FrameContext<'_> {
    /// Longest path in segments (`u32::MAX`: unlimited).
    fn max_segments(&self) -> u32 {
        self.settings.max_depth.unwrap_or(u32::MAX)
    }
}

/// The VCM integrator (and its sub-algorithms, see [`Algorithm`]).
pub struct Vcm {
    scene: Arc<Scene>,
    traversal: Arc<dyn Traversal>,
    settings: VcmSettings,
    /// The camera's projection onto the image.
    projection: Projection,
    plan: BidirPlan,
    /// r₀, the first iteration's merge radius (world units), and how it was found; `None`
    /// where the frames do not merge (no camera rays are traced to measure it).
    first_radius: Option<(f32, String)>,
    schedule: Schedule,
    /// The schedule of the last frame rendered: its buffers, and the film it rendered into,
    /// have been allocated (`None` before the first frame).
    last_frame: Option<Schedule>,
    /// Capacity of each iteration's cache, from the preprocess (0 without a cache).
    cache_capacity: usize,
    /// One light vertex cache per sample of a frame.
    caches: Vec<LightVertexCache>,
    /// One hash grid per sample of a frame (empty unless the frame merged).
    grids: Vec<HashGrid>,
    /// The light pass workers' result lists, reused from frame to frame.
    light_buffers: ResultBuffers,
    /// Shading in SIMD lanes at plain Lambert vertices, or why the scene allows none.
    lambert_lanes: Result<LambertLanes, &'static str>,
    /// Raised to end the frame in progress early ([`Integrator::set_stop`]).
    stop: StopFlag,
}

impl Vcm {
    /// The integrator for `scene`, traced with `traversal` (built over
    /// [`Scene::triangle_corners`]). Sizes the light vertex cache with a preprocess of
    /// 10,000 light paths when the algorithm uses the cache.
    pub fn new(
        scene: Arc<Scene>,
        traversal: Arc<dyn Traversal>,
        settings: VcmSettings,
    ) -> Result<Vcm, RenderError> {
        let VcmSettings { width, height, .. } = settings;
        crate::integrator::check_image_size(width, height)?;
        settings.check()?;
        let plan = BidirPlan::new(settings.algorithm, &scene.features, settings.prune);
        let projection = scene.camera.projection(width, height);
        let size = Vec2::new(width as f32, height as f32);
        let first_radius = plan.merges.then(|| {
            let view = (&projection, size);
            settings.radius.initial(&scene, traversal.as_ref(), view)
        });
        let mut vcm = Vcm {
            projection,
            lambert_lanes: LambertLanes::for_scene(&scene, settings.lambert_lanes),
            scene,
            traversal,
            settings,
            plan,
            first_radius,
            schedule: Schedule::default(),
            last_frame: None,
            cache_capacity: 0,
            caches: Vec::new(),
            grids: Vec::new(),
            light_buffers: ResultBuffers::default(),
            stop: StopFlag::new(),
        };
        if plan.cache {
            vcm.cache_capacity = vcm.estimate_cache_capacity();
        }
        vcm.check_memory(vcm.schedule, None)?;
        vcm.size_buffers();
        Ok(vcm)
    }

    /// The settings this integrator renders with.
    pub fn settings(&self) -> &VcmSettings {
        &self.settings
    }

    /// The merge radius of iteration `iteration` (from 0; frame f of S samples per pixel
    /// renders iterations f · S to f · S + S − 1): r₀ · (iteration + 1)^((α − 1) / 2); 0
    /// where the frames do not merge.
    pub fn radius(&self, iteration: u64) -> f32 {
        let r0 = self.first_radius.as_ref().map_or(0.0, |(r0, _)| *r0);
        merge_radius(r0, self.settings.alpha, iteration)
    }

    /// The light vertex caches of the last frame, one per sample per pixel (each empty, with
    /// no capacity, when the algorithm keeps no cache).
    pub fn caches(&self) -> &[LightVertexCache] {
        &self.caches
    }

    /// The hash grids over the last frame's caches (each empty unless the frame merged).
    pub fn grids(&self) -> &[HashGrid] {
        &self.grids
    }

    /// Keeps one cache (of the preprocess's capacity) and one grid per sample of a frame.
    fn size_buffers(&mut self) {
        let samples = self.schedule.samples_per_frame as usize;
        let capacity = self.cache_capacity;
        self.caches
            .resize_with(samples, || LightVertexCache::with_capacity(capacity));
        self.grids.resize_with(samples, HashGrid::default);
    }

    /// The contexts of the frame's iterations, one per sample per pixel, from
    /// `first_sample` on.
    fn iterations(&self, first_sample: u32) -> Vec<FrameContext<'_>> {
        let samples = self.schedule.samples_per_frame;
        let light_paths = self.light_paths() as f32;
        (0..samples)
            .map(|sample| {
                let iteration = u64::from(first_sample) + u64::from(sample);
                let radius = self.radius(iteration);
                FrameContext {
                    scene: &self.scene,
                    traversal: self.traversal.as_ref(),
                    settings: &self.settings,
                    projection: &self.projection,
                    iteration,
                    radius,
                    factors: MisFactors::new(
                        self.plan.connects,
                        self.plan.merges,
                        radius,
                        light_paths,
                    ),
                    plan: &self.plan,
                    lanes: self.lambert_lanes.as_ref().ok(),
                    stop: &self.stop,
                }
            })
            .collect()
    }

    /// Traces [`PREPROCESS_LIGHT_PATHS`] light paths (without storing or splatting anything)
    /// and returns the cache capacity they suggest for one frame.
    fn estimate_cache_capacity(&mut self) -> usize {
        let light_paths = self.light_paths();
        let ctx = FrameContext {
            scene: &self.scene,
            traversal: self.traversal.as_ref(),
            settings: &self.settings,
            projection: &self.projection,
            iteration: 0,
            radius: 1.0,
            factors: MisFactors::new(false, false, 1.0, 1.0),
            plan: &self.plan,
            lanes: self.lambert_lanes.as_ref().ok(),
            // The preprocess always runs to its end.
            stop: &StopFlag::new(),
        };
        let scheduler = self.schedule.scheduler;
        let vertices = light_pass::count_vertices(ctx, scheduler, PREPROCESS_LIGHT_PATHS);
        LightVertexCache::estimate_capacity(
            vertices,
            u64::from(PREPROCESS_LIGHT_PATHS),
            light_paths as u64,
        )
    }

    /// Ends a frame that a stop request or a failed traversal cut short, leaving the film as
    /// it was and keeping the frame's buffers for the next.
    fn drop_frame(
        &mut self,
        light: Vec<light_pass::LightResults>,
        caches: Vec<LightVertexCache>,
        grids: Vec<HashGrid>,
    ) -> FrameStats {
        self.light_buffers.recycle(light);
        (self.caches, self.grids) = (caches, grids);
        FrameStats::INTERRUPTED
    }

    fn light_paths(&self) -> u32 {
        self.settings.light_paths() as u32
    }
}

impl Integrator for Vcm {
    /// Renders iterations `first_sample …`: `samples_per_frame` iterations of the algorithm
    /// at once.
    fn render_frame(&mut self, film: &mut Film, first_sample: u32) -> FrameStats {
        let VcmSettings { width, height, .. } = self.settings;
        let plan = self.plan;
        assert_eq!(
            (film.width(), film.height()),
            (width, height),
            "film size differs from the settings"
        );
        let start = Instant::now();
        self.last_frame = Some(self.schedule);
        let mut stats = FrameStats::default();
        let scheduler = self.schedule.scheduler;
        let mut caches = std::mem::take(&mut self.caches);
        let mut grids = std::mem::take(&mut self.grids);
        let iterations = self.iterations(first_sample);
        let mut light = if plan.light_paths() {
            let buffers = &self.light_buffers;
            light_pass::run(&iterations, scheduler, plan.splats, buffers, &mut stats)
        } else {
            Vec::new()
        };
        if frame_cut_short(&self.stop, self.traversal.as_ref()) {
            return self.drop_frame(light, caches, grids);
        }
        if plan.cache {
            for (cache, results) in caches.iter_mut().zip(&mut light) {
                cache.clear();
                cache.extend(results.vertices());
                stats.light_vertices += cache.len() as u64;
                stats.discarded_light_vertices += cache.discarded();
            }
        }
        if plan.merges {
            let grid_start = Instant::now();
            grids = caches
                .par_iter()
                .zip(&iterations)
                .map(|(cache, ctx)| {
                    // Only the vertices that merge: in VCM not a light path's first.
                    let shortest = ctx.factors.shortest_merged();
                    let (positions, indices): (Vec<_>, Vec<_>) = (cache.vertices().iter())
                        .zip(0u32..)
                        .filter(|(vertex, _)| vertex.path_length.get() >= shortest)
                        .map(|(vertex, i)| (vertex.position, i))
                        .unzip();
                    HashGrid::build_over(&positions, &indices, ctx.radius)
                })
                .collect();
            stats.grid_build_time = grid_start.elapsed();
        }
        let samples: Vec<_> = iterations
            .into_iter()
            .zip(caches.iter().zip(&grids))
            .map(|(frame, (cache, grid))| camera_pass::CameraContext { frame, cache, grid })
            .collect();
        let camera = camera_pass::run(&samples, scheduler, &mut stats);
        if frame_cut_short(&self.stop, self.traversal.as_ref()) {
            return self.drop_frame(light, caches, grids);
        }
        film.add_in_bands(|band| {
            for (sample, radiance) in camera.iter().enumerate() {
                if let Some(results) = light.get(sample).filter(|_| plan.splats) {
                    band.add_each((&results.splats, false), |&(_, pixel, contribution)| {
                        (pixel as usize, contribution)
                    });
                }
                band.add_each((radiance, true), |&(pixel, radiance)| {
                    (pixel as usize, radiance)
                });
            }
        });
        self.light_buffers.recycle(light);
        (self.caches, self.grids) = (caches, grids);
        stats.shading_time = start
            .elapsed()
            .saturating_sub(stats.traversal_time + stats.grid_build_time);
        stats
    }

    fn image_size(&self) -> (u32, u32) {
        (self.settings.width, self.settings.height)
    }

    /// Light paths, the light vertex cache, light tracing splats, merging and the hash grid.
    fn decisions(&self) -> Vec<Decision> {
        let mut decisions = self
            .plan
            .decisions(self.settings.algorithm, &self.scene.features);
        decisions.push(match &self.lambert_lanes {
            Ok(_) => Decision::runs(LANES_PART, LANES_RUN),
            Err(why) => Decision::left_out(LANES_PART, *why),
        });
        if let Some((r0, how)) = &self.first_radius {
            let reason = format!("r₀ = {r0} world units: {how}");
            decisions.push(Decision::runs("merge radius", reason));
        }
        decisions
    }

    fn set_stop(&mut self, stop: StopFlag) {
        self.stop = stop;
    }

    /// Both passes run under `schedule.scheduler`; `schedule.samples_per_frame` iterations
    /// per frame, each with its own cache and grid.
    /// Checks that frames with `schedule` fit the available memory first.
    fn set_schedule(&mut self, schedule: Schedule) -> Result<(), RenderError> {
        let schedule = schedule.validated()?;
        self.check_memory(schedule, self.last_frame)?;
        self.schedule = schedule;
        self.size_buffers();
        Ok(())
    }

    fn samples_per_frame(&self) -> u32 {
        self.schedule.samples_per_frame
    }

    fn failure(&self) -> Option<String> {
        traversal_failure(self.traversal.as_ref())
    }
}

/// Adds a scheduled pass's shadow rays and traversal time (as a share of the wall clock,
/// [`SchedulerStats::traversal_share`]) to `stats`; the caller counts its closest-hit rays by
/// kind.
fn add_scheduled(stats: &mut FrameStats, scheduled: &SchedulerStats) {
    stats.shadow_rays += scheduled.shadow_rays;
    stats.traversal_time += scheduled.traversal_share();
    stats.queue_memory = stats.queue_memory.max(scheduled.queue_memory());
}
