//! The light transport algorithms, their options and one builder for any of them, shared by
//! `vcm render`, `vcm convergence` and the viewer.

use std::sync::Arc;

use crate::Backend;
use crate::frames::FrameSizes;
pub use vcm::Algorithm;
use vcm::{
    DEFAULT_ALPHA, DEFAULT_RADIUS_FRACTION, Integrator, PathTracer, PtSettings, RenderError,
    Schedule, Scheduler, Vcm, VcmSettings,
};
use vcm_scene::sampling::SampleSequence;
use vcm_scene::{Scene, ShadingPlan};
use vcm_traversal::Traversal;

/// How the samples of a pixel relate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum SamplerKind {
    /// Stratified: the points of an Owen-scrambled Sobol sequence per pixel (and per frame's
    /// light paths), which lowers the error at the same sample count.
    #[default]
    Sobol,
    /// Independent random numbers for every sample.
    Independent,
}

impl SamplerKind {
    fn sequence(self) -> SampleSequence {
        match self {
            SamplerKind::Sobol => SampleSequence::Sobol,
            SamplerKind::Independent => SampleSequence::Independent,
        }
    }
}

/// Options of every integrator.
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct IntegratorOptions {
    /// Seed of all random numbers: a render is a pure function of scene, settings and seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// How the samples of a pixel relate: stratified (sobol) or independent.
    #[arg(long, value_enum, default_value_t = SamplerKind::Sobol)]
    pub sampler: SamplerKind,
    /// Maximum path length in segments (a directly seen light is 1); default unlimited with
    /// Russian roulette.
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Light vertices each camera vertex connects to (bpt, vcm; 1 to 1024).
    #[arg(long, default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(vcm::MAX_CONNECTIONS)))]
    pub connections: u32,
    /// Initial merge radius as a fraction of the scene's bounding-sphere radius (ppm, bpm, vcm).
    #[arg(long, default_value_t = DEFAULT_RADIUS_FRACTION, allow_negative_numbers = true)]
    pub radius: f32,
    /// Radius reduction exponent: frame i merges within r₀ · i^((α − 1) / 2) (ppm, bpm, vcm).
    #[arg(long, default_value_t = DEFAULT_ALPHA, allow_negative_numbers = true)]
    pub alpha: f32,
    /// Run every part of the algorithm and of shading, even those the scene does not need
    /// (`vcm render --explain` lists them); the image's expectation is the same.
    #[arg(long)]
    pub no_prune: bool,
}

impl IntegratorOptions {
    /// The shading plan renders with these options use on `scene`: every part with
    /// `--no-prune`, else the scene's own.
    pub fn shading_plan(&self, scene: &Scene) -> ShadingPlan {
        if self.no_prune {
            ShadingPlan::FULL
        } else {
            scene.shading
        }
    }
}

impl Default for IntegratorOptions {
    fn default() -> Self {
        IntegratorOptions {
            seed: 0,
            sampler: SamplerKind::Sobol,
            max_depth: None,
            connections: 1,
            radius: DEFAULT_RADIUS_FRACTION,
            alpha: DEFAULT_ALPHA,
            no_prune: false,
        }
    }
}

/// How paths are grouped into batches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SchedulerKind {
    /// One batch of all active paths per pass.
    None,
    /// Worker threads trace tiles to completion, merging in the next tile when few paths
    /// are left.
    Tile,
    /// A pool of queues over tiles: one thread submits every traversal while the others
    /// shade, so shading overlaps GPU traversal.
    Queue,
}

/// How frames are scheduled; the image a seed gives does not depend on it. Options left out
/// keep the integrator's own schedule (tiles of 32 pixels, one sample per pixel per frame).
#[derive(clap::Args, Clone, Copy, Debug, Default, PartialEq)]
pub struct ScheduleOptions {
    /// How paths are grouped into batches (default tile).
    #[arg(long, value_enum)]
    pub scheduler: Option<SchedulerKind>,
    /// Tile side in pixels (--scheduler tile or queue; default 32).
    #[arg(long)]
    pub tile_size: Option<u32>,
    /// Fraction of a tile's paths below which a worker or queue merges in the next tile
    /// (--scheduler tile or queue; 0 disables merging; default 0.5).
    #[arg(long)]
    pub tile_merge: Option<f32>,
    /// Queues in the pool, which bounds the paths in flight (--scheduler queue; default
    /// threads + 1: one per shading thread and one being traversed).
    #[arg(long)]
    pub queues: Option<usize>,
    /// Samples per pixel each frame renders (default: 1 on the CPU backend; on the GPU as
    /// many as keep a frame within a second, up to 16).
    #[arg(long)]
    pub spp_per_frame: Option<u32>,
}

impl ScheduleOptions {
    /// The scheduler these options name: `--scheduler`, or tiles where only a tile option is
    /// given; `None` where they name neither.
    fn named_scheduler(&self) -> Option<Scheduler> {
        let size = self.tile_size.unwrap_or(Scheduler::DEFAULT_TILE_SIZE);
        let merge_below = self.tile_merge.unwrap_or(Scheduler::DEFAULT_MERGE_BELOW);
        let tiles = Scheduler::Tile { size, merge_below };
        match self.scheduler {
            Some(SchedulerKind::None) => Some(Scheduler::None),
            Some(SchedulerKind::Tile) => Some(tiles),
            Some(SchedulerKind::Queue) => Some(Scheduler::Queue {
                queues: self.queues.unwrap_or_else(Scheduler::default_queues),
                size,
                merge_below,
            }),
            None => (self.tile_size.is_some() || self.tile_merge.is_some()).then_some(tiles),
        }
    }

