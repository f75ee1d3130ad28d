//! The wavefront path tracer: all paths of a frame advance together, one segment per wave.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{UVec2, Vec2};
use rayon::prelude::*;
use vcm_scene::Scene;
use vcm_scene::sampling::Rng;
use vcm_traversal::{HitBatch, RayBatch, Traversal};

use crate::error::RenderError;
use crate::film::Film;
use crate::integrator::{FrameStats, Integrator, check_image_size};
use crate::path_state::PathState;
use crate::shade::{ShadeContext, shade};
use crate::surface_hit::Hit;

/// What a [`PathTracer`] renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PtSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Seed of every path's random stream.
    pub seed: u64,
    /// Longest path in segments (a directly seen light is 1); `None`: unlimited, ended by
    /// Russian roulette only.
    pub max_depth: Option<u32>,
}

/// Unidirectional path tracer with next event estimation and MIS, one sample per pixel and
/// frame, run as waves of ray batches over a [`Traversal`] backend.
pub struct PathTracer {
    scene: Arc<Scene>,
    traversal: Arc<dyn Traversal>,
    settings: PtSettings,
    paths: Vec<PathState>,
    rays: RayBatch,
    hits: HitBatch,
    shadow_rays: RayBatch,
    occluded: Vec<bool>,
}

impl PathTracer {
    /// A path tracer for `scene`, traced with `traversal` (built over
    /// [`Scene::triangle_corners`], primitive id = triangle index).
    pub fn new(
        scene: Arc<Scene>,
        traversal: Arc<dyn Traversal>,
        settings: PtSettings,
    ) -> Result<PathTracer, RenderError> {
        check_image_size(settings.width, settings.height)?;
        Ok(PathTracer {
            scene,
            traversal,
            settings,
            paths: Vec::new(),
            rays: RayBatch::default(),
            hits: HitBatch::default(),
            shadow_rays: RayBatch::default(),
            occluded: Vec::new(),
        })
    }

    /// The settings this tracer renders with.
    pub fn settings(&self) -> &PtSettings {
        &self.settings
    }
}

impl Integrator for PathTracer {
    /// Renders frame `iteration`: one path per pixel, each added to `film` once it ends.
    fn render_frame(&mut self, film: &mut Film, iteration: u32) -> FrameStats {
        let PtSettings { width, height, .. } = self.settings;
        assert_eq!(
            (film.width(), film.height()),
            (width, height),
            "film size differs from the settings"
        );
        let start = Instant::now();
        let mut stats = FrameStats::default();
        self.generate_camera_paths(iteration);
        stats.camera_rays = self.paths.len() as u64;
        while !self.paths.is_empty() {
            stats.traversal_time += self.trace();
            self.shade();
            stats.shadow_rays += self.shadow_rays.len() as u64;
            stats.traversal_time += self.trace_shadows();
            self.retire_finished_paths(film);
            stats.continuation_rays += self.paths.len() as u64;
        }
        stats.shading_time = start.elapsed().saturating_sub(stats.traversal_time);
        stats
    }

    fn image_size(&self) -> (u32, u32) {
        (self.settings.width, self.settings.height)
    }
}

impl PathTracer {
    /// One path per pixel in pixel order, its position jittered uniformly over the pixel.
    fn generate_camera_paths(&mut self, iteration: u32) {
        let PtSettings {
            width,
            height,
            seed,
            ..
        } = self.settings;
        let camera = &self.scene.camera;
        (0..width * height)
            .into_par_iter()
            .map(|pixel| {
                let mut rng = Rng::from_key(&[seed, u64::from(iteration), u64::from(pixel), 0]);
                let xy = UVec2::new(pixel % width, pixel / width).as_vec2();
                let raster: Vec2 = xy + rng.uniform2();
                let direction = camera.direction(width, height, raster);
                PathState::new(pixel, rng, camera.position, direction)
            })
            .collect_into_vec(&mut self.paths);
    }

    /// Closest hits of every active path's current segment; returns the time taken.
    fn trace(&mut self) -> Duration {
        self.rays.clear();
        for path in &self.paths {
            self.rays
                .push(path.origin, path.direction, 0.0, f32::INFINITY);
        }
        let start = Instant::now();
        self.traversal.intersect(&self.rays, &mut self.hits);
        start.elapsed()
    }

    /// Shades every path at its hit in parallel and queues the shadow rays in path order.
    fn shade(&mut self) {
        let ctx = ShadeContext {
            scene: &self.scene,
            max_segments: self.settings.max_depth.unwrap_or(u32::MAX),
        };
        let hits = &self.hits;
        self.paths.par_iter_mut().enumerate().for_each(|(i, path)| {
            shade(&ctx, path, Hit::from_batch(hits, i));
        });
        self.shadow_rays.clear();
        for shadow in self.paths.iter().filter_map(|p| p.shadow.as_ref()) {
            self.shadow_rays
                .push(shadow.origin, shadow.direction, 0.0, shadow.tmax);
        }
    }

    /// Tests the queued shadow rays and adds the unoccluded contributions to their paths;
    /// returns the traversal time.
    fn trace_shadows(&mut self) -> Duration {
        let start = Instant::now();
        self.traversal
            .occluded(&self.shadow_rays, &mut self.occluded);
        let elapsed = start.elapsed();
        let with_shadow = self.paths.iter_mut().filter(|p| p.shadow.is_some());
        for (path, &blocked) in with_shadow.zip(&self.occluded) {
            let shadow = path.shadow.take().expect("filtered on a queued shadow ray");
            if !blocked {
                path.radiance += shadow.contribution;
            }
        }
        elapsed
    }

    /// Adds the radiance of ended paths to `film` and keeps the others, in order.
    fn retire_finished_paths(&mut self, film: &mut Film) {
        self.paths.retain(|path| {
            if !path.alive {
                film.add(path.pixel as usize, path.radiance);
            }
            path.alive
        });
    }
}
