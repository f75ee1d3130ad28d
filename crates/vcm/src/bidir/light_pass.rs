//! The light pass: light paths traced in waves, their vertices stored in the light vertex
//! cache and (for light tracing, BPT and VCM) connected to the camera.

use std::num::NonZeroU32;
use std::sync::{Mutex, PoisonError};

use glam::{UVec2, Vec3};
use rayon::prelude::*;
use vcm_scene::bsdf::{FixedOutgoing, Pdfs, TransportMode};
use vcm_scene::sampling::{Sampler, SobolSampler};
use vcm_scheduler::{Scheduler, Tile, Wavefront};
use vcm_traversal::{HitBatch, RayBatch};

use super::mis::{MisFactors, SubpathMis, camera_connection_weight};
use super::path_order::{in_path_order, path_key};
use super::{Algorithm, FrameContext, VcmSettings, add_scheduled};
use crate::integrator::FrameStats;
use crate::light_vertex_cache::LightVertex;
use crate::medium::Medium;
use crate::path_state::ShadowRay;
use crate::roulette::Roulette;
use crate::shadow::{offset_off_light, segment_to};
use crate::surface_hit::{Hit, SurfaceHit};
use crate::vertex_numbers::{EMISSION, LIGHT};
use crate::walk::Walk;
use crate::wave::{fill_extension_rays, for_started_in_lanes, shade_in_parallel, start_paths};

mod lanes;

/// Random stream tag of light paths (camera paths use 0).
const LIGHT_STREAM: u64 = 1;

/// Random stream tag of the preprocess's light paths.
const PREPROCESS_STREAM: u64 = 2;

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
    /// The path's index in its iteration (its random stream and its place in the results).
    index: u32,
    /// The path's sample of the frame: the iteration it belongs to.
    sample: u32,
    walk: Walk<SubpathMis>,
    /// The path starts at a light at infinity (its first segment has no length).
    from_infinity: bool,
    /// The path starts at a delta light (a point, spot or directional light).
    from_delta: bool,
    alive: bool,
    /// The vertex the last shading step produced, if it can be connected or merged.
    vertex: Option<LightVertex>,
    /// The camera connection the last shading step produced.
    splat: Option<Splat>,
    /// Vertices of the path kept so far (the next one's ordinal, [`path_key`]).
    kept_vertices: u32,
    /// Unoccluded splats of the path so far.
    kept_splats: u32,
}

crate::walk::walker!(LightPathState, SubpathMis);

/// Bytes a light path in flight takes: its state, its ray and hit, and its camera
/// connection's shadow ray.
pub(crate) const BYTES_PER_PATH: u64 = (size_of::<LightPathState>()
    + 2 * RayBatch::BYTES_PER_RAY
    + HitBatch::BYTES_PER_HIT
    + size_of::<bool>()) as u64;

/// Bytes of one light vertex in a worker's results (the vertex, its key and its place in
/// the key order), before it is copied into the light vertex cache.
pub(crate) const BYTES_PER_RESULT_VERTEX: u64 =
    (size_of::<LightVertex>() + size_of::<u64>() + size_of::<(u32, u32)>()) as u64;

/// Bytes of one light tracing splat in the results.
pub(crate) const BYTES_PER_SPLAT: u64 = size_of::<(u64, u32, Vec3)>() as u64;

/// says, and returns each iteration's vertices and (with `splat`) unoccluded camera
/// connections.
pub(crate) fn run(
    iterations: &[FrameContext],
    scheduler: Scheduler,
    splat: bool,
    buffers: &ResultBuffers,
    stats: &mut FrameStats,
) -> Vec<LightResults> {
    trace(
        iterations,
        scheduler,
        iterations[0].settings.light_path_grid(),
        LIGHT_STREAM,
        splat,
        buffers,
        stats,
    )
}

/// Traces `count` light paths that store and splat nothing and returns how many cacheable
/// (non-specular) vertices they have (the preprocess that sizes the cache).
pub(crate) fn count_vertices(ctx: FrameContext, scheduler: Scheduler, count: u32) -> u64 {
    let mut stats = FrameStats::default();
    let results = trace(
        &[ctx],
        scheduler,
        (count, 1),
        PREPROCESS_STREAM,
        false,
        &ResultBuffers::default(),
        &mut stats,
    );
    results[0].vertex_count() as u64
}

