//! Vertex connection and merging (Georgiev et al. 2012) and the algorithms it contains:
//! light tracing, bidirectional path tracing, progressive photon mapping and bidirectional
//! photon mapping, all from one integrator.
//!
//! A frame has two passes, each run as waves of ray batches over a [`Traversal`]:
//! 1. **Light pass**: one light path per pixel. Every non-specular vertex is stored in the
//!    [`LightVertexCache`] and, for the algorithms that use it, connected to the camera (a
//!    light tracing splat). Merging algorithms then build a [`HashGrid`] over the cache.
//! 2. **Camera pass**: one path per pixel. Each non-specular vertex takes a light sample,
//!    connects to `connections` vertices picked uniformly from the whole cache (the
//!    contribution scaled by c = N_v / (N_c · N_p), so that it estimates the same sum as
//!    connecting to all vertices of one light path) and merges with the cached vertices
//!    within the frame's radius.
//!
//! Every technique is weighted by the balance heuristic through the recursive quantities of
//! [`mis`]. Connections to cache vertices are weighted as bidirectional path tracing weights
//! its connections (one per light path); with N_c ≠ N_v / N_p this is still a partition of
//! unity, hence unbiased.

mod camera_pass;
mod light_pass;
pub(crate) mod mis;
mod plan;
mod walk;

use std::sync::Arc;
use std::time::Instant;

use vcm_scene::{Decision, Scene};
use vcm_scheduler::SchedulerStats;
use vcm_traversal::Traversal;

use crate::error::RenderError;
use crate::film::Film;
use crate::hash_grid::HashGrid;
use crate::integrator::{FrameStats, Integrator, Schedule};
use crate::light_vertex_cache::LightVertexCache;
use light_pass::LightPassOutputs;
use mis::MisFactors;
use plan::BidirPlan;

/// Light paths traced by the preprocess that sizes the light vertex cache.
const PREPROCESS_LIGHT_PATHS: u32 = 10_000;

/// Default initial merge radius, as a fraction of the scene's bounding-sphere radius.
pub const DEFAULT_RADIUS_FRACTION: f32 = 0.003;

/// Default radius reduction exponent α of progressive photon mapping.
pub const DEFAULT_ALPHA: f32 = 0.75;

/// The algorithms of the VCM integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Algorithm {
    /// Light tracing: light paths connected to the camera (plus emission seen directly).
    LightTracing,
    /// Bidirectional path tracing: every connection technique, no merging.
    Bpt,
    /// Progressive photon mapping: merging at the first non-specular camera vertex only.
    Ppm,
    /// Bidirectional photon mapping: merging at every camera vertex, no connections; emission
    /// found by the camera path is weighted against the merges (a glossy vertex lit by a
    /// light is found by its own sampling, not only by a light vertex in its lobe).
    Bpm,
    /// Vertex connection and merging: all techniques.
    Vcm,
}

impl Algorithm {
    /// The lower-case short name (lt, bpt, ppm, bpm, vcm).
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::LightTracing => "lt",
            Algorithm::Bpt => "bpt",
            Algorithm::Ppm => "ppm",
            Algorithm::Bpm => "bpm",
            Algorithm::Vcm => "vcm",
        }
    }

    /// Whether camera vertices connect to light samples and light vertices, and light vertices
    /// to the camera.
    pub fn connects(self) -> bool {
        matches!(self, Algorithm::Bpt | Algorithm::Vcm)
    }

    /// Whether camera vertices merge with light vertices (needs the hash grid).
    pub fn merges(self) -> bool {
        matches!(self, Algorithm::Ppm | Algorithm::Bpm | Algorithm::Vcm)
    }

    /// Whether light vertices are splatted onto the image through the camera.
    fn splats(self) -> bool {
        matches!(
            self,
            Algorithm::LightTracing | Algorithm::Bpt | Algorithm::Vcm
        )
    }

    /// Whether light vertices are kept in the cache (for connections or merging).
    fn caches(self) -> bool {
        self.connects() || self.merges()
    }
}

/// What a [`Vcm`] integrator renders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VcmSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Seed of every path's random stream.
    pub seed: u64,
    /// Longest path in segments (a directly seen light is 1); `None`: unlimited.
    pub max_depth: Option<u32>,
    /// Which techniques are used.
    pub algorithm: Algorithm,
    /// N_c, light vertices each camera vertex connects to (≥ 1).
    pub connections: u32,
    /// Merge radius of the first frame, as a fraction of the scene's bounding-sphere radius.
    pub radius_fraction: f32,
    /// Radius reduction: frame i (from 1) merges within r₀ · i^((α − 1) / 2).
    pub alpha: f32,
    /// Leave out what the scene does not need (see [`Integrator::decisions`]); `false` runs every
    /// part of the algorithm, for comparisons.
    pub prune: bool,
}

impl VcmSettings {
    /// Default settings of `algorithm` for a `width` × `height` image.
    pub fn new(algorithm: Algorithm, width: u32, height: u32) -> VcmSettings {
        VcmSettings {
            width,
            height,
            seed: 0,
            max_depth: None,
            algorithm,
            connections: 1,
            radius_fraction: DEFAULT_RADIUS_FRACTION,
            alpha: DEFAULT_ALPHA,
            prune: true,
        }
    }
}

