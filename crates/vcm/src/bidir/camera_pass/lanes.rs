//! The camera vertex ([`super::shade`]) on plain Lambert surfaces, in lanes
//! ([`crate::lambert`]): the light sample, the connections to cached light vertices and,
//! where the algorithm merges, merging with the light vertices found around it, each
//! weighted by VCM's MIS ([`crate::bidir::mis`]), and the continuation with the MIS
//! quantities' update and Russian roulette.

use std::f32::consts::PI;

use glam::Vec3;
use smallvec::SmallVec;
use vcm_scene::bsdf::TransportMode;

use super::{
    CachePicks, CameraContext, CameraPathState, MergingHit, Neighbours, pick_and_prefetch,
};
use crate::bidir::Algorithm;
use crate::bidir::mis::{
    CameraMis, ConnectionPdfs, LightSamplePdfs, MisFactors, SubpathMis, connection_weight,
    light_sample_weight, merge_weight,
};
use crate::lambert::continuation::Continuations;
use crate::lambert::light_sample::{LightInputs, light_samples};
use crate::lambert::shadow_rays::ShadowLanes;
use crate::lambert::surface::{SurfaceInputs, Vertex};
use crate::lambert::{Arrivals, LambertLanes, lane_of, start_vertices};
use crate::lanes::{F32s, LANES, Mask, Vec3s};
use crate::light_vertex_cache::LightVertex;
use crate::surface_hit::{Hit, SurfaceHit};
use crate::vertex_numbers::{CAMERA_LANES, Draw};
use crate::wave::LaneShading;

/// The camera pass's vertices in lanes, where the frame and the scene allow them.
pub(super) struct CameraLanes<'a> {
    iterations: &'a [CameraContext<'a>],
    tables: Option<&'a LambertLanes>,
}

impl<'a> CameraLanes<'a> {
    /// The lanes of a camera pass over `iterations`: where the scene allows them and the
    /// algorithm connects (BPT and VCM; light tracing's camera paths only find emission, and
    /// BPM's and PPM's neither connect nor sample lights).
    pub fn new(iterations: &'a [CameraContext<'a>]) -> CameraLanes<'a> {
        let ctx = &iterations[0];
        let applies = ctx.plan.connects && ctx.settings.algorithm != Algorithm::LightTracing;
        CameraLanes {
            iterations,
            tables: ctx.lanes.filter(|_| applies),
        }
    }

    /// A plain Lambert surface that does not emit, with room left for another segment.
    #[inline]
    fn takes_vertex(&self, path: &CameraPathState, hit: Hit) -> bool {
        self.tables.is_some_and(|tables| {
            let ctx = &self.iterations[path.sample as usize];
            path.walk.segments < ctx.max_segments() && tables.takes_surface(hit)
        })
    }
}

/// Where nothing merges, the lanes' vertices are not prepared ahead: they pick the light
/// vertices they connect to themselves.
impl LaneShading<CameraPathState, SurfaceHit> for CameraLanes<'_> {
    #[inline]
    fn takes(&self, path: &CameraPathState, hit: Hit) -> bool {
        self.takes_vertex(path, hit)
    }

    /// The light vertices the vertex connects to start loading (as [`super::prepare`]).
    fn prepare(&self, path: &mut CameraPathState, _: Hit) {
        pick_and_prefetch(&self.iterations[path.sample as usize], path);
    }

    fn shade(
        &self,
        paths: &mut [CameraPathState],
        group: &[(usize, Hit)],
        _: &[(usize, SurfaceHit)],
    ) {
        if let Some(tables) = self.tables {
            shade(tables, self.iterations, (paths, group), None);
        }
    }
}

/// Where the algorithm merges, the lanes' vertices are prepared ahead as the others are
/// ([`MergingHit`]: the connections' picks and the light vertices within the radius).
impl LaneShading<CameraPathState, MergingHit> for CameraLanes<'_> {
    const PREPARED: bool = true;

    #[inline]
    fn takes(&self, path: &CameraPathState, hit: Hit) -> bool {
        self.takes_vertex(path, hit)
    }

    fn shade(
        &self,
        paths: &mut [CameraPathState],
        group: &[(usize, Hit)],
        prepared: &[(usize, MergingHit)],
    ) {
        if let Some(tables) = self.tables {
            let found = |lane: usize| &prepared[lane.min(prepared.len() - 1)].1.found;
            shade(tables, self.iterations, (paths, group), Some(&found));
        }
    }
}