/// What one scheduler worker's light paths of one iteration left: their vertices and
/// unoccluded splats, with the [`path_key`] of each.
#[derive(Default)]
struct WorkerResults {
    vertices: Vec<LightVertex>,
    /// The key of each vertex.
    keys: Vec<u64>,
    /// (key, pixel, contribution).
    splats: Vec<(u64, u32, Vec3)>,
}

impl WorkerResults {
    /// Empties the lists, keeping their memory.
    fn clear(&mut self) {
        self.vertices.clear();
        self.keys.clear();
        self.splats.clear();
    }
}

/// Worker result lists kept from frame to frame. A worker's vertex list grows to a good share
/// of the cache; growing it anew every frame (reallocating, copying and faulting in fresh
/// pages) cost VCM about 6% of its time on the Cornell box.
#[derive(Default)]
pub(crate) struct ResultBuffers {
    spare: Mutex<Vec<WorkerResults>>,
}

impl ResultBuffers {
    /// A spare set of empty lists, or new ones.
    fn take(&self) -> WorkerResults {
        let mut spare = self.spare.lock().unwrap_or_else(PoisonError::into_inner);
        spare.pop().unwrap_or_default()
    }

    /// Keeps the lists of `results` (emptied) for later frames.
    pub fn recycle(&self, results: Vec<LightResults>) {
        let mut spare = self.spare.lock().unwrap_or_else(PoisonError::into_inner);
        for mut part in results.into_iter().flat_map(|r| r.parts) {
            part.clear();
            spare.push(part);
        }
    }
}

/// The vertices and unoccluded splats of one iteration's light paths, in [`path_key`]
/// order: path by path, each path's from the light on, whatever worker traced it.
pub(crate) struct LightResults {
    /// Each worker's results, as it found them.
    parts: Vec<WorkerResults>,
    /// (part, index in it) of every vertex, in key order.
    order: Vec<(u32, u32)>,
    /// (key, pixel, contribution), in key order.
    pub splats: Vec<(u64, u32, Vec3)>,
}

impl LightResults {
    /// The results of all `parts` (one per scheduler worker) of the paths `0..paths`, in key
    /// order. The vertices are ordered through a (part, index) per vertex and read in that
    /// order later ([`LightResults::vertices`]), so that the 64-byte vertices move only into
    /// the cache.
    fn gather(parts: Vec<WorkerResults>, paths: usize) -> LightResults {
        let places = parts.iter().enumerate().flat_map(|(part, results)| {
            let keys = results.keys.iter().enumerate();
            keys.map(move |(i, &key)| (key, (part as u32, i as u32)))
        });
        let splats = parts.iter().flat_map(|part| &part.splats);
        let (order, splats) = rayon::join(
            || in_path_order(paths, places),
            || in_path_order(paths, splats.map(|&splat| (splat.0, splat))),
        );
        LightResults {
            parts,
            order,
            splats,
        }
    }

    /// The parts of a pass that a stop request cut short, left unordered: they are only
    /// recycled.
    fn dropped(parts: Vec<WorkerResults>) -> LightResults {
        LightResults {
            parts,
            order: Vec::new(),
            splats: Vec::new(),
        }
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.order.len()
    }

    /// The vertices in key order.
    pub fn vertices(&self) -> impl IndexedParallelIterator<Item = LightVertex> + '_ {
        let parts = &self.parts;
        self.order
            .par_iter()
            .map(move |&(part, i)| parts[part as usize].vertices[i as usize])
    }
}

