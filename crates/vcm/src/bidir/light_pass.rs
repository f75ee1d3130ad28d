//! The light pass: light paths traced in waves, their vertices stored in the light vertex
//! cache and (for light tracing, BPT and VCM) connected to the camera.

use glam::{UVec2, Vec3};
use rayon::prelude::*;
use vcm_scene::bsdf::{Bsdf, TransportMode};
use vcm_scene::sampling::Rng;
use vcm_traversal::{HitBatch, RayBatch};

use super::mis::{SubpathMis, camera_connection_weight};
use super::walk::Walk;
use super::{Algorithm, FrameContext, VcmSettings, timed};
use crate::film::Film;
use crate::integrator::FrameStats;
use crate::light_vertex_cache::{LightVertex, LightVertexCache};
use crate::path_state::ShadowRay;
use crate::shadow::{offset_off_light, segment_to};
use crate::surface_hit::{Hit, SurfaceHit};

/// Random stream tag of light paths (camera paths use 0).
const LIGHT_STREAM: u64 = 1;

/// Random stream tag of the preprocess's light paths.
const PREPROCESS_STREAM: u64 = 2;

/// Where the light pass puts its results (`None`: the algorithm does not use them).
pub(crate) struct LightPassOutputs<'a> {
    /// The light vertex cache.
    pub cache: Option<&'a mut LightVertexCache>,
    /// The film that light tracing splats go to.
    pub film: Option<&'a mut Film>,
}

/// A light tracing splat waiting for its occlusion test.
#[derive(Clone, Copy, Debug)]
struct Splat {
    /// The pixel the light vertex projects to.
    pixel: u32,
    /// The ray from the light vertex to the camera and its contribution.
    ray: ShadowRay,
}

/// One light path between waves.
#[derive(Clone, Debug)]
struct LightPathState {
    walk: Walk,
    /// 1 / the largest channel of the throughput after emission: makes Russian roulette
    /// independent of the light's units.
    roulette_scale: f32,
    /// The path starts at a light at infinity (its first segment has no length).
    from_infinity: bool,
    alive: bool,
    /// The vertex the last shading step produced, if it can be connected or merged.
    vertex: Option<LightVertex>,
    /// The camera connection the last shading step produced.
    splat: Option<Splat>,
}

/// The light pass's reusable buffers.
#[derive(Default)]
pub(crate) struct LightPass {
    paths: Vec<LightPathState>,
    rays: RayBatch,
    hits: HitBatch,
    shadow_rays: RayBatch,
    occluded: Vec<bool>,
}

impl LightPass {
    /// Traces one light path per index in `0..count` for frame `ctx.iteration`, stores their
    /// vertices in `outputs.cache` and splats their camera connections onto `outputs.film`.
    pub fn run(
        &mut self,
        ctx: &FrameContext,
        count: u32,
        mut outputs: LightPassOutputs,
        stats: &mut FrameStats,
    ) {
        let splat = outputs.film.is_some();
        self.trace_paths(ctx, count, LIGHT_STREAM, splat, stats, |pass, stats| {
            let vertices = pass.paths.iter_mut().filter_map(|p| p.vertex.take());
            match outputs.cache.as_deref_mut() {
                Some(cache) => cache.extend(vertices),
                None => vertices.for_each(drop),
            }
            if let Some(film) = outputs.film.as_deref_mut() {
                pass.add_unoccluded_splats(ctx, film, stats);
            }
        });
    }

    /// Traces `count` light paths that store and splat nothing and returns how many
    /// cacheable (non-specular) vertices they have (the preprocess that sizes the cache).
    pub fn count_vertices(&mut self, ctx: &FrameContext, count: u32) -> u64 {
        let mut vertices = 0;
        let mut stats = FrameStats::default();
        self.trace_paths(
            ctx,
            count,
            PREPROCESS_STREAM,
            false,
            &mut stats,
            |pass, _| {
                vertices += pass
                    .paths
                    .iter_mut()
                    .filter_map(|p| p.vertex.take())
                    .count() as u64;
            },
        );
        vertices
    }

