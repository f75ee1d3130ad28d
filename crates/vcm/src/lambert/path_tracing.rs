//! The path tracer's vertex ([`crate::shade::shade`]) on plain Lambert surfaces, in lanes:
//! a light sample weighted against BSDF sampling by the power heuristic (Veach 1997 eq.
//! 9.13), its shadow ray, and the cosine-weighted continuation with Russian roulette.

use vcm_scene::Scene;
use vcm_scene::bsdf::TransportMode;
use vcm_scene::sampling::power_heuristic;

use super::continuation::Continuations;
use super::light_sample::{LightInputs, light_samples};
use super::{Arrivals, LambertLanes, start_vertices};
use crate::lanes::F32s;
use crate::path_state::{PathState, SegmentOrigin};
use crate::surface_hit::Hit;
use crate::vertex_numbers::{Draw, PATH_TRACER_LANES};
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

impl<T> LaneShading<PathState, T> for LambertShading<'_> {
    /// A plain Lambert surface that does not emit, with room left for another segment.
    #[inline]
    fn takes(&self, path: &PathState, hit: Hit) -> bool {
        self.tables.is_some_and(|tables| {
            path.walk.segments < self.max_segments && tables.takes_surface(hit)
        })
    }

    fn shade(&self, paths: &mut [PathState], group: &[(usize, Hit)], _: &[(usize, T)]) {
        if let Some(tables) = self.tables {
            shade(tables, self.scene, paths, group);
        }
    }
}

/// Shades `paths[i]` at `hit` for each `(i, hit)` of `group` (at most
/// [`LANES`](crate::lanes::LANES)), as [`crate::shade::shade`] would.
fn shade(tables: &LambertLanes, scene: &Scene, paths: &mut [PathState], group: &[(usize, Hit)]) {
    let numbers = start_vertices((paths, group), &PATH_TRACER_LANES);
    let light_pick = numbers.first(Draw::LightPick);
    let mut light = LightInputs::default();
    let arrivals = Arrivals::gather((tables, scene), (paths, group), |lane, _, _| {
        light.gather(tables, scene, lane, light_pick.0[lane])
    });
    let Arrivals { vertex, throughput } = arrivals;
    let shadows = light_samples(
        (scene, &vertex, &light),
        throughput,
        (numbers.pair(Draw::LightPoint), false),
        // Full weight for delta lights, which BSDF sampling cannot reach.
        |illumination, eval, light_pdf_w| {
            let weight = power_heuristic(1.0, light_pdf_w, 1.0, eval.pdf);
            illumination.delta.select(F32s::splat(1.0), weight)
        },
    );
    let continuations = Continuations::sample(
        &vertex,
        throughput,
        &numbers,
        (TransportMode::Radiance, false),
    );
    let pdf_w = continuations.next.eval.pdf;
    for (lane, &(i, _)) in group.iter().enumerate() {
        let path = &mut paths[i];
        path.shadow = shadows.ray(lane);
        let mis = SegmentOrigin::Bsdf {
            pdf_w: pdf_w.0[lane],
        };
        path.alive = continuations.go_on(lane, &mut path.walk, mis);
    }
}