/// What both passes of a frame read.
pub(crate) struct FrameContext<'a> {
    pub scene: &'a Scene,
    pub traversal: &'a dyn Traversal,
    pub settings: &'a VcmSettings,
    /// The frame (seeds the paths).
    pub iteration: u32,
    pub factors: &'a MisFactors,
    /// The parts of the frame that run.
    pub plan: &'a BidirPlan,
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
    plan: BidirPlan,
    base_radius: f32,
    schedule: Schedule,
    cache: LightVertexCache,
    grid: HashGrid,
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
        if settings.connections == 0 {
            return Err(RenderError::InvalidSetting(
                "connections per camera vertex must be at least 1".into(),
            ));
        }
        if !(settings.radius_fraction.is_finite() && settings.radius_fraction > 0.0) {
            return Err(RenderError::InvalidSetting(
                "the merge radius must be a positive number".into(),
            ));
        }
        if !(settings.alpha > 0.0 && settings.alpha <= 1.0) {
            return Err(RenderError::InvalidSetting(
                "alpha must be in (0, 1]".into(),
            ));
        }
        let base_radius = settings.radius_fraction * scene.features.bounds.radius();
        let plan = BidirPlan::new(settings.algorithm, &scene.features, settings.prune);
        let mut vcm = Vcm {
            scene,
            traversal,
            settings,
            plan,
            base_radius,
            schedule: Schedule::default(),
            cache: LightVertexCache::default(),
            grid: HashGrid::default(),
        };
        if plan.cache {
            vcm.cache = LightVertexCache::with_capacity(vcm.estimate_cache_capacity());
        }
        Ok(vcm)
    }

    /// The settings this integrator renders with.
    pub fn settings(&self) -> &VcmSettings {
        &self.settings
    }

    /// The merge radius of frame `iteration` (from 0): r₀ · (iteration + 1)^((α − 1) / 2).
    pub fn radius(&self, iteration: u32) -> f32 {
        let exponent = 0.5 * (self.settings.alpha - 1.0);
        self.base_radius * ((iteration as f32) + 1.0).powf(exponent)
    }

    /// The light vertex cache of the last frame.
    pub fn cache(&self) -> &LightVertexCache {
        &self.cache
    }

    /// The hash grid over the last frame's cache (empty unless the frame merged).
    pub fn grid(&self) -> &HashGrid {
        &self.grid
    }

    /// Traces [`PREPROCESS_LIGHT_PATHS`] light paths (without storing or splatting anything)
    /// and returns the cache capacity they suggest for one frame.
    fn estimate_cache_capacity(&mut self) -> usize {
        let light_paths = self.light_paths();
        let factors = MisFactors::new(false, false, 1.0, 1.0);
        let ctx = FrameContext {
            scene: &self.scene,
            traversal: self.traversal.as_ref(),
            settings: &self.settings,
            iteration: 0,
            factors: &factors,
            plan: &self.plan,
        };
        let scheduler = self.schedule.scheduler;
        let vertices = light_pass::count_vertices(&ctx, scheduler, PREPROCESS_LIGHT_PATHS);
        LightVertexCache::estimate_capacity(
            vertices,
            u64::from(PREPROCESS_LIGHT_PATHS),
            light_paths as u64,
        )
    }

    fn light_paths(&self) -> u32 {
        self.settings.width * self.settings.height
    }
}

impl Integrator for Vcm {
    fn render_frame(&mut self, film: &mut Film, iteration: u32) -> FrameStats {
        let VcmSettings { width, height, .. } = self.settings;
        let plan = self.plan;
        assert_eq!(
            (film.width(), film.height()),
            (width, height),
            "film size differs from the settings"
        );
        let start = Instant::now();
        let radius = self.radius(iteration);
        let light_paths = self.light_paths();
        let factors = MisFactors::new(plan.connects, plan.merges, radius, light_paths as f32);
        let mut stats = FrameStats::default();
        self.cache.clear();
        let outputs = LightPassOutputs {
            cache: plan.cache.then_some(&mut self.cache),
            film: plan.splats.then_some(&mut *film),
        };
        let frame = FrameContext {
            scene: &self.scene,
            traversal: self.traversal.as_ref(),
            settings: &self.settings,
            iteration,
            factors: &factors,
            plan: &plan,
        };
        let scheduler = self.schedule.scheduler;
        if plan.light_paths() {
            light_pass::run(&frame, scheduler, outputs, &mut stats);
        }
        stats.light_vertices = self.cache.len() as u64;
        stats.discarded_light_vertices = self.cache.discarded();

        if plan.merges {
            let grid_start = Instant::now();
            let positions: Vec<_> = self.cache.vertices().iter().map(|v| v.position).collect();
            self.grid = HashGrid::build(&positions, radius);
            stats.grid_build_time = grid_start.elapsed();
        }
        let ctx = camera_pass::CameraContext {
            frame,
            cache: &self.cache,
            grid: &self.grid,
            radius,
        };
        camera_pass::run(&ctx, scheduler, film, &mut stats);
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
        self.plan
            .decisions(self.settings.algorithm, &self.scene.features)
    }

    /// Both passes run under `schedule.scheduler`; one sample per pixel per frame only (the
    /// light vertex cache and the hash grid hold one light path per pixel).
    fn set_schedule(&mut self, schedule: Schedule) -> Result<(), RenderError> {
        let schedule = schedule.validated()?;
        if schedule.samples_per_frame != 1 {
            return Err(RenderError::InvalidSetting(format!(
                "{} renders one sample per pixel per frame so far",
                self.settings.algorithm.name()
            )));
        }
        self.schedule = schedule;
        Ok(())
    }
}

/// Adds a scheduled pass's shadow rays and traversal time (as a share of the wall clock,
/// [`SchedulerStats::traversal_share`]) to `stats`; the caller counts its closest-hit rays by
/// kind.
fn add_scheduled(stats: &mut FrameStats, scheduled: &SchedulerStats) {
    stats.shadow_rays += scheduled.shadow_rays;
    stats.traversal_time += scheduled.traversal_share();
}
