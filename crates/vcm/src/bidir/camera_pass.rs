//! The camera pass: camera paths traced in waves; at each vertex emission, a light sample,
//! connections to cached light vertices and merging, each weighted by VCM's MIS.

use std::f32::consts::PI;

use glam::{UVec2, Vec2, Vec3};
use smallvec::SmallVec;
use vcm_scene::bsdf::{FixedOutgoing, Pdfs, TransportMode};
use vcm_scene::light::HitEmission;
use vcm_scene::sampling::{Rng, Sampler, SobolSampler};
use vcm_scheduler::{Scheduler, Tile, Wavefront};
use vcm_traversal::{HitBatch, RayBatch};

use super::mis::{
    CameraMis, ConnectionPdfs, LightSamplePdfs, connection_weight, emission_hit_weight,
    light_sample_weight, merge_weight,
};
use super::{Algorithm, FrameContext, VcmSettings, add_scheduled};
use crate::hash_grid::{GridCells, HashGrid};
use crate::integrator::FrameStats;
use crate::light_vertex_cache::{LightVertex, LightVertexCache};
use crate::medium::Medium;
use crate::path_state::ShadowRay;
use crate::prefetch::prefetch;
use crate::roulette::Roulette;
use crate::shadow::{LightSample, segment_to};
use crate::surface_hit::{Hit, SurfaceHit};
use crate::vertex_numbers::{CAMERA, Draw};
use crate::walk::Walk;
use crate::wave::{Ahead, fill_extension_rays, shade_in_parallel, start_paths};

mod lanes;

/// Shadow rays a camera path state holds without a heap allocation: the light sample and
/// one connection, the default (`--connections 1`).
const INLINE_SHADOW_RAYS: usize = 2;

/// What the camera paths of one iteration read: the iteration, and its light pass's results.
pub(crate) struct CameraContext<'a> {
    pub frame: FrameContext<'a>,
    /// The iteration's light vertices.
    pub cache: &'a LightVertexCache,
    /// The hash grid over `cache` (empty unless the algorithm merges).
    pub grid: &'a HashGrid,
}

impl<'a> std::ops::Deref for CameraContext<'a> {
    type Target = FrameContext<'a>;

    fn deref(&self) -> &FrameContext<'a> {
        &self.frame
    }
}

/// One camera path between waves.
#[derive(Clone, Debug)]
struct CameraPathState {
    pixel: u32,
    /// The path's sample of the frame: the iteration it belongs to.
    sample: u32,
    walk: Walk<CameraMis>,
    radiance: Vec3,
    alive: bool,
    /// Occlusion rays queued by the last shading step: the light sample and connections
    /// (held in the path state up to [`INLINE_SHADOW_RAYS`], so that the common case allocates
    /// nothing per path).
    shadows: SmallVec<[ShadowRay; INLINE_SHADOW_RAYS]>,
    /// The light vertices the vertex being shaded connects to, picked when its hit was
    /// prepared: deriving the picks' stream takes a few dozen dependent multiplications,
    /// paid once where `prepare` and shading each derived it (3% of VCM's instructions).
    picks: Option<CachePicks>,
}

crate::walk::walker!(CameraPathState, CameraMis);

/// Bytes a camera path in flight takes with `connections` per vertex: its state, its rays
/// and hit, and its light sample's and connections' shadow rays (those beyond the inline
/// ones held twice: in the path's list and in the batch).
pub(crate) fn bytes_per_path(connections: u32) -> u64 {
    let shadows = u64::from(connections) + 1;
    let spilled = shadows.saturating_sub(INLINE_SHADOW_RAYS as u64);
    (size_of::<CameraPathState>() + RayBatch::BYTES_PER_RAY + HitBatch::BYTES_PER_HIT) as u64
        + spilled * size_of::<ShadowRay>() as u64
        + shadows * (RayBatch::BYTES_PER_RAY + size_of::<bool>()) as u64
}

/// Bytes of one camera sample of a frame: its (sample, pixel, radiance) as its path ends
/// and its (pixel, radiance) in its iteration's list.
pub(crate) const BYTES_PER_SAMPLE: u64 =
    (size_of::<(u32, u32, Vec3)>() + size_of::<(u32, Vec3)>()) as u64;