/// Traces the light paths of every index of a `size.0 × size.1` grid (tiles of it for the
/// tile scheduler), one per iteration, and gathers each iteration's results in a fixed order
/// (the workers' lists come from `buffers`).
fn trace(
    iterations: &[FrameContext],
    scheduler: Scheduler,
    size: (u32, u32),
    stream: u64,
    splat: bool,
    buffers: &ResultBuffers,
    stats: &mut FrameStats,
) -> Vec<LightResults> {
    let per_iteration = || iterations.iter().map(|_| buffers.take()).collect();
    let new_wavefront = || LightWavefront {
        iterations,
        grid_width: size.0,
        stream,
        splat,
        paths: Vec::new(),
        results: per_iteration(),
    };
    let (traversal, stop) = (iterations[0].traversal, iterations[0].stop);
    let (outputs, scheduled) = vcm_scheduler::run(scheduler, size, traversal, stop, new_wavefront);
    stats.light_rays += scheduled.closest_rays;
    add_scheduled(stats, &scheduled);
    let mut parts: Vec<Vec<WorkerResults>> = iterations.iter().map(|_| Vec::new()).collect();
    for output in outputs {
        for (iteration_parts, part) in parts.iter_mut().zip(output) {
            iteration_parts.push(part);
        }
    }
    let paths = size.0 as usize * size.1 as usize;
    if stop.is_raised() {
        return parts.into_iter().map(LightResults::dropped).collect();
    }
    let gather = |parts| LightResults::gather(parts, paths);
    parts.into_par_iter().map(gather).collect()
}

/// The light paths one scheduler worker has in flight, and the results of their vertices.
struct LightWavefront<'a> {
    /// The frame's iterations; a path's `sample` indexes them.
    iterations: &'a [FrameContext<'a>],
    /// Width of the grid whose tiles name the paths (path index = y · width + x).
    grid_width: u32,
    stream: u64,
    /// Whether vertices are connected to the camera.
    splat: bool,
    paths: Vec<LightPathState>,
    /// Results per iteration.
    results: Vec<WorkerResults>,
}

impl Wavefront for LightWavefront<'_> {
    type Output = Vec<WorkerResults>;

    /// Starts the light paths of the tile's indices, one per iteration: each emits from a
    /// light, its numbers computed [`LANES`](crate::lanes::LANES) paths at a time
    /// ([`SobolSampler::prefetch`]).
    fn start(&mut self, tile: Tile) {
        let (iterations, stream) = (self.iterations, self.stream);
        let samples = iterations.len() as u32;
        let first = self.paths.len();
        start_paths(
            &mut self.paths,
            (tile, self.grid_width),
            samples,
            |index, sample| {
                LightPathState::new(&iterations[sample as usize], index, sample, stream)
            },
        );
        for_started_in_lanes(&mut self.paths[first..], |chunk| {
            SobolSampler::prefetch(chunk.iter_mut().map(|path| &mut path.walk.rng));
            for path in chunk {
                emit(&iterations[path.sample as usize], path);
            }
        });
        // The few that could not start (a light that emits nothing) are dropped.
        self.paths.retain(|path| path.alive);
    }

    fn active(&self) -> usize {
        self.paths.len()
    }

    fn memory_bytes(&self) -> usize {
        self.paths.capacity() * size_of::<LightPathState>()
    }

    fn extension_rays(&self, rays: &mut RayBatch) {
        let segments = self.paths.iter().map(|p| (p.walk.origin, p.walk.direction));
        fill_extension_rays(rays, segments);
    }

    /// Shades every path at its hit in parallel, keeps the cacheable vertices and queues the
    /// camera connections, in path order.
    fn shade(&mut self, hits: &HitBatch, shadow_rays: &mut RayBatch) {
        let (iterations, splat) = (self.iterations, self.splat);
        let scene = iterations[0].scene;
        shade_in_parallel(
            &mut self.paths,
            (hits, iterations[0].stop),
            vertex_sampler,
            &lanes::LightLanes { iterations, splat },
            |_, hit| SurfaceHit::at(scene, hit),
            None::<fn(&_, &mut _, _)>,
            |path, hit| shade(&iterations[path.sample as usize], path, hit, splat),
        );
        for path in &mut self.paths {
            if let Some(vertex) = path.vertex.take() {
                let results = &mut self.results[path.sample as usize];
                results.keys.push(path_key(path.index, path.kept_vertices));
                results.vertices.push(vertex);
                path.kept_vertices += 1;
            }
        }
        let rays = self
            .paths
            .iter()
            .filter_map(|p| Some(&p.splat.as_ref()?.ray));
        ShadowRay::fill_batch(shadow_rays, rays);
    }

    /// Keeps the unoccluded splats and retires the paths that ended, in one pass over the
    /// paths.
    fn resolve(&mut self, occluded: &[bool]) {
        let mut blocked = occluded.iter();
        let results = &mut self.results;
        self.paths.retain_mut(|path| {
            if let Some(splat) = path.splat.take()
                && !blocked.next().expect("one test per queued splat")
            {
                let key = path_key(path.index, path.kept_splats);
                let splats = &mut results[path.sample as usize].splats;
                splats.push((key, splat.pixel, splat.ray.contribution));
                path.kept_splats += 1;
            }
            path.alive
        });
    }

    fn finish(self) -> Vec<WorkerResults> {
        self.results
    }
}