/// Shades `paths[i]` at `hit` for each `(i, hit)` of `group` (at most [`LANES`]), as
/// [`super::shade`] would; where merging, with the light vertices `found(lane)` found within
/// the radius of each lane's vertex.
fn shade<'f>(
    tables: &LambertLanes,
    iterations: &[CameraContext],
    (paths, group): (&mut [CameraPathState], &[(usize, Hit)]),
    found: Option<&dyn Fn(usize) -> &'f Neighbours>,
) {
    let numbers = start_vertices((paths, group), &CAMERA_LANES);
    let at = |lane: usize| lane_of(group, lane);
    let ctx = |lane: usize| &iterations[paths[at(lane).0].sample as usize];
    let scene = iterations[0].scene;
    let light_pick = numbers.first(Draw::LightPick);
    let mut light = LightInputs::default();
    let mut mis = SubpathMis::<F32s>::default();
    let mut t = F32s::default();
    let arrivals = Arrivals::gather((tables, scene), (paths, group), |lane, hit, path| {
        light.gather(tables, scene, lane, light_pick.0[lane]);
        mis.set(lane, &path.walk.mis.subpath);
        t.0[lane] = hit.t;
    });
    let Arrivals { vertex, throughput } = arrivals;
    let factors = MisFactors::lanes(|lane| &ctx(lane).factors);
    mis.arrive(Some(t * t), vertex.cos_geometric_out());
    // Lanes where a delta light's sample is its path's only technique (as `light_sample`).
    let only_for_delta = Mask::from_bools(std::array::from_fn(|lane| {
        let segments = paths[at(lane).0].walk.segments;
        ctx(lane).factors.only_delta_light_sample(segments)
    }));
    let sample = light_samples(
        (scene, &vertex, &light),
        throughput,
        (numbers.pair(Draw::LightPoint), true),
        |illumination, eval, light_pdf_w| {
            let pdfs = LightSamplePdfs {
                direct_pdf_w: light_pdf_w,
                emission_pdf_w: illumination.emission_pdf_w * light.pick_pmf,
                cos_at_light: illumination.cos_at_light,
                cos_at_receiver: vertex.cos_geometric(illumination.direction),
                // No BSDF sample hits a delta light.
                bsdf_fwd_pdf_w: illumination.delta.select(F32s::splat(0.0), eval.pdf),
                bsdf_rev_pdf_w: eval.pdf_rev,
            };
            let weight = light_sample_weight(&mis, &pdfs, &factors);
            (illumination.delta & only_for_delta).select(F32s::splat(1.0), weight)
        },
    );
    let picks: [CachePicks; LANES] = std::array::from_fn(|lane| {
        let picks = paths[at(lane).0].picks.clone();
        picks.expect("a vertex in lanes is prepared")
    });
    let most = picks.iter().map(|p| p.count).max().unwrap_or(0);
    // One connection per vertex by default (`--connections`): kept inline, not allocated
    // for every group.
    let connected: SmallVec<[ShadowLanes; 1]> = (0..most as usize)
        .filter_map(|k| {
            let pick: [Pick; LANES] = std::array::from_fn(|lane| {
                let ctx = ctx(lane);
                let light = &ctx.cache.vertices()[picks[lane].indices().nth(k)?];
                let segments = paths[at(lane).0].walk.segments;
                let length = segments.saturating_add(light.path_length.get() + 1);
                (length <= ctx.max_segments()).then_some((ctx, light))
            });
            let any = pick.iter().any(Option::is_some);
            let lanes = (tables, &vertex);
            any.then(|| connections(lanes, &pick, (throughput, &mis, &factors)))
        })
        .collect();
    let merged = found.map(|found| {
        let segments = std::array::from_fn(|lane| paths[at(lane).0].walk.segments);
        let triangles = std::array::from_fn(|lane| at(lane).1.triangle);
        merges(
            (&ctx, segments, triangles),
            (&vertex, &mis, &factors),
            found,
        )
    });
    let continuations = Continuations::sample(
        &vertex,
        throughput,
        &numbers,
        (TransportMode::Radiance, true),
    );
    // With d_VC without the merge here, for the emission the next segment may find.
    let (next_mis, next_beside) = continuations.scattered_mis(&vertex, &mis, &factors);
    for (lane, &(i, _)) in group.iter().enumerate() {
        let path = &mut paths[i];
        path.picks = None;
        if !vertex.alive.get(lane) {
            path.alive = false;
            continue;
        }
        if let Some(merged) = &merged {
            path.radiance += throughput.lane(lane) * merged.lane(lane);
        }
        // One push per ray: `extend` from an iterator did not inline.
        let rays = std::iter::once(&sample).chain(&connected);
        for ray in rays.filter_map(|shadows| shadows.ray(lane)) {
            path.shadows.push(ray);
        }
        let next = CameraMis {
            subpath: next_mis.lane(lane),
            d_vc_beside_light: next_beside.0[lane],
        };
        path.alive = continuations.go_on(lane, &mut path.walk, next);
    }
}

