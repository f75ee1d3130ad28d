//! The light vertex ([`super::shade`]) on plain Lambert surfaces, in lanes
//! ([`crate::lambert`]): the vertex kept for the cache, its connection to the camera (a
//! light tracing splat weighted by VCM's MIS), and the continuation in importance transport
//! with the MIS quantities' update and Russian roulette.

use glam::UVec2;
use vcm_scene::bsdf::TransportMode;

use super::{LightPathState, Splat, path_length};
use crate::bidir::mis::{MisFactors, SubpathMis, camera_connection_weight};
use crate::bidir::{Algorithm, FrameContext, VcmSettings};
use crate::lambert::continuation::Continuations;
use crate::lambert::shadow_rays::ShadowLanes;
use crate::lambert::surface::Vertex;
use crate::lambert::{Arrivals, LambertLanes, lane_of, start_vertices};
use crate::lanes::{F32s, LANES, Mask, Vec3s};
use crate::light_vertex_cache::LightVertex;
use crate::surface_hit::Hit;
use crate::vertex_numbers::LIGHT_LANES;
use crate::wave::LaneShading;

/// The light pass's vertices in lanes, where the scene allows them.
pub(super) struct LightLanes<'a> {
    pub iterations: &'a [FrameContext<'a>],
    /// Whether vertices are connected to the camera.
    pub splat: bool,
}

impl<T> LaneShading<LightPathState, T> for LightLanes<'_> {
    /// A plain Lambert surface that does not emit.
    #[inline]
    fn takes(&self, _: &LightPathState, hit: Hit) -> bool {
        let ctx = &self.iterations[0];
        ctx.lanes.is_some_and(|tables| tables.takes_surface(hit))
    }

    fn shade(&self, paths: &mut [LightPathState], group: &[(usize, Hit)], _: &[(usize, T)]) {
        if let Some(tables) = self.iterations[0].lanes {
            shade(tables, self, paths, group);
        }
    }
}

/// Shades `paths[i]` at `hit` for each `(i, hit)` of `group` (at most [`LANES`]), as
/// [`super::shade`] would.
fn shade(
    tables: &LambertLanes,
    lanes: &LightLanes,
    paths: &mut [LightPathState],
    group: &[(usize, Hit)],
) {
    let numbers = start_vertices((paths, group), &LIGHT_LANES);
    let at = |lane: usize| lane_of(group, lane);
    let samples: [usize; LANES] = std::array::from_fn(|lane| paths[at(lane).0].sample as usize);
    let ctx = |lane: usize| &lanes.iterations[samples[lane]];
    let scene = lanes.iterations[0].scene;
    let mut mis = SubpathMis::<F32s>::default();
    let mut distance_sq = F32s::default();
    let arrivals = Arrivals::gather((tables, scene), (paths, group), |lane, hit, path| {
        mis.set(lane, &path.walk.mis);
        // The first segment from a light at infinity has no length: × 1 leaves d_VCM
        // as is.
        let has_length = path.walk.segments > 1 || !path.from_infinity;
        distance_sq.0[lane] = if has_length { hit.t * hit.t } else { 1.0 };
    });
    let Arrivals { vertex, throughput } = arrivals;
    // The factors at each lane's vertex (beside the light on the path's first hit).
    let here: [MisFactors; LANES] = std::array::from_fn(|lane| {
        let segments = paths[at(lane).0].walk.segments;
        ctx(lane).factors.at_light_vertex(segments)
    });
    let factors = MisFactors::lanes(|lane| &here[lane]);
    mis.arrive(Some(distance_sq), vertex.cos_geometric_out());
    let splats = lanes
        .splat
        .then(|| camera_connections(&lanes.iterations[0], &vertex, (throughput, &mis, &factors)));
    let continuations = Continuations::sample(
        &vertex,
        throughput,
        &numbers,
        (TransportMode::Importance, true),
    );
    let (next_mis, _) = continuations.scattered_mis(&vertex, &mis, &factors);
    for (lane, &(i, hit)) in group.iter().enumerate() {
        let path = &mut paths[i];
        let max_segments = ctx(lane).max_segments();
        let splats_here = super::splats_here(ctx(lane), path);
        let walk = &mut path.walk;
        let light_vertex = LightVertex {
            position: vertex.position.lane(lane),
            wo: vertex.wo.lane(lane),
            throughput: walk.throughput,
            mis: mis.lane(lane),
            triangle: hit.triangle,
            u: hit.u,
            v: hit.v,
            path_length: path_length(walk.segments),
        };
        if walk.segments < max_segments && splats_here {
            path.splat = splats.as_ref().and_then(|s| s.splat(ctx(lane), lane));
        }
        path.vertex = Some(light_vertex);
        // A further vertex has segments + 1 segments, and using it takes one more.
        let continues = walk.segments.saturating_add(2) <= max_segments;
        path.alive = continues
            && vertex.alive.get(lane)
            && continuations.go_on(lane, walk, next_mis.lane(lane));
    }
}