/// `scheduler` says, and returns each iteration's (pixel, radiance) samples: one per pixel, in
/// no particular order (the additions to different pixels commute).
pub(crate) fn run(
    iterations: &[CameraContext],
    scheduler: Scheduler,
    stats: &mut FrameStats,
) -> Vec<Vec<(u32, Vec3)>> {
    let VcmSettings { width, height, .. } = *iterations[0].settings;
    let new_wavefront = || CameraWavefront {
        iterations,
        paths: Vec::new(),
        finished: Vec::new(),
    };
    let (traversal, stop) = (iterations[0].frame.traversal, iterations[0].frame.stop);
    let (outputs, scheduled) =
        vcm_scheduler::run(scheduler, (width, height), traversal, stop, new_wavefront);
    let camera_rays = u64::from(width) * u64::from(height) * iterations.len() as u64;
    stats.camera_rays += camera_rays;
    // Fewer than one ray per camera path only where a stop request cut the pass short.
    stats.continuation_rays += scheduled.closest_rays.saturating_sub(camera_rays);
    add_scheduled(stats, &scheduled);
    // `vec![v; n]` would clone the empty vector, dropping the reserved room of all but one.
    let pixels = width as usize * height as usize;
    let mut samples: Vec<Vec<_>> = (0..iterations.len())
        .map(|_| Vec::with_capacity(pixels))
        .collect();
    for (sample, pixel, radiance) in outputs.into_iter().flatten() {
        samples[sample as usize].push((pixel, radiance));
    }
    samples
}

/// The camera paths one scheduler worker has in flight, and the radiance of those that ended.
struct CameraWavefront<'a> {
    /// The frame's iterations; a path's `sample` indexes them.
    iterations: &'a [CameraContext<'a>],
    paths: Vec<CameraPathState>,
    /// (sample, pixel, radiance) of the paths that ended.
    finished: Vec<(u32, u32, Vec3)>,
}

impl Wavefront for CameraWavefront<'_> {
    type Output = Vec<(u32, u32, Vec3)>;

    /// Starts the camera paths of the tile's pixels, one per iteration.
    fn start(&mut self, tile: Tile) {
        let iterations = self.iterations;
        let samples = iterations.len() as u32;
        let width = iterations[0].settings.width;
        start_paths(&mut self.paths, (tile, width), samples, |pixel, sample| {
            start(&iterations[sample as usize], pixel, sample)
        });
    }

    fn active(&self) -> usize {
        self.paths.len()
    }

    /// The paths and the shadow rays they queued.
    fn memory_bytes(&self) -> usize {
        let spilled = self.paths.iter().filter(|p| p.shadows.spilled());
        let shadows: usize = spilled.map(|p| p.shadows.capacity()).sum();
        self.paths.capacity() * size_of::<CameraPathState>() + shadows * size_of::<ShadowRay>()
    }

    fn extension_rays(&self, rays: &mut RayBatch) {
        let segments = self.paths.iter().map(|p| (p.walk.origin, p.walk.direction));
        fill_extension_rays(rays, segments);
    }

    /// Shades every path at its hit in parallel and queues its light sample and connections,
    /// in path order.
    fn shade(&mut self, hits: &HitBatch, shadow_rays: &mut RayBatch) {
        let iterations = self.iterations;
        let ctx = |path: &CameraPathState| &iterations[path.sample as usize];
        // Without merging a vertex carries only its surface point ahead: the grid's state
        // would make every prepared vertex twice the size.
        if iterations[0].plan.merges {
            shade_in_parallel(
                &mut self.paths,
                (hits, iterations[0].frame.stop),
                vertex_sampler,
                &lanes::CameraLanes::new(iterations),
                |path, hit| MergingHit::prepare(ctx(path), path, hit),
                Some(|path: &_, hit: &mut MergingHit, step| hit.look_ahead(ctx(path), step)),
                |path, hit| {
                    let hit = hit.map(|(hit, ahead)| (hit, &ahead.surface, Some(&ahead.found)));
                    shade(ctx(path), path, hit)
                },
            );
        } else {
            shade_in_parallel(
                &mut self.paths,
                (hits, iterations[0].frame.stop),
                vertex_sampler,
                &lanes::CameraLanes::new(iterations),
                |path, hit| prepare(ctx(path), path, hit),
                None::<fn(&_, &mut _, _)>,
                |path, hit| shade(ctx(path), path, hit.map(|(hit, s)| (hit, s, None))),
            );
        }
        let shadows = self.paths.iter().flat_map(|p| &p.shadows);
        ShadowRay::fill_batch(shadow_rays, shadows);
    }

    /// Adds the unoccluded contributions to their paths and retires the paths that ended,
    /// in one pass over the paths.
    fn resolve(&mut self, occluded: &[bool]) {
        let mut blocked = occluded.iter();
        let finished = &mut self.finished;
        self.paths.retain_mut(|path| {
            for shadow in path.shadows.drain(..) {
                if !blocked.next().expect("one test per queued ray") {
                    path.radiance += shadow.contribution;
                }
            }
            if !path.alive {
                finished.push((path.sample, path.pixel, path.radiance));
            }
            path.alive
        });
    }

    fn finish(self) -> Vec<(u32, u32, Vec3)> {
        self.finished
    }
}