    /// The schedule of a frame of `samples_per_frame` on `backend`: the scheduler these
    /// options name, else the backend's [preferred one](Backend::preferred_scheduler) for
    /// that frame size.
    pub fn schedule_on(&self, backend: Backend, samples_per_frame: u32) -> Schedule {
        Schedule {
            scheduler: self
                .named_scheduler()
                .unwrap_or_else(|| backend.preferred_scheduler(samples_per_frame)),
            samples_per_frame,
        }
    }

    /// The schedule of the first frame on `backend` (what an integrator is set up with, which
    /// also checks the options and the memory they need), of at most `samples_left` samples
    /// per pixel where a render has no more to do: a frame never renders past it.
    pub fn first_schedule_on(&self, backend: Backend, samples_left: Option<u32>) -> Schedule {
        let first = self.frame_sizes(backend).first();
        self.schedule_on(backend, samples_left.map_or(first, |left| first.min(left)))
    }

    /// How frames are sized on `backend`: `--spp-per-frame` in every frame where given, else
    /// the backend's [preference](Backend::preferred_frame_sizes).
    pub fn frame_sizes(&self, backend: Backend) -> FrameSizes {
        self.spp_per_frame
            .map_or_else(|| backend.preferred_frame_sizes(), FrameSizes::Fixed)
    }
}

/// The integrator of `algorithm` for a `width` × `height` image. With `options.no_prune`
/// it renders a copy of the scene whose shading runs every part ([`ShadingPlan::FULL`]),
/// every vertex through the general BSDF (no SIMD lanes).
pub fn build(
    algorithm: Algorithm,
    scene: &Arc<Scene>,
    traversal: Arc<dyn Traversal>,
    (width, height): (u32, u32),
    options: &IntegratorOptions,
) -> Result<Box<dyn Integrator>, RenderError> {
    let shading = options.shading_plan(scene);
    let scene = if shading != scene.shading {
        Arc::new(Scene {
            shading,
            ..Scene::clone(scene)
        })
    } else {
        Arc::clone(scene)
    };
    Ok(match algorithm {
        Algorithm::Pt => {
            let settings = PtSettings {
                seed: options.seed,
                sequence: options.sampler.sequence(),
                max_depth: options.max_depth,
                lambert_lanes: !options.no_prune,
                ..PtSettings::new(width, height)
            };
            Box::new(PathTracer::new(scene, traversal, settings)?)
        }
        bidirectional => {
            let settings = VcmSettings {
                seed: options.seed,
                sequence: options.sampler.sequence(),
                max_depth: options.max_depth,
                connections: options.connections,
                radius_fraction: options.radius,
                alpha: options.alpha,
                prune: !options.no_prune,
                lambert_lanes: !options.no_prune,
                ..VcmSettings::new(bidirectional, width, height)
            };
            Box::new(Vcm::new(scene, traversal, settings)?)
        }
    })
}

/// The image size: `width`, and `height` or else the one the camera's aspect ratio gives
/// (square without one).
pub fn image_size(scene: &Scene, width: u32, height: Option<u32>) -> (u32, u32) {
    let height = height.unwrap_or_else(|| {
        let aspect = scene.camera.aspect_ratio.unwrap_or(1.0);
        ((width as f32 / aspect).round() as u32).max(1)
    });
    (width, height)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_backend_picks_the_scheduler_only_where_the_options_name_none() {
        let none = ScheduleOptions::default();
        assert_eq!(none.schedule_on(Backend::Cpu, 1), Schedule::default());
        assert_eq!(none.schedule_on(Backend::Gpu, 1), Schedule::ONE_BATCH);
        // The GPU takes tiles once frames are big enough to fill their batches.
        let big = none.schedule_on(Backend::Gpu, Backend::GPU_TILE_SAMPLES);
        assert!(matches!(big.scheduler, Scheduler::Tile { size: 64, .. }));
        let one_batch = ScheduleOptions {
            scheduler: Some(SchedulerKind::None),
            ..ScheduleOptions::default()
        };
        assert_eq!(
            one_batch.schedule_on(Backend::Gpu, 16),
            Schedule {
                scheduler: Scheduler::None,
                samples_per_frame: 16
            }
        );
        let tiles = ScheduleOptions {
            tile_size: Some(48),
            ..ScheduleOptions::default()
        };
        assert!(matches!(
            tiles.schedule_on(Backend::Gpu, 1).scheduler,
            Scheduler::Tile { size: 48, .. }
        ));
        assert_eq!(
            one_batch.schedule_on(Backend::Cpu, 1).scheduler,
            Scheduler::None
        );
    }

    #[test]
    fn frames_are_paced_on_the_gpu_unless_the_options_fix_their_size() {
        let none = ScheduleOptions::default();
        assert_eq!(none.frame_sizes(Backend::Cpu), FrameSizes::Fixed(1));
        assert_eq!(
            none.frame_sizes(Backend::Gpu),
            FrameSizes::Paced(crate::frames::Frames::MOST_PACED)
        );
        let four = ScheduleOptions {
            spp_per_frame: Some(4),
            ..ScheduleOptions::default()
        };
        for backend in Backend::ALL {
            assert_eq!(four.frame_sizes(*backend), FrameSizes::Fixed(4));
        }
    }

    #[test]
    fn the_first_frame_never_renders_past_the_samples_left() {
        let many = ScheduleOptions {
            spp_per_frame: Some(100_000),
            ..ScheduleOptions::default()
        };
        let first = |left| many.first_schedule_on(Backend::Cpu, left).samples_per_frame;
        assert_eq!(first(Some(1)), 1);
        assert_eq!(first(Some(300_000)), 100_000);
        assert_eq!(first(None), 100_000);
    }
}
