//! Shading one path vertex: emission found by the path, one light sample (next event
//! estimation) and the continuation by BSDF sampling.
//!
//! MIS combines the two ways a path can reach an area light or the environment, BSDF
//! sampling (pdf p_bsdf in solid angle) and light sampling (p_light = pick pmf × area pdf ×
//! d² / cos θ_light, the area-to-solid-angle conversion of Veach 1997 eq. 8.10; for the
//! environment pick pmf × its direction pdf), with the power heuristic
//! w_i = p_i² / (p_bsdf² + p_light²) (Veach 1997 eq. 9.13), one sample of each technique.

use glam::Vec3;
use vcm_scene::Scene;
use vcm_scene::bsdf::{FixedOutgoing, LobeKind, Pdfs, TransportMode};
use vcm_scene::mesh::SurfacePoint;
use vcm_scene::sampling::{SobolSampler, power_heuristic};

use crate::path_state::{PathState, SegmentOrigin, ShadowRay};
use crate::shadow::LightSample;
use crate::surface_hit::{Hit, SurfaceHit};
use crate::vertex_numbers::PATH_TRACER;
use crate::walk::Walk;

/// What shading needs besides the path: the scene and the path length limit.
pub(crate) struct ShadeContext<'a> {
    /// The scene being rendered.
    pub scene: &'a Scene,
    /// Longest path in segments (`u32::MAX`: unlimited).
    pub max_segments: u32,
}

/// The sampler of `path`, moved to the numbers of the vertex it has reached
/// ([`PATH_TRACER`]'s layout).
pub(crate) fn vertex_sampler(path: &mut PathState) -> &mut SobolSampler {
    path.walk.start_vertex(PATH_TRACER.pairs())
}

/// Shades the vertex where `path` hit the scene (`None`: it escaped and ends). Adds the
/// weighted emission to the path's radiance, queues at most one shadow ray and either
/// prepares the next segment or ends the path.
pub(crate) fn shade(ctx: &ShadeContext, path: &mut PathState, hit: Option<(Hit, &SurfaceHit)>) {
    path.shadow = None;
    // `max_depth` 0 allows not even the camera segment.
    if path.walk.segments > ctx.max_segments {
        path.alive = false;
        return;
    }
    let Some((hit, surface)) = hit else {
        let walk = &path.walk;
        let transmittance = walk.medium.transmittance(f32::INFINITY);
        path.radiance += walk.throughput * transmittance * escaped(ctx.scene, walk);
        path.alive = false;
        return;
    };
    let scene = ctx.scene;
    vertex_sampler(path);
    path.walk.cross(hit.t);
    let point = surface.point;
    path.radiance += path.walk.throughput * emission(scene, &path.walk, &point, hit);

    // Both a light sample and a continuation add a segment.
    if path.walk.segments >= ctx.max_segments {
        path.alive = false;
        return;
    }
    let bsdf = scene.bsdf(&point);
    let Some(seen) = bsdf.fix_outgoing(-path.walk.direction) else {
        path.alive = false;
        return;
    };
    if bsdf.has_non_delta() {
        path.shadow = next_event(scene, &mut path.walk, surface, &seen);
    }
    path.alive = path
        .walk
        .scatter(
            scene,
            surface,
            &seen,
            (TransportMode::Radiance, Pdfs::Forward),
            |mis, sample| {
                *mis = if sample.lobe == LobeKind::Specular {
                    SegmentOrigin::Deterministic
                } else {
                    SegmentOrigin::Bsdf {
                        pdf_w: sample.pdf_fwd,
                    }
                };
            },
        )
        .is_some();
}

/// Emitted radiance toward the path at `point`, MIS-weighted against light sampling
/// (full weight after the camera and delta lobes, which light sampling cannot produce).
fn emission(scene: &Scene, walk: &Walk<SegmentOrigin>, point: &SurfacePoint, hit: Hit) -> Vec3 {
    let Some(emitted) = scene.emission_on_hit(hit.triangle, hit.u, hit.v, walk.direction) else {
        return Vec3::ZERO;
    };
    let SegmentOrigin::Bsdf { pdf_w } = walk.mis else {
        return emitted.radiance;
    };
    let light = scene
        .light_sampler
        .light_of_triangle(hit.triangle)
        .expect("an emitting triangle is an area light");
    let cos_at_light = point.geometric_normal.dot(-walk.direction).abs();
    // Light sampling's pdf of the same point in solid angle at the receiver (Veach eq. 8.10).
    let light_pdf_w =
        scene.light_sampler.pmf(light) * emitted.direct_pdf_a * hit.t * hit.t / cos_at_light;
    emitted.radiance * power_heuristic(1.0, pdf_w, 1.0, light_pdf_w)
}

/// Radiance from the environment toward a path that left the scene, MIS-weighted against
/// light sampling like [`emission`] (light sampling picks directions: no area conversion).
fn escaped(scene: &Scene, walk: &Walk<SegmentOrigin>) -> Vec3 {
    let Some((light, emitted)) = scene.emission_on_escape(walk.direction) else {
        return Vec3::ZERO;
    };
    let SegmentOrigin::Bsdf { pdf_w } = walk.mis else {
        return emitted.radiance;
    };
    let light_pdf_w = scene.light_sampler.pmf(light) * emitted.direct_pdf_a;
    emitted.radiance * power_heuristic(1.0, pdf_w, 1.0, light_pdf_w)
}

/// One light sample from `surface` (its BSDF `seen` from the path): the MIS-weighted
/// contribution and its shadow ray, or `None` when the sample cannot contribute.
fn next_event(
    scene: &Scene,
    walk: &mut Walk<SegmentOrigin>,
    surface: &SurfaceHit,
    seen: &FixedOutgoing,
) -> Option<ShadowRay> {
    // Path tracing weighs light samples against BSDF samples from the camera side only.
    let sample = LightSample::sample(scene, &mut walk.rng, surface, seen, Pdfs::Forward)?;
    let light_pdf_w = sample.direct_pdf_w();
    let weight = if sample.light.is_delta() {
        1.0
    } else {
        power_heuristic(1.0, light_pdf_w, 1.0, sample.eval.pdf_fwd)
    };
    let transmittance = sample.transmittance(scene, surface, walk.medium);
    let contribution = walk.throughput
        * transmittance
        * sample.illumination.value
        * sample.eval.f_cos
        * (weight / light_pdf_w);
    Some(sample.shadow_ray(surface, contribution))
}