/// Starts the camera path of `pixel` in iteration `ctx` (the frame's `sample`), its position
/// jittered uniformly over the pixel.
fn start(ctx: &CameraContext, pixel: u32, sample: u32) -> CameraPathState {
    let VcmSettings {
        width,
        seed,
        sequence,
        ..
    } = *ctx.settings;
    let camera = &ctx.scene.camera;
    // The iterations' camera paths through a pixel are the samples of its stratified sequence.
    let mut rng = sequence.sampler(&[seed, u64::from(pixel), 0], ctx.iteration);
    let xy = UVec2::new(pixel % width, pixel / width).as_vec2();
    let raster: Vec2 = xy + rng.uniform2();
    let direction = ctx.projection.direction(raster);
    let cos_camera = camera.forward.dot(direction);
    let camera_pdf_w = 1.0 / (ctx.projection.pixel_area() * cos_camera.powi(3));
    CameraPathState {
        pixel,
        sample,
        walk: Walk {
            rng,
            origin: camera.position,
            direction,
            throughput: Vec3::ONE,
            medium: Medium::OUTSIDE,
            mis: CameraMis::camera(camera_pdf_w, &ctx.factors),
            segments: 1,
            roulette: Roulette::UNIT,
        },
        radiance: Vec3::ZERO,
        alive: true,
        shadows: SmallVec::new(),
        picks: None,
    }
}

/// The sampler of `path`, moved to the numbers of the vertex it has reached.
fn vertex_sampler(path: &mut CameraPathState) -> &mut SobolSampler {
    path.walk.start_vertex(CAMERA.pairs())
}

/// What a camera vertex computes before its chunk of paths is shaded
/// ([`shade_in_parallel`]): the surface point, and what it will read starts loading: where
/// it connects to the cache, the picked light vertices. These lie all over memory and take
/// a while to arrive; the chunk's other paths are prepared and shaded meanwhile. The picks
/// are kept in the path for its shading.
fn prepare(ctx: &CameraContext, path: &mut CameraPathState, hit: Hit) -> SurfaceHit {
    if ctx.plan.connects {
        pick_and_prefetch(ctx, path);
    }
    SurfaceHit::at(ctx.scene, hit)
}

/// Picks the light vertices the vertex `path` reached connects to, keeps the picks in the
/// path, and starts loading the vertices.
fn pick_and_prefetch(ctx: &CameraContext, path: &mut CameraPathState) {
    let picks = CachePicks::next(vertex_sampler(path), ctx);
    let vertices = ctx.cache.vertices();
    picks.indices().for_each(|i| prefetch(&vertices[i]));
    path.picks = Some(picks);
}

/// The light vertices within the merge radius of a camera vertex, in the cache's order.
type Neighbours = SmallVec<[u32; 16]>;

/// A merging camera vertex prepared ahead: its surface point, the grid cells around it and
/// the light vertices found in them, filled in three steps, each reading what the one
/// before requested: where the cells' buckets begin, their entries, the vertices they name.
struct MergingHit {
    surface: SurfaceHit,
    cells: GridCells,
    found: Neighbours,
}

impl MergingHit {
    /// [`prepare`], and a request for where the buckets of the cells around the point begin.
    fn prepare(ctx: &CameraContext, path: &mut CameraPathState, hit: Hit) -> MergingHit {
        let surface = prepare(ctx, path, hit);
        let cells = ctx.grid.cells(surface.point.position);
        ctx.grid.prefetch_bucket_starts(&cells);
        MergingHit {
            surface,
            cells,
            found: Neighbours::new(),
        }
    }

