//! The path tracer's vertex ([`crate::shade::shade`]) on plain Lambert surfaces, in lanes:
//! a light sample weighted against BSDF sampling by the power heuristic (Veach 1997 eq.
//! 9.13), its shadow ray, and the cosine-weighted continuation with Russian roulette.

use vcm_scene::Scene;
use vcm_scene::bsdf::TransportMode;
use vcm_scene::sampling::{SobolSampler, power_heuristic};

use super::LambertLanes;
use super::light_sample::{LightInputs, illuminate};
use super::surface::{Scattered, SurfaceInputs, Vertex};
use crate::lanes::{F32s, LANES, Mask, Vec3s};
use crate::path_state::{PathState, SegmentOrigin, ShadowRay};
use crate::shade::vertex_sampler;
use crate::shadow::segment_to;
use crate::surface_hit::Hit;
use crate::vertex_numbers::{Draw, LAMBERT_CAMERA_DRAWS, PATH_TRACER};
use crate::wave::LaneShading;

/// [`LambertLanes`] at work in one pass of the path tracer.
pub(crate) struct LambertShading<'a> {
    /// The tables, where the scene allows shading in lanes.
    pub tables: Option<&'a LambertLanes>,
    /// The scene being rendered.
    pub scene: &'a Scene,
    /// Longest path in segments (`u32::MAX`: unlimited).
    pub max_segments: u32,
}

impl LaneShading<PathState> for LambertShading<'_> {
    /// A plain Lambert surface that does not emit, with room left for another segment.
    #[inline]
    fn takes(&self, path: &PathState, hit: Hit) -> bool {
        self.tables
            .is_some_and(|tables| path.segments < self.max_segments && tables.takes_surface(hit))
    }

    fn shade(&self, paths: &mut [PathState], group: &[(usize, Hit)]) {
        if let Some(tables) = self.tables {
            shade(tables, self.scene, paths, group);
        }
    }
}

/// Shades `paths[i]` at `hit` for each `(i, hit)` of `group` (at most [`LANES`]), as
/// [`crate::shade::shade`] would.
fn shade(tables: &LambertLanes, scene: &Scene, paths: &mut [PathState], group: &[(usize, Hit)]) {
    debug_assert!(!group.is_empty() && group.len() <= LANES);
    for &(i, _) in group {
        vertex_sampler(&mut paths[i]);
    }
    // Lanes past the group repeat its last path; their results are dropped.
    let at = |lane: usize| group[lane.min(group.len() - 1)];
    let samplers = std::array::from_fn(|lane| &paths[at(lane).0].rng);
    let numbers = SobolSampler::peek_lanes(
        samplers,
        const { PATH_TRACER.indices(LAMBERT_CAMERA_DRAWS) },
    );
    let pair = |k: usize| (F32s(numbers[k][0]), F32s(numbers[k][1]));
    let mut surface = SurfaceInputs::default();
    let mut light = LightInputs::default();
    let (mut direction, mut throughput) = (Vec3s::default(), Vec3s::default());
    for (lane, &u_pick) in numbers[0][0].iter().enumerate() {
        let (i, hit) = at(lane);
        surface.gather(tables, scene, lane, (hit.triangle, hit.u, hit.v));
        light.gather(tables, scene, lane, u_pick);
        direction.set(lane, paths[i].direction);
        throughput.set(lane, paths[i].throughput);
    }
    let vertex = Vertex::new(&surface, -direction, Mask::first(group.len()));
    let shadow = light_sample(&vertex, &surface, &light, throughput, pair(1));
    let next = vertex.sample(surface.f, pair(2), TransportMode::Radiance, false);
    let continuation = Continuation {
        throughput: throughput.mul(next.eval.f_cos.div(next.eval.pdf)),
        origin: vertex.spawn(next.wi),
        roulette_numbers: F32s(numbers[3][0]),
        next,
    };
    for (lane, &(i, _)) in group.iter().enumerate() {
        continuation.write(&mut paths[i], lane, &shadow);
    }
}

/// `next_event`: one light sample, its contribution and its shadow ray.
#[inline(always)]
fn light_sample(
    vertex: &Vertex,
    surface: &SurfaceInputs,
    light: &LightInputs,
    throughput: Vec3s,
    numbers: (F32s, F32s),
) -> LaneShadow {
    let illumination = illuminate(light, vertex, numbers);
    let direction = illumination.direction;
    let eval = vertex.eval(surface.f, direction, TransportMode::Radiance, false);
    let light_pdf_w = illumination.direct_pdf_w * light.pick_pmf;
    let weight = power_heuristic(1.0, light_pdf_w, 1.0, eval.pdf);
    let contribution = throughput
        .mul(light.emission)
        .mul(eval.f_cos)
        .scale(weight / light_pdf_w);
    LaneShadow {
        queued: vertex.alive & illumination.lit & eval.valid & eval.f_cos.is_nonzero(),
        origin: vertex.spawn(direction),
        target: illumination.target,
        contribution,
    }
}

/// The lanes' shadow rays.
struct LaneShadow {
    queued: Mask,
    origin: Vec3s,
    target: Vec3s,
    contribution: Vec3s,
}

/// The lanes' next segments, before Russian roulette.
struct Continuation {
    next: Scattered,
    throughput: Vec3s,
    origin: Vec3s,
    roulette_numbers: F32s,
}

impl Continuation {
    /// Writes lane `lane`'s results into its path: the shadow ray, Russian roulette (which
    /// draws a number only where it plays) and the next segment, and moves the path's
    /// numbers past those it drew.
    fn write(&self, path: &mut PathState, lane: usize, shadow: &LaneShadow) {
        path.shadow = shadow.queued.get(lane).then(|| {
            let origin = shadow.origin.lane(lane);
            let (direction, tmax) = segment_to(origin, shadow.target.lane(lane));
            ShadowRay {
                origin,
                direction,
                tmax,
                contribution: shadow.contribution.lane(lane),
            }
        });
        // Light pick, light point, lobe and direction.
        path.rng.skip(const { PATH_TRACER.index(Draw::Roulette) });
        if !self.next.valid.get(lane) {
            path.alive = false;
            return;
        }
        let mut throughput = self.throughput.lane(lane);
        path.segment_origin = SegmentOrigin::Bsdf {
            pdf_w: self.next.eval.pdf.0[lane],
        };
        let roulette_number = self.roulette_numbers.0[lane];
        let mut drawn = false;
        let survives = path.roulette.survives(path.segments, &mut throughput, || {
            drawn = true;
            roulette_number
        });
        path.rng.skip(u32::from(drawn));
        path.throughput = throughput;
        path.alive = survives;
        if survives {
            path.origin = self.origin.lane(lane);
            path.direction = self.next.wi.lane(lane);
            path.segments += 1;
        }
    }
}
