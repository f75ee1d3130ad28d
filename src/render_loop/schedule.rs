//! The schedule of each frame: which scheduler groups its paths into ray batches, and how
//! many samples per pixel it renders, from the options a user gives and, for what they leave
//! out, the backend's preferences (`docs/schedulers.md`).

use vcm::{Schedule, Scheduler};

use super::frames::Frames;
use crate::Backend;

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

/// How the samples per pixel of each frame are chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FrameSizes {
    /// This many in every frame (fewer in a last frame that reaches a budget).
    Fixed(u32),
    /// As many as fit [`Frames::TARGET`], a power of two from 1 up to this many.
    Paced(u32),
}

impl FrameSizes {
    /// Samples per pixel of the first frame (for `Fixed(0)` 0, which every integrator rejects).
    pub fn first(self) -> u32 {
        match self {
            FrameSizes::Fixed(samples) => samples,
            FrameSizes::Paced(_) => 1,
        }
    }
}

/// How frames are scheduled; the image a seed gives does not depend on it. Options left out
/// keep the backend's preferences ([`preferred_scheduler`], [`preferred_frame_sizes`]).
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
    /// options name, else the backend's [preferred one](preferred_scheduler) for that frame
    /// size.
    pub fn schedule_on(&self, backend: Backend, samples_per_frame: u32) -> Schedule {
        Schedule {
            scheduler: self
                .named_scheduler()
                .unwrap_or_else(|| preferred_scheduler(backend, samples_per_frame)),
            samples_per_frame,
        }
    }

    /// The schedule of the first frame on `backend` (what an integrator is set up with, which
    /// also checks the options and the memory they need), of at most `samples_left` samples
    /// per pixel where a render has no more to do: a frame never renders past it.
    pub(super) fn first_schedule_on(
        &self,
        backend: Backend,
        samples_left: Option<u32>,
    ) -> Schedule {
        let first = self.frame_sizes(backend).first();
        self.schedule_on(backend, samples_left.map_or(first, |left| first.min(left)))
    }

    /// How frames are sized on `backend`: `--spp-per-frame` in every frame where given, else
    /// the backend's [preference](preferred_frame_sizes).
    pub fn frame_sizes(&self, backend: Backend) -> FrameSizes {
        self.spp_per_frame
            .map_or_else(|| preferred_frame_sizes(backend), FrameSizes::Fixed)
    }
}

/// Samples per pixel per frame from which the GPU backend prefers tiles.
pub const GPU_TILE_SAMPLES: u32 = 4;

/// The scheduler to run frames of `samples_per_frame` with on `backend` when the user picks
/// none (`docs/schedulers.md`). On the CPU tiles ([`Scheduler::default`]) are fastest at any
/// frame size. On the GPU every traversal call pays a dispatch and two transfers, so a tile's
/// batches must be big: one batch per pass is fastest at one or two samples per frame,
/// 64-pixel tiles from [`GPU_TILE_SAMPLES`] on (H100, 16 threads: 1.1–1.9× over one batch at
/// 4 samples per frame, 2.4–2.5× at 16).
pub fn preferred_scheduler(backend: Backend, samples_per_frame: u32) -> Scheduler {
    match backend {
        Backend::Cpu => Scheduler::default(),
        Backend::Gpu if samples_per_frame >= GPU_TILE_SAMPLES => Scheduler::Tile {
            size: 64,
            merge_below: Scheduler::DEFAULT_MERGE_BELOW,
        },
        Backend::Gpu => Scheduler::None,
    }
}

/// How `backend` sizes frames when the user names no `--spp-per-frame`: one sample per pixel
/// per frame on the CPU (more make no backend faster there and VCM slower,
/// `docs/schedulers.md`), paced frames of up to [`Frames::MOST_PACED`] on the GPU.
pub fn preferred_frame_sizes(backend: Backend) -> FrameSizes {
    match backend {
        Backend::Cpu => FrameSizes::Fixed(1),
        Backend::Gpu => FrameSizes::Paced(Frames::MOST_PACED),
    }
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
        let big = none.schedule_on(Backend::Gpu, GPU_TILE_SAMPLES);
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
            FrameSizes::Paced(Frames::MOST_PACED)
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