    /// First the cells' grid entries, then the query in them and a request for each light
    /// vertex found. Independent from vertex to vertex, the queries' cache misses overlap
    /// here, where inside each vertex's shading they would wait one after another.
    fn look_ahead(&mut self, ctx: &CameraContext, step: Ahead) {
        match step {
            Ahead::First => ctx.grid.prefetch_entries(&self.cells),
            Ahead::Second => {
                let vertices = ctx.cache.vertices();
                let found = &mut self.found;
                ctx.grid
                    .query_cells(&self.cells, self.surface.point.position, |i| {
                        prefetch(&vertices[i]);
                        found.push(i as u32);
                    });
                // In the cache's order, so that the merges' sum does not depend on how the
                // grid lays its cells out.
                found.sort_unstable();
            }
        }
    }
}

/// Shades the vertex where a camera path hit the scene (`None`: it escaped and ends).
/// `hit` holds the surface point and, where merging, the light vertices within the radius.
fn shade(
    ctx: &CameraContext,
    path: &mut CameraPathState,
    hit: Option<(Hit, &SurfaceHit, Option<&Neighbours>)>,
) {
    let max_segments = ctx.max_segments();
    if path.walk.segments > max_segments {
        path.alive = false;
        return;
    }
    let Some((hit, surface, neighbours)) = hit else {
        path.walk.cross(f32::INFINITY);
        path.radiance += path.walk.throughput * escaped(ctx, path);
        path.alive = false;
        return;
    };
    let scene = ctx.scene;
    let algorithm = ctx.settings.algorithm;
    vertex_sampler(path);
    path.walk.cross(hit.t);
    let wo = -path.walk.direction;
    path.walk
        .mis
        .arrive(Some(hit.t * hit.t), surface.cos_geometric(wo));
    path.radiance += path.walk.throughput * emission(ctx, path, hit);
    // Light tracing finds everything else from the light side.
    if algorithm == Algorithm::LightTracing || path.walk.segments >= max_segments {
        path.alive = false;
        return;
    }
    let bsdf = scene.bsdf(&surface.point);
    let Some(seen) = bsdf.fix_outgoing(wo) else {
        path.alive = false;
        return;
    };
    if bsdf.has_non_delta() {
        if ctx.plan.connects {
            // `prepare` picked them and started loading their vertices.
            let picks = path.picks.take().expect("a connecting hit is prepared");
            path.walk.rng.skip(const { CAMERA.index(Draw::LightPick) });
            if let Some(shadow) = light_sample(ctx, path, surface, &seen) {
                path.shadows.push(shadow);
            }
            connect_to_cache(ctx, path, surface, &seen, &picks);
        }
        if ctx.plan.merges {
            let found = neighbours.expect("looked ahead where merging");
            path.radiance += path.walk.throughput * merge(ctx, path, (surface, found), &seen);
            // Photon mapping proper stops at the first diffuse or glossy vertex.
            if algorithm == Algorithm::Ppm {
                path.alive = false;
                return;
            }
        }
    }
    let transport = (TransportMode::Radiance, Pdfs::Both);
    path.alive = path
        .walk
        .scatter(scene, surface, &seen, transport, |mis, sample| {
            mis.scattered(surface, sample, &ctx.factors)
        })
        .is_some();
}

/// Emitted radiance found by the path at `hit`, MIS-weighted.
fn emission(ctx: &CameraContext, path: &CameraPathState, hit: Hit) -> Vec3 {
    let scene = ctx.scene;
    let Some(emitted) = scene.emission_on_hit(hit.triangle, hit.u, hit.v, path.walk.direction)
    else {
        return Vec3::ZERO;
    };
    let light = scene
        .light_sampler
        .light_of_triangle(hit.triangle)
        .expect("an emitting triangle is an area light");
    emitted.radiance * found_emission_weight(ctx, path, light, &emitted)
}

/// Radiance from the environment toward a path that left the scene, MIS-weighted. The path's
/// MIS quantities take no distance or cosine for this segment: the environment's pdfs are
/// per solid angle.
fn escaped(ctx: &CameraContext, path: &CameraPathState) -> Vec3 {
    let Some((light, emitted)) = ctx.scene.emission_on_escape(path.walk.direction) else {
        return Vec3::ZERO;
    };
    emitted.radiance * found_emission_weight(ctx, path, light, &emitted)
}