impl LightPathState {
    /// Light path `index` of iteration `ctx` (the frame's `sample`) before it is emitted,
    /// its sampler at the numbers of the emission.
    fn new(ctx: &FrameContext, index: u32, sample: u32, stream: u64) -> LightPathState {
        // The light paths of one iteration are the samples of one stratified sequence.
        let key = [ctx.settings.seed, ctx.iteration, stream];
        let mut rng = ctx.settings.sequence.sampler(&key, u64::from(index));
        rng.start_step(0, EMISSION.pairs());
        LightPathState {
            index,
            sample,
            walk: Walk {
                rng,
                origin: Vec3::ZERO,
                direction: Vec3::Z,
                throughput: Vec3::ZERO,
                medium: Medium::OUTSIDE,
                mis: SubpathMis::default(),
                segments: 1,
                roulette: Roulette::UNIT,
            },
            from_infinity: false,
            from_delta: false,
            alive: false,
            vertex: None,
            splat: None,
            kept_vertices: 0,
            kept_splats: 0,
        }
    }
}

/// Starts `path` in iteration `ctx`: picks a light by power and samples an emitted ray. A
/// light that emits nothing there leaves the path dead.
fn emit(ctx: &FrameContext, path: &mut LightPathState) {
    let rng = &mut path.walk.rng;
    let (u_pick, u_pos, u_dir) = (rng.uniform(), rng.uniform2(), rng.uniform2());
    let scene = ctx.scene;
    let Some((light_index, pick_pmf)) = scene.light_sampler.sample(u_pick) else {
        return;
    };
    let light = &scene.lights[light_index];
    let Some(emission) = light.emit(&scene.textures, u_pos, u_dir) else {
        return;
    };
    let emission_pdf_w = emission.emission_pdf_w * pick_pmf;
    path.walk.throughput = emission.value * (emission.cos_at_light / emission_pdf_w);
    path.walk.roulette = Roulette::relative_to(path.walk.throughput);
    path.walk.mis = SubpathMis::light(
        emission.direct_pdf_a * pick_pmf,
        emission_pdf_w,
        emission.cos_at_light,
        light.is_delta(),
        light.is_finite(),
        &ctx.factors,
    );
    path.walk.origin = offset_off_light(light, emission.position, emission.direction);
    path.walk.direction = emission.direction;
    path.from_infinity = !light.is_finite();
    path.from_delta = light.is_delta();
    path.alive = path.walk.throughput.max_element() > 0.0 && path.walk.throughput.is_finite();
}

/// The sampler of `path`, moved to the numbers of the vertex it has reached.
fn vertex_sampler(path: &mut LightPathState) -> &mut SobolSampler {
    path.walk.start_vertex(LIGHT.pairs())
}