    /// The wave loop: emit, then trace, shade (`splat`: connect to the camera) and hand the
    /// wave to `collect` until every path has ended.
    fn trace_paths(
        &mut self,
        ctx: &FrameContext,
        count: u32,
        stream: u64,
        splat: bool,
        stats: &mut FrameStats,
        mut collect: impl FnMut(&mut LightPass, &mut FrameStats),
    ) {
        (0..count)
            .into_par_iter()
            .map(|index| emit(ctx, index, stream))
            .collect_into_vec(&mut self.paths);
        self.paths.retain(|p| p.alive);
        while !self.paths.is_empty() {
            self.rays.clear();
            for path in &self.paths {
                self.rays
                    .push(path.walk.origin, path.walk.direction, 0.0, f32::INFINITY);
            }
            stats.light_rays += self.rays.len() as u64;
            let (rays, hits) = (&self.rays, &mut self.hits);
            timed(&mut stats.traversal_time, || {
                ctx.traversal.intersect(rays, hits)
            });
            let hits = &self.hits;
            self.paths.par_iter_mut().enumerate().for_each(|(i, path)| {
                shade(ctx, path, Hit::from_batch(hits, i), splat);
            });
            collect(self, stats);
            self.paths.retain(|p| p.alive);
        }
    }

    /// Tests the wave's camera connections and splats the unoccluded ones, in path order.
    fn add_unoccluded_splats(
        &mut self,
        ctx: &FrameContext,
        film: &mut Film,
        stats: &mut FrameStats,
    ) {
        let rays = self
            .paths
            .iter()
            .filter_map(|p| Some(&p.splat.as_ref()?.ray));
        ShadowRay::fill_batch(&mut self.shadow_rays, rays);
        stats.shadow_rays += self.shadow_rays.len() as u64;
        let (rays, occluded) = (&self.shadow_rays, &mut self.occluded);
        timed(&mut stats.traversal_time, || {
            ctx.traversal.occluded(rays, occluded)
        });
        let splats = self.paths.iter_mut().filter_map(|p| p.splat.take());
        for (splat, &blocked) in splats.zip(&self.occluded) {
            if !blocked {
                film.add_splat(splat.pixel as usize, splat.ray.contribution);
            }
        }
    }
}

/// Starts light path `index`: picks a light by power and samples an emitted ray.
fn emit(ctx: &FrameContext, index: u32, stream: u64) -> LightPathState {
    let mut rng = Rng::from_key(&[
        ctx.settings.seed,
        u64::from(ctx.iteration),
        u64::from(index),
        stream,
    ]);
    let (u_pick, u_pos, u_dir) = (rng.uniform(), rng.uniform2(), rng.uniform2());
    let mut path = LightPathState {
        walk: Walk {
            rng,
            origin: Vec3::ZERO,
            direction: Vec3::Z,
            throughput: Vec3::ZERO,
            mis: SubpathMis::default(),
            segments: 1,
        },
        roulette_scale: 0.0,
        from_infinity: false,
        alive: false,
        vertex: None,
        splat: None,
    };
    let scene = ctx.scene;
    let Some((light_index, pick_pmf)) = scene.light_sampler.sample(u_pick) else {
        return path;
    };
    let light = &scene.lights[light_index];
    let Some(emission) = light.emit(&scene.textures, u_pos, u_dir) else {
        return path;
    };
    let emission_pdf_w = emission.emission_pdf_w * pick_pmf;
    path.walk.throughput = emission.value * (emission.cos_at_light / emission_pdf_w);
    path.roulette_scale = 1.0 / path.walk.throughput.max_element();
    path.walk.mis = SubpathMis::light(
        emission.direct_pdf_a * pick_pmf,
        emission_pdf_w,
        emission.cos_at_light,
        light.is_delta(),
        light.is_finite(),
        ctx.factors,
    );
    path.walk.origin = offset_off_light(light, emission.position, emission.direction);
    path.walk.direction = emission.direction;
    path.from_infinity = !light.is_finite();
    path.alive = path.walk.throughput.max_element() > 0.0 && path.walk.throughput.is_finite();
    path
}