/// Weight of emission from light `light` that the camera path found by itself.
fn found_emission_weight(
    ctx: &CameraContext,
    path: &CameraPathState,
    light: usize,
    emitted: &HitEmission,
) -> f32 {
    if path.walk.segments == 1 {
        // No other technique samples a light seen directly through a pinhole.
        1.0
    } else if ctx.settings.algorithm == Algorithm::Ppm {
        // Photon mapping proper merges at the first non-specular vertex and stops there: a
        // light is found only through specular vertices, which nothing else samples.
        1.0
    } else {
        let pick_pmf = ctx.scene.light_sampler.pmf(light);
        emission_hit_weight(
            &path.walk.mis.beside_light(),
            pick_pmf * emitted.direct_pdf_a,
            pick_pmf * emitted.emission_pdf_w,
            &ctx.factors,
        )
    }
}

/// One light sample (next event estimation) from a camera vertex.
fn light_sample(
    ctx: &CameraContext,
    path: &mut CameraPathState,
    surface: &SurfaceHit,
    seen: &FixedOutgoing,
) -> Option<ShadowRay> {
    let sample = LightSample::sample(ctx.scene, &mut path.walk.rng, surface, seen, Pdfs::Both)?;
    let (illumination, eval) = (&sample.illumination, &sample.eval);
    let pdfs = LightSamplePdfs {
        direct_pdf_w: sample.direct_pdf_w(),
        emission_pdf_w: illumination.emission_pdf_w * sample.pick_pmf,
        cos_at_light: illumination.cos_at_light,
        cos_at_receiver: surface.cos_geometric(illumination.direction),
        // No BSDF sample hits a delta light.
        bsdf_fwd_pdf_w: if sample.light.is_delta() {
            0.0
        } else {
            eval.pdf_fwd
        },
        bsdf_rev_pdf_w: eval.pdf_rev,
    };
    let only = sample.light.is_delta() && ctx.factors.only_delta_light_sample(path.walk.segments);
    let weight = if only {
        1.0
    } else {
        light_sample_weight(&path.walk.mis.subpath, &pdfs, &ctx.factors)
    };
    let transmittance = sample.transmittance(ctx.scene, surface, path.walk.medium);
    let contribution = path.walk.throughput
        * transmittance
        * illumination.value
        * eval.f_cos
        * (weight / pdfs.direct_pdf_w);
    Some(sample.shadow_ray(surface, contribution))
}

/// The N_c light vertices a camera vertex connects to, picked uniformly from the cache.
#[derive(Clone, Debug)]
struct CachePicks {
    /// The stream the picks are drawn from.
    rng: Rng,
    /// N_c, or 0 for an empty cache.
    count: u32,
    /// N_v, the vertices in the cache.
    vertices: usize,
}

impl CachePicks {
    /// The picks of one camera vertex, from a stream of their own that `rng` gives in place
    /// of its next pair of dimensions (which the vertex then skips), without moving on.
    fn next(rng: &SobolSampler, ctx: &CameraContext) -> CachePicks {
        let vertices = ctx.cache.len();
        let count = if vertices == 0 {
            0
        } else {
            ctx.settings.connections
        };
        CachePicks {
            rng: rng.next_stream(),
            count,
            vertices,
        }
    }

    /// The picked cache indices, in order (the same every call).
    fn indices(&self) -> impl Iterator<Item = usize> + use<> {
        let (mut rng, vertices) = (self.rng.clone(), self.vertices as u64);
        (0..self.count).map(move |_| ((u64::from(rng.next_u32()) * vertices) >> 32) as usize)
    }
}

/// Connects the camera vertex to the light vertices `picks`.
fn connect_to_cache(
    ctx: &CameraContext,
    path: &mut CameraPathState,
    surface: &SurfaceHit,
    seen: &FixedOutgoing,
    picks: &CachePicks,
) {
    let vertices = ctx.cache.vertices();
    // c = (1 / N_c) · (N_v / N_p): each pick stands for N_v / N_c vertices of N_p paths.
    let scale = vertices.len() as f32 / (ctx.settings.connections as f32 * ctx.factors.light_paths);
    for pick in picks.indices() {
        let vertex = &vertices[pick];
        let segments = path
            .walk
            .segments
            .saturating_add(vertex.path_length.get() + 1);
        if segments > ctx.max_segments() {
            continue;
        }
        if let Some(shadow) = connect(ctx, path, surface, seen, vertex, scale) {
            path.shadows.push(shadow);
        }
    }
}