/// Merging at each lane's vertex ([`super::merge`]) with the light vertices `found(lane)`
/// within the radius, for camera paths of `segments` segments with MIS quantities `mis`, at
/// vertices on `triangles`: the MIS-weighted density estimate per unit throughput. Each lane
/// adds its vertices' terms in their order, the k-th of every lane at once.
#[inline(always)]
fn merges<'c, 'f>(
    (ctx, segments, triangles): (
        &impl Fn(usize) -> &'c CameraContext<'c>,
        [u32; LANES],
        [u32; LANES],
    ),
    (vertex, mis, factors): (&Vertex, &SubpathMis<F32s>, &MisFactors<F32s>),
    found: &dyn Fn(usize) -> &'f Neighbours,
) -> Vec3s {
    let most = (0..LANES).map(|lane| found(lane).len()).max().unwrap_or(0);
    let mut sum = Vec3s::default();
    for k in 0..most {
        let (mut wo, mut light_throughput) = (Vec3s::default(), Vec3s::default());
        let mut light_mis = SubpathMis::<F32s>::default();
        let mut cos_light = F32s::splat(1.0);
        let mut merging = [false; LANES];
        for (lane, merges) in merging.iter_mut().enumerate() {
            let ctx = ctx(lane);
            let Some(&i) = found(lane).get(k) else {
                continue;
            };
            let light = &ctx.cache.vertices()[i as usize];
            if segments[lane].saturating_add(light.path_length.get()) > ctx.max_segments() {
                continue;
            }
            let known = (triangles[lane], vertex.n_g.lane(lane));
            cos_light.0[lane] = light.cos_on_arrival(&ctx.scene.mesh, known);
            *merges = cos_light.0[lane] != 0.0;
            wo.set(lane, light.wo);
            light_throughput.set(lane, light.throughput);
            light_mis.set(lane, &light.mis);
        }
        let eval = vertex.eval(wo, TransportMode::Radiance, true);
        let weight = merge_weight(mis, &light_mis, eval.pdf, eval.pdf_rev, factors);
        // The photon's flux weighs f·|ωi·n_s| / |ωi·n_g|, n_g its own surface's (see `merge`).
        let term = light_throughput.mul(eval.f_cos).scale(weight / cos_light);
        let adds = Mask::from_bools(merging) & eval.valid & eval.f_cos.is_nonzero();
        sum = adds.select3(sum + term, sum);
    }
    let radius = F32s::from_fn(|lane| ctx(lane).radius);
    sum.div(F32s::splat(PI) * radius * radius * factors.light_paths)
}

/// The light vertex a lane connects to, with its iteration.
type Pick<'c> = Option<(&'c CameraContext<'c>, &'c LightVertex)>;

