//! The wavefront path tracer: paths advance together, one segment per pass, grouped into
//! batches by a [`Scheduler`].

use std::sync::Arc;

use glam::Vec3;
use rayon::prelude::*;
use vcm_scene::sampling::SampleSequence;
use vcm_scene::{Decision, Scene};
use vcm_scheduler::{SchedulerStats, StopFlag, Tile, Wavefront};
use vcm_traversal::{HitBatch, RayBatch, Traversal};

use crate::camera_rays::jittered_directions;
use crate::error::RenderError;
use crate::film::Film;
use crate::integrator::{
    FrameStats, Integrator, Schedule, check_image_size, frame_cut_short, traversal_failure,
};
use crate::lambert::path_tracing::LambertShading;
use crate::lambert::{LANES_PART, LANES_RUN, LambertLanes};
use crate::memory::{MemoryEstimate, bytes_of, check_render};
use crate::path_state::{PathState, ShadowRay};
use crate::shade::{ShadeContext, shade, vertex_sampler};
use crate::surface_hit::SurfaceHit;
use crate::wave::{fill_extension_rays, for_started_in_lanes, shade_in_parallel, start_paths};

/// What a [`PathTracer`] renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PtSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Seed of every path's random stream.
    pub seed: u64,
    /// How the samples of a pixel relate (default: stratified, [`SampleSequence::Sobol`]).
    pub sequence: SampleSequence,
    /// Longest path in segments (a directly seen light is 1); `None`: unlimited, ended by
    /// Russian roulette only.
    pub max_depth: Option<u32>,
    /// Shade vertices on plain Lambertian surfaces in SIMD lanes where the scene allows it
    /// (where no volume absorbs; the same image bit for bit, faster); `false`:
    /// every vertex goes through the general BSDF, for comparisons.
    pub lambert_lanes: bool,
}

impl PtSettings {
    /// Default settings for a `width` × `height` image: seed 0, stratified samples, paths
    /// ended by Russian roulette only, plain Lambert vertices in lanes.
    pub fn new(width: u32, height: u32) -> PtSettings {
        PtSettings {
            width,
            height,
            seed: 0,
            sequence: SampleSequence::default(),
            max_depth: None,
            lambert_lanes: true,
        }
    }
}

/// Unidirectional path tracer with next event estimation and MIS, run as waves of ray
/// batches over a [`Traversal`] backend, grouped by its [`Schedule`]
/// ([`Integrator::set_schedule`]).
pub struct PathTracer {
    scene: Arc<Scene>,
    traversal: Arc<dyn Traversal>,
    settings: PtSettings,
    /// Shading in SIMD lanes at plain Lambert vertices, or why the scene allows none.
    lambert_lanes: Result<LambertLanes, &'static str>,
    schedule: Schedule,
    /// The schedule of the last frame rendered: its buffers, and the film it rendered into,
    /// have been allocated (`None` before the first frame).
    last_frame: Option<Schedule>,
    last_schedule_stats: SchedulerStats,
    /// Raised to end the frame in progress early ([`Integrator::set_stop`]).
    stop: StopFlag,
}

impl PathTracer {
    /// A path tracer for `scene`, traced with `traversal` (built over
    /// [`Scene::triangle_corners`], primitive id = triangle index), with the default
    /// [`Schedule`].
    pub fn new(
        scene: Arc<Scene>,
        traversal: Arc<dyn Traversal>,
        settings: PtSettings,
    ) -> Result<PathTracer, RenderError> {
        check_image_size(settings.width, settings.height)?;
        let tracer = PathTracer {
            lambert_lanes: LambertLanes::for_scene(&scene, settings.lambert_lanes),
            scene,
            traversal,
            settings,
            schedule: Schedule::default(),
            last_frame: None,
            last_schedule_stats: SchedulerStats::default(),
            stop: StopFlag::new(),
        };
        tracer.check_memory(tracer.schedule, None)?;
        Ok(tracer)
    }