/// Shades the vertex where a light path hit the scene (`None`: it escaped and ends): records
/// it as a cacheable vertex, connects it to the camera (`splat`), and continues the path.
fn shade(
    ctx: &FrameContext,
    path: &mut LightPathState,
    hit: Option<(Hit, &SurfaceHit)>,
    splat: bool,
) {
    let Some((hit, surface)) = hit else {
        path.alive = false;
        return;
    };
    vertex_sampler(path);
    let scene = ctx.scene;
    path.walk.cross(hit.t);
    let wo = -path.walk.direction;
    let distance_sq = (path.walk.segments > 1 || !path.from_infinity).then_some(hit.t * hit.t);
    path.walk.mis.arrive(distance_sq, surface.cos_geometric(wo));
    let bsdf = scene.bsdf(&surface.point);
    let seen = bsdf.fix_outgoing(wo);
    let max_segments = ctx.max_segments();
    // The factors at this vertex (beside the light on the path's first hit).
    let factors = ctx.factors.at_light_vertex(path.walk.segments);
    if bsdf.has_non_delta() {
        let vertex = LightVertex {
            position: surface.point.position,
            wo,
            throughput: path.walk.throughput,
            mis: path.walk.mis,
            triangle: hit.triangle,
            u: hit.u,
            v: hit.v,
            path_length: path_length(path.walk.segments),
        };
        if splat && path.walk.segments < max_segments && splats_here(ctx, path) {
            path.splat = seen.as_ref().and_then(|seen| {
                let medium = path.walk.medium;
                connect_to_camera(ctx, (surface, seen), (&vertex, &factors), medium)
            });
        }
        path.vertex = Some(vertex);
    }
    // A further vertex has segments + 1 segments, and using it takes one more.
    path.alive = path.walk.segments.saturating_add(2) <= max_segments
        && seen.is_some_and(|seen| {
            let transport = (TransportMode::Importance, Pdfs::Both);
            path.walk
                .scatter(scene, surface, &seen, transport, |mis, sample| {
                    mis.scattered(surface, sample, &factors);
                })
                .is_some()
        });
}

/// Whether the vertex `path` has reached is splatted: not a delta light's path's first
/// where light samples find it ([`MisFactors::splats_first_of_delta`]).
fn splats_here(ctx: &FrameContext, path: &LightPathState) -> bool {
    !(path.from_delta && path.walk.segments == 1) || ctx.factors.splats_first_of_delta()
}

/// The path length of a light vertex `segments` segments from the light.
fn path_length(segments: u32) -> NonZeroU32 {
    NonZeroU32::new(segments).expect("a light vertex lies at least one segment from the light")
}

/// Connects a light vertex, reached through `medium`, to the camera: its splat, if the vertex
/// projects into the image and scatters toward the camera. `factors` are those at the vertex.
fn connect_to_camera(
    ctx: &FrameContext,
    (surface, seen): (&SurfaceHit, &FixedOutgoing),
    (vertex, factors): (&LightVertex, &MisFactors),
    medium: Medium,
) -> Option<Splat> {
    let camera = &ctx.scene.camera;
    let VcmSettings { width, height, .. } = *ctx.settings;
    let raster = ctx.projection.raster_of(vertex.position)?;
    let to_camera = camera.position - vertex.position;
    let distance_sq = to_camera.length_squared();
    let distance = distance_sq.sqrt();
    let direction = to_camera / distance;
    let eval = seen.eval(direction, TransportMode::Importance, Pdfs::Both);
    if eval.f_cos == Vec3::ZERO {
        return None;
    }
    // The camera's solid-angle pdf per pixel sample is d_image² / (pixel_area · cos θ) with
    // d_image = 1 / cos θ; its area pdf at the vertex adds |cos θ_surface| / d².
    let cos_camera = camera.forward.dot(-direction);
    let camera_pdf_w = 1.0 / (ctx.projection.pixel_area() * cos_camera.powi(3));
    let camera_pdf_a = camera_pdf_w * surface.cos_geometric(direction) / distance_sq;
    let weight = if ctx.settings.algorithm == Algorithm::LightTracing {
        1.0
    } else {
        camera_connection_weight(&vertex.mis, camera_pdf_a, eval.pdf_rev, factors)
    };
    let transmittance = medium
        .toward(ctx.scene, &surface.point, direction)
        .transmittance(distance);
    let contribution = vertex.throughput
        * transmittance
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