/// One connection per lane to the cached light vertex `picks[lane]` (`connect`), for camera
/// vertices with throughput `throughput` and MIS quantities `mis`. Light vertices on plain
/// Lambert surfaces are evaluated in the lanes, the others by the general BSDF.
#[inline(always)]
fn connections(
    (tables, vertex): (&LambertLanes, &Vertex),
    picks: &[Pick; LANES],
    (throughput, mis, factors): (Vec3s, &SubpathMis<F32s>, &MisFactors<F32s>),
) -> ShadowLanes {
    let first = picks.iter().flatten().next().expect("a lane connects").0;
    let scene = first.scene;
    let (mut position, mut wo) = (Vec3s::default(), Vec3s::default());
    let mut light_throughput = Vec3s::default();
    let (mut light_mis, mut scale) = (SubpathMis::<F32s>::default(), F32s::default());
    let (mut connects, mut lambert) = ([false; LANES], [false; LANES]);
    // The factors at each lane's light vertex (lanes without one take the first's).
    let mut light_factors = [first.factors; LANES];
    // Lanes without a Lambert light vertex keep zero inputs: their lane values are replaced
    // or dropped.
    let mut light_surface = SurfaceInputs::default();
    for (lane, pick) in picks.iter().enumerate() {
        let Some((ctx, light)) = pick else {
            continue;
        };
        connects[lane] = true;
        position.set(lane, light.position);
        wo.set(lane, light.wo);
        light_throughput.set(lane, light.throughput);
        light_mis.set(lane, &light.mis);
        light_factors[lane] = ctx.factors.at_light_vertex(light.path_length.get());
        // c = (1 / N_c) · (N_v / N_p): each pick stands for N_v / N_c vertices of N_p paths.
        let connections = ctx.settings.connections as f32;
        scale.0[lane] = ctx.cache.len() as f32 / (connections * ctx.factors.light_paths);
        if tables.material_of(scene, light.triangle).is_some() {
            light_surface.gather(tables, scene, lane, (light.triangle, light.u, light.v));
            lambert[lane] = true;
        }
    }
    let zero = F32s::splat(0.0);
    let to_light: Vec3s = position - vertex.position;
    let distance_sq = to_light.length_squared();
    let direction = to_light.div(distance_sq.sqrt());
    let camera = vertex.eval(direction, TransportMode::Radiance, true);
    let camera_ok = vertex.alive
        & Mask::from_bools(connects)
        & !distance_sq.eq(zero)
        & camera.valid
        & camera.f_cos.is_nonzero();
    let light_vertex = Vertex::new(&light_surface, wo, Mask::from_bools(lambert));
    let mut light = light_vertex.eval(-direction, TransportMode::Importance, true);
    let mut light_ok = light_vertex.alive.bools();
    for (ok, &valid) in light_ok.iter_mut().zip(&light.valid.bools()) {
        *ok &= valid;
    }
    let mut light_cos = light_vertex.cos_geometric(direction);
    let mut target = light_vertex.spawn(-direction);
    for (lane, pick) in picks.iter().enumerate() {
        if let Some((_, light_vertex)) = pick
            && !lambert[lane]
            && camera_ok.get(lane)
        {
            let side = general_light_side(scene, light_vertex, direction.lane(lane));
            light.f_cos.set(lane, side.f_cos);
            (light.pdf.0[lane], light.pdf_rev.0[lane]) = (side.pdf_fwd, side.pdf_rev);
            light_cos.0[lane] = side.cos_geometric;
            target.set(lane, side.target);
            light_ok[lane] = true;
        }
    }
    let pdfs = ConnectionPdfs {
        camera_fwd_pdf_a: camera.pdf * light_cos / distance_sq,
        camera_rev_pdf_w: camera.pdf_rev,
        light_fwd_pdf_a: light.pdf * vertex.cos_geometric(direction) / distance_sq,
        light_rev_pdf_w: light.pdf_rev,
    };
    let light_factors = MisFactors::lanes(|lane| &light_factors[lane]);
    let weight = connection_weight((mis, &light_mis), &pdfs, (factors, &light_factors));
    ShadowLanes {
        queued: camera_ok & Mask::from_bools(light_ok) & light.f_cos.is_nonzero(),
        origin: vertex.spawn(direction),
        target,
        distant: Mask::none(),
        contribution: throughput
            .mul(light_throughput)
            .mul(camera.f_cos)
            .mul(light.f_cos)
            .scale(weight * scale / distance_sq),
    }
}

/// A light vertex's BSDF toward a connection along `direction` (from the camera vertex),
/// by the general code: the light vertex's material is not plain Lambert.
struct LightSide {
    f_cos: Vec3,
    pdf_fwd: f32,
    pdf_rev: f32,
    /// |cos| of `direction` with the light vertex's geometric normal.
    cos_geometric: f32,
    /// The shadow ray's end, offset off the light vertex's surface.
    target: Vec3,
}

/// `connect`'s light side for `vertex`, seen along `direction`.
fn general_light_side(
    scene: &vcm_scene::Scene,
    vertex: &LightVertex,
    direction: Vec3,
) -> LightSide {
    let surface = SurfaceHit::new(scene, vertex.triangle, vertex.u, vertex.v);
    let bsdf = scene.bsdf(&surface.point);
    let eval = bsdf.eval(vertex.wo, -direction, TransportMode::Importance);
    LightSide {
        f_cos: eval.f_cos,
        pdf_fwd: eval.pdf_fwd,
        pdf_rev: eval.pdf_rev,
        cos_geometric: surface.cos_geometric(direction),
        target: surface.spawn(-direction),
    }
}