/// The lanes' connections to the camera (`connect_to_camera`), before the projection.
struct CameraConnections {
    /// The light vertices.
    position: Vec3s,
    /// The shadow rays toward the camera.
    shadows: ShadowLanes,
}

/// The light vertices `vertex` connected to the camera of `ctx` (which all iterations
/// share), with the paths' throughput and MIS quantities.
#[inline(always)]
fn camera_connections(
    ctx: &FrameContext,
    vertex: &Vertex,
    (throughput, mis, factors): (Vec3s, &SubpathMis<F32s>, &MisFactors<F32s>),
) -> CameraConnections {
    let camera = &ctx.scene.camera;
    let to_camera = Vec3s::splat(camera.position) - vertex.position;
    let distance_sq = to_camera.length_squared();
    let direction = to_camera.div(distance_sq.sqrt());
    let eval = vertex.eval(direction, TransportMode::Importance, true);
    // The camera's solid-angle pdf per pixel sample is d_image² / (pixel_area · cos θ) with
    // d_image = 1 / cos θ; its area pdf at the vertex adds |cos θ_surface| / d².
    let cos_camera = Vec3s::splat(camera.forward).dot(-direction);
    let cubed = F32s::from_fn(|lane| cos_camera.0[lane].powi(3));
    let camera_pdf_w = F32s::splat(1.0) / (F32s::splat(ctx.projection.pixel_area()) * cubed);
    let camera_pdf_a = camera_pdf_w * vertex.cos_geometric(direction) / distance_sq;
    let weight = if ctx.settings.algorithm == Algorithm::LightTracing {
        F32s::splat(1.0)
    } else {
        camera_connection_weight(mis, camera_pdf_a, eval.pdf_rev, factors)
    };
    CameraConnections {
        position: vertex.position,
        shadows: ShadowLanes {
            queued: vertex.alive & eval.valid & eval.f_cos.is_nonzero(),
            origin: vertex.spawn(direction),
            target: Vec3s::splat(camera.position),
            distant: Mask::none(),
            contribution: throughput
                .mul(eval.f_cos)
                .scale(weight * camera_pdf_w / (distance_sq * factors.light_paths)),
        },
    }
}

impl CameraConnections {
    /// Lane `lane`'s splat in iteration `ctx`, if it connected and projects into the image.
    fn splat(&self, ctx: &FrameContext, lane: usize) -> Option<Splat> {
        let VcmSettings { width, height, .. } = *ctx.settings;
        let ray = self.shadows.ray(lane)?;
        let raster = ctx.projection.raster_of(self.position.lane(lane))?;
        let pixel = raster.as_uvec2().min(UVec2::new(width - 1, height - 1));
        Some(Splat {
            pixel: pixel.y * width + pixel.x,
            ray,
        })
    }
}