    /// Estimates the memory of a frame with `schedule`, the film it renders into included:
    /// the paths in flight with their rays, hits and shadow rays, and the frame's radiance
    /// samples (twice over with several samples per pixel, which are sorted into a copy).
    fn memory_estimate(&self, schedule: Schedule) -> MemoryEstimate {
        let PtSettings { width, height, .. } = self.settings;
        let samples = schedule.samples_per_frame;
        let pixels = u64::from(width) * u64::from(height);
        let paths = schedule
            .scheduler
            .most_paths_in_flight((width, height), samples);
        let per_path = size_of::<PathState>()
            + 2 * RayBatch::BYTES_PER_RAY
            + HitBatch::BYTES_PER_HIT
            + size_of::<bool>();
        let copies = if samples > 1 { 2 } else { 1 };
        MemoryEstimate::default()
            .with("film", pixels.saturating_mul(Film::BYTES_PER_PIXEL))
            .with("paths in flight", paths.saturating_mul(per_path as u64))
            .with(
                "radiance samples",
                copies * bytes_of::<(u64, Vec3)>(pixels * u64::from(samples)),
            )
    }

    /// Fails when a frame with `schedule` would need more memory than is available, past
    /// what a frame with the `current` schedule allocated already.
    fn check_memory(
        &self,
        schedule: Schedule,
        current: Option<Schedule>,
    ) -> Result<(), RenderError> {
        Ok(check_render(schedule, 1, current, |schedule, _| {
            self.memory_estimate(schedule)
        })?)
    }

    /// The settings this tracer renders with.
    pub fn settings(&self) -> &PtSettings {
        &self.settings
    }

    /// What the scheduler measured in the last frame (worker time, idle time, queue sizes).
    pub fn schedule_stats(&self) -> &SchedulerStats {
        &self.last_schedule_stats
    }
}

impl Integrator for PathTracer {
    /// Renders samples `first_sample …`: `samples_per_frame` paths per pixel, each added to `film`
    /// once it ends, in pixel and sample order whatever the scheduler.
    fn render_frame(&mut self, film: &mut Film, first_sample: u32) -> FrameStats {
        let PtSettings { width, height, .. } = self.settings;
        assert_eq!(
            (film.width(), film.height()),
            (width, height),
            "film size differs from the settings"
        );
        self.last_frame = Some(self.schedule);
        let samples = self.schedule.samples_per_frame;
        let new_wavefront = || PtWavefront {
            scene: &self.scene,
            settings: &self.settings,
            lambert_lanes: self.lambert_lanes.as_ref().ok(),
            first_sample,
            samples,
            stop: &self.stop,
            paths: Vec::new(),
            finished: Vec::new(),
        };
        let (outputs, stats) = vcm_scheduler::run(
            self.schedule.scheduler,
            (width, height),
            self.traversal.as_ref(),
            &self.stop,
            new_wavefront,
        );
        self.last_schedule_stats = stats;
        if frame_cut_short(&self.stop, self.traversal.as_ref()) {
            // Cut short: drop the frame whole, leaving the film as it was.
            return FrameStats::INTERRUPTED;
        }
        // With several samples per pixel, the order of a pixel's additions must not depend
        // on the scheduler; with one, every pixel gets a single addition anyway.
        let finished = if samples > 1 {
            let mut all: Vec<_> = outputs.into_iter().flatten().collect();
            all.par_sort_unstable_by_key(|&(key, _)| key);
            vec![all]
        } else {
            outputs
        };
        film.add_in_bands(|band| {
            for list in &finished {
                band.add_each((list, true), |&(key, radiance)| {
                    ((key / u64::from(samples)) as usize, radiance)
                });
            }
        });
        let camera_rays = u64::from(width) * u64::from(height) * u64::from(samples);
        let traversal_time = stats.traversal_share();
        FrameStats {
            camera_rays,
            continuation_rays: stats.closest_rays - camera_rays,
            shadow_rays: stats.shadow_rays,
            traversal_time,
            shading_time: stats.wall.saturating_sub(traversal_time),
            queue_memory: stats.queue_memory(),
            ..FrameStats::default()
        }
    }

    fn image_size(&self) -> (u32, u32) {
        (self.settings.width, self.settings.height)
    }

    /// Checks that frames with `schedule` fit the available memory, then renders with it.
    fn set_schedule(&mut self, schedule: Schedule) -> Result<(), RenderError> {
        let schedule = schedule.validated()?;
        self.check_memory(schedule, self.last_frame)?;
        self.schedule = schedule;
        Ok(())
    }

    fn set_stop(&mut self, stop: StopFlag) {
        self.stop = stop;
    }

    fn decisions(&self) -> Vec<Decision> {
        let reason = "path tracing neither connects nor merges";
        vec![
            Decision::left_out("light paths", reason),
            Decision::left_out("light vertex cache", reason),
            Decision::left_out("merging and hash grid", reason),
            match &self.lambert_lanes {
                Ok(_) => Decision::runs(LANES_PART, LANES_RUN),
                Err(why) => Decision::left_out(LANES_PART, *why),
            },
        ]
    }