/// Shades the vertex where a light path hit the scene (`None`: it escaped and ends): records
/// it as a cacheable vertex, connects it to the camera (`splat`), and continues the path.
fn shade(ctx: &FrameContext, path: &mut LightPathState, hit: Option<Hit>, splat: bool) {
    let Some(hit) = hit else {
        path.alive = false;
        return;
    };
    let scene = ctx.scene;
    let surface = SurfaceHit::new(scene, hit.triangle, hit.u, hit.v);
    let wo = -path.walk.direction;
    let distance_sq = (path.walk.segments > 1 || !path.from_infinity).then_some(hit.t * hit.t);
    path.walk.mis.arrive(distance_sq, surface.cos_geometric(wo));
    let bsdf = scene.bsdf(&surface.point);
    let max_segments = ctx.max_segments();
    if bsdf.has_non_delta() {
        let vertex = LightVertex {
            position: surface.point.position,
            wo,
            throughput: path.walk.throughput,
            mis: path.walk.mis,
            triangle: hit.triangle,
            u: hit.u,
            v: hit.v,
            path_length: path.walk.segments,
        };
        if splat && path.walk.segments < max_segments {
            path.splat = connect_to_camera(ctx, &surface, &bsdf, &vertex);
        }
        path.vertex = Some(vertex);
    }
    // A further vertex has segments + 1 segments, and using it takes one more.
    path.alive = path.walk.segments.saturating_add(2) <= max_segments
        && path
            .walk
            .scatter(
                &surface,
                &bsdf,
                wo,
                TransportMode::Importance,
                ctx.factors,
                path.roulette_scale,
            )
            .is_some();
}

/// Connects a light vertex to the camera: its splat, if the vertex projects into the image
/// and scatters toward the camera.
fn connect_to_camera(
    ctx: &FrameContext,
    surface: &SurfaceHit,
    bsdf: &Bsdf,
    vertex: &LightVertex,
) -> Option<Splat> {
    let camera = &ctx.scene.camera;
    let VcmSettings { width, height, .. } = *ctx.settings;
    let raster = camera.raster_of(width, height, vertex.position)?;
    let to_camera = camera.position - vertex.position;
    let distance_sq = to_camera.length_squared();
    let direction = to_camera / distance_sq.sqrt();
    let eval = bsdf.eval(vertex.wo, direction, TransportMode::Importance);
    if eval.f_cos == Vec3::ZERO {
        return None;
    }
    // The camera's solid-angle pdf per pixel sample is d_image² / (pixel_area · cos θ) with
    // d_image = 1 / cos θ; its area pdf at the vertex adds |cos θ_surface| / d².
    let cos_camera = camera.forward.dot(-direction);
    let camera_pdf_w = 1.0 / (camera.pixel_area(width, height) * cos_camera.powi(3));
    let camera_pdf_a = camera_pdf_w * surface.cos_geometric(direction) / distance_sq;
    let weight = if ctx.settings.algorithm == Algorithm::LightTracing {
        1.0
    } else {
        camera_connection_weight(&vertex.mis, camera_pdf_a, eval.pdf_rev, ctx.factors)
    };
    let contribution = vertex.throughput
        * eval.f_cos
        * (weight * camera_pdf_w / (distance_sq * ctx.factors.light_paths));
    let origin = surface.spawn(direction);
    let (ray_direction, tmax) = segment_to(origin, camera.position);
    let pixel = raster.as_uvec2().min(UVec2::new(width - 1, height - 1));
    Some(Splat {
        pixel: pixel.y * width + pixel.x,
        ray: ShadowRay {
            origin,
            direction: ray_direction,
            tmax,
            contribution,
        },
    })
}