/// The connection between a camera vertex and one light vertex, its contribution already
/// scaled by `scale`.
fn connect(
    ctx: &CameraContext,
    path: &CameraPathState,
    surface: &SurfaceHit,
    seen: &FixedOutgoing,
    vertex: &LightVertex,
    scale: f32,
) -> Option<ShadowRay> {
    let to_light = vertex.position - surface.point.position;
    let distance_sq = to_light.length_squared();
    if distance_sq == 0.0 {
        return None;
    }
    let distance = distance_sq.sqrt();
    let direction = to_light / distance;
    let camera_eval = seen.eval(direction, TransportMode::Radiance, Pdfs::Both);
    if camera_eval.f_cos == Vec3::ZERO {
        return None;
    }
    let light_surface = SurfaceHit::new(ctx.scene, vertex.triangle, vertex.u, vertex.v);
    let light_bsdf = ctx.scene.bsdf(&light_surface.point);
    let light_eval = light_bsdf.eval(vertex.wo, -direction, TransportMode::Importance);
    if light_eval.f_cos == Vec3::ZERO {
        return None;
    }
    let pdfs = ConnectionPdfs {
        camera_fwd_pdf_a: camera_eval.pdf_fwd * light_surface.cos_geometric(direction)
            / distance_sq,
        camera_rev_pdf_w: camera_eval.pdf_rev,
        light_fwd_pdf_a: light_eval.pdf_fwd * surface.cos_geometric(direction) / distance_sq,
        light_rev_pdf_w: light_eval.pdf_rev,
    };
    let light_factors = ctx.factors.at_light_vertex(vertex.path_length.get());
    let weight = connection_weight(
        (&path.walk.mis.subpath, &vertex.mis),
        &pdfs,
        (&ctx.factors, &light_factors),
    );
    let transmittance = path
        .walk
        .medium
        .toward(ctx.scene, &surface.point, direction)
        .transmittance(distance);
    let contribution = path.walk.throughput
        * transmittance
        * vertex.throughput
        * camera_eval.f_cos
        * light_eval.f_cos
        * (weight * scale / distance_sq);
    let origin = surface.spawn(direction);
    let (ray_direction, tmax) = segment_to(origin, light_surface.spawn(-direction));
    Some(ShadowRay {
        origin,
        direction: ray_direction,
        tmax,
        contribution,
    })
}

/// Density estimation with the light vertices within the frame's radius (vertex merging):
/// the MIS-weighted reflected radiance at the camera vertex, per unit throughput.
fn merge(
    ctx: &CameraContext,
    path: &CameraPathState,
    (surface, found): (&SurfaceHit, &Neighbours),
    seen: &FixedOutgoing,
) -> Vec3 {
    let vertices = ctx.cache.vertices();
    let max_segments = ctx.max_segments();
    let ppm = ctx.settings.algorithm == Algorithm::Ppm;
    let mut sum = Vec3::ZERO;
    // The vertices within the radius, found and requested by `look_ahead` (the grid holds
    // only those that merge: in VCM not a light path's first, `MisFactors::shortest_merged`).
    found.iter().for_each(|&i| {
        let vertex = &vertices[i as usize];
        if path.walk.segments.saturating_add(vertex.path_length.get()) > max_segments {
            return;
        }
        let eval = seen.eval(vertex.wo, TransportMode::Radiance, Pdfs::Both);
        let point = &surface.point;
        let cos_light =
            vertex.cos_on_arrival(&ctx.scene.mesh, (point.triangle, point.geometric_normal));
        if eval.f_cos == Vec3::ZERO || cos_light == 0.0 {
            return;
        }
        let weight = if ppm {
            1.0
        } else {
            merge_weight(
                &path.walk.mis.subpath,
                &vertex.mis,
                eval.pdf_fwd,
                eval.pdf_rev,
                &ctx.factors,
            )
        };
        // The light vertices' density is over the area of the surfaces they lie on, so the
        // photon's flux weighs f·|ωi·n_s| / |ωi·n_g|: f_cos (= f·|ωi·n_s| in radiance mode)
        // over the geometric cosine. With shading normals the two cosines differ; f alone
        // would reflect the light as if the shading normal were the geometric one. n_g is
        // the photon's own surface's: the light path's pdf, and so the weight, holds that
        // cosine (the weight falls with it), while a photon on another triangle within the
        // radius (an edge, a curved mesh) may arrive along the camera vertex's plane, where
        // 1/|ωi·n_g| of the camera vertex's normal is unbounded.
        sum += vertex.throughput * eval.f_cos * (weight / cos_light);
    });
    sum / (PI * ctx.radius * ctx.radius * ctx.factors.light_paths)
}