    fn samples_per_frame(&self) -> u32 {
        self.schedule.samples_per_frame
    }

    fn failure(&self) -> Option<String> {
        traversal_failure(self.traversal.as_ref())
    }
}

/// The paths one scheduler worker has in flight, and the results of those that ended, keyed
/// by `pixel · samples + sample`.
struct PtWavefront<'a> {
    scene: &'a Scene,
    settings: &'a PtSettings,
    lambert_lanes: Option<&'a LambertLanes>,
    first_sample: u32,
    samples: u32,
    /// The frame's stop request: shading ends early once it is raised.
    stop: &'a StopFlag,
    paths: Vec<PathState>,
    finished: Vec<(u64, Vec3)>,
}

impl Wavefront for PtWavefront<'_> {
    type Output = Vec<(u64, Vec3)>;

    /// `samples` paths per pixel of `tile`, each through a uniformly jittered point of its
    /// pixel: sample i of the render is sample i of the pixel's sequence keyed by
    /// (seed, pixel).
    fn start(&mut self, tile: Tile) {
        let PtSettings {
            width,
            height,
            seed,
            sequence,
            ..
        } = *self.settings;
        let (first_sample, samples) = (self.first_sample, self.samples);
        let camera = &self.scene.camera;
        let projection = camera.projection(width, height);
        let first_new = self.paths.len();
        start_paths(&mut self.paths, (tile, width), samples, |pixel, sample| {
            let index = u64::from(first_sample + sample);
            let rng = sequence.sampler(&[seed, u64::from(pixel)], index);
            // Aimed below, in lanes.
            PathState::new(pixel, sample, rng, camera.position, Vec3::ZERO)
        });
        for_started_in_lanes(&mut self.paths[first_new..], |paths| {
            let directions =
                jittered_directions(paths, &projection, width, |p| (p.pixel, &p.walk.rng));
            for (path, direction) in paths.iter_mut().zip(directions) {
                path.walk.direction = direction;
                path.walk.rng.skip(1);
            }
        });
    }

    fn active(&self) -> usize {
        self.paths.len()
    }

    fn memory_bytes(&self) -> usize {
        self.paths.capacity() * size_of::<PathState>()
    }

    fn extension_rays(&self, rays: &mut RayBatch) {
        let segments = self.paths.iter().map(|p| (p.walk.origin, p.walk.direction));
        fill_extension_rays(rays, segments);
    }

    /// Shades every path at its hit in parallel and queues the shadow rays in path order.
    fn shade(&mut self, hits: &HitBatch, shadow_rays: &mut RayBatch) {
        let ctx = ShadeContext {
            scene: self.scene,
            max_segments: self.settings.max_depth.unwrap_or(u32::MAX),
        };
        let scene = self.scene;
        let lanes = LambertShading {
            tables: self.lambert_lanes,
            scene,
            max_segments: ctx.max_segments,
        };
        shade_in_parallel(
            &mut self.paths,
            (hits, self.stop),
            vertex_sampler,
            &lanes,
            |_, hit| SurfaceHit::at(scene, hit),
            None::<fn(&_, &mut _, _)>,
            |path, hit| shade(&ctx, path, hit),
        );
        let shadows = self.paths.iter().filter_map(|p| p.shadow.as_ref());
        ShadowRay::fill_batch(shadow_rays, shadows);
    }

    /// Adds the unoccluded shadow contributions and retires the paths that ended, in one
    /// pass over the paths from the last: an ended path's place is taken by the list's last
    /// path, already resolved, so only ended paths cause a move (keeping the list in order
    /// moved every path behind the first that ended: 3.3% of the path tracer's time on the
    /// Cornell box). No result depends on the order: each path draws from its own keyed
    /// numbers, and a frame's film additions are put in key order when a pixel has several.
    fn resolve(&mut self, occluded: &[bool]) {
        let mut blocked = occluded.iter().rev();
        let samples = u64::from(self.samples);
        for i in (0..self.paths.len()).rev() {
            let path = &mut self.paths[i];
            if let Some(shadow) = path.shadow.take()
                && !blocked.next().expect("one test per queued ray")
            {
                path.radiance += shadow.contribution;
            }
            if !path.alive {
                let key = u64::from(path.pixel) * samples + u64::from(path.sample);
                self.finished.push((key, path.radiance));
                self.paths.swap_remove(i);
            }
        }
    }

    fn finish(self) -> Self::Output {
        self.finished
    }
}
