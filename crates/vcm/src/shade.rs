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
use vcm_scene::sampling::{Sampler, SobolSampler, power_heuristic};

use crate::path_state::{PathState, SegmentOrigin, ShadowRay};
use crate::shadow::LightSample;
use crate::surface_hit::{Hit, SurfaceHit};
use crate::vertex_numbers::PATH_TRACER;

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
    path.rng.start_step(path.segments, PATH_TRACER.pairs());
    &mut path.rng
}

/// Shades the vertex where `path` hit the scene (`None`: it escaped and ends). Adds the
/// weighted emission to the path's radiance, queues at most one shadow ray and either
/// prepares the next segment or ends the path.
pub(crate) fn shade(ctx: &ShadeContext, path: &mut PathState, hit: Option<(Hit, &SurfaceHit)>) {
    path.shadow = None;
    // `max_depth` 0 allows not even the camera segment.
    if path.segments > ctx.max_segments {
        path.alive = false;
        return;
    }
    let Some((hit, surface)) = hit else {
        let transmittance = path.medium.transmittance(f32::INFINITY);
        path.radiance += path.throughput * transmittance * escaped(ctx.scene, path);
        path.alive = false;
        return;
    };
    let scene = ctx.scene;
    vertex_sampler(path);
    path.throughput *= path.medium.transmittance(hit.t);
    let point = surface.point;
    path.radiance += path.throughput * emission(scene, path, &point, hit);

    // Both a light sample and a continuation add a segment.
    if path.segments >= ctx.max_segments {
        path.alive = false;
        return;
    }
    let bsdf = scene.bsdf(&point);
    let Some(seen) = bsdf.fix_outgoing(-path.direction) else {
        path.alive = false;
        return;
    };
    if bsdf.has_non_delta() {
        path.shadow = next_event(scene, path, surface, &seen);
    }
    path.alive = scatter(path, &seen, |w| surface.spawn(w));
    path.medium = path.medium.toward(scene, &point, path.direction);
}

/// Emitted radiance toward the path at `point`, MIS-weighted against light sampling
/// (full weight after the camera and delta lobes, which light sampling cannot produce).
fn emission(scene: &Scene, path: &PathState, point: &SurfacePoint, hit: Hit) -> Vec3 {
    let Some(emitted) = scene.emission_on_hit(hit.triangle, hit.u, hit.v, path.direction) else {
        return Vec3::ZERO;
    };
    let SegmentOrigin::Bsdf { pdf_w } = path.segment_origin else {
        return emitted.radiance;
    };
    let light = scene
        .light_sampler
        .light_of_triangle(hit.triangle)
        .expect("an emitting triangle is an area light");
    let cos_at_light = point.geometric_normal.dot(-path.direction).abs();
    // Light sampling's pdf of the same point in solid angle at the receiver (Veach eq. 8.10).
    let light_pdf_w =
        scene.light_sampler.pmf(light) * emitted.direct_pdf_a * hit.t * hit.t / cos_at_light;
    emitted.radiance * power_heuristic(1.0, pdf_w, 1.0, light_pdf_w)
}

/// Radiance from the environment toward a path that left the scene, MIS-weighted against
/// light sampling like [`emission`] (light sampling picks directions: no area conversion).
fn escaped(scene: &Scene, path: &PathState) -> Vec3 {
    let Some((light, emitted)) = scene.emission_on_escape(path.direction) else {
        return Vec3::ZERO;
    };
    let SegmentOrigin::Bsdf { pdf_w } = path.segment_origin else {
        return emitted.radiance;
    };
    let light_pdf_w = scene.light_sampler.pmf(light) * emitted.direct_pdf_a;
    emitted.radiance * power_heuristic(1.0, pdf_w, 1.0, light_pdf_w)
}

/// One light sample from `surface` (its BSDF `seen` from the path): the MIS-weighted
/// contribution and its shadow ray, or `None` when the sample cannot contribute.
fn next_event(
    scene: &Scene,
    path: &mut PathState,
    surface: &SurfaceHit,
    seen: &FixedOutgoing,
) -> Option<ShadowRay> {
    // Path tracing weighs light samples against BSDF samples from the camera side only.
    let sample = LightSample::sample(scene, &mut path.rng, surface, seen, Pdfs::Forward)?;
    let light_pdf_w = sample.direct_pdf_w();
    let weight = if sample.light.is_delta() {
        1.0
    } else {
        power_heuristic(1.0, light_pdf_w, 1.0, sample.eval.pdf_fwd)
    };
    let transmittance = sample.transmittance(scene, surface, path.medium);
    let contribution = path.throughput
        * transmittance
        * sample.illumination.value
        * sample.eval.f_cos
        * (weight / light_pdf_w);
    Some(sample.shadow_ray(surface, contribution))
}

/// Samples the BSDF (`seen` from the path) for the next segment and applies Russian
/// roulette; returns whether the path goes on.
fn scatter(path: &mut PathState, seen: &FixedOutgoing, spawn: impl Fn(Vec3) -> Vec3) -> bool {
    let (u_lobe, u_dir) = (path.rng.uniform(), path.rng.uniform2());
    let Some(sample) = seen.sample(u_lobe, u_dir, TransportMode::Radiance, Pdfs::Forward) else {
        return false;
    };
    path.throughput *= sample.f_cos / sample.pdf_fwd;
    path.segment_origin = if sample.lobe == LobeKind::Specular {
        SegmentOrigin::Deterministic
    } else {
        SegmentOrigin::Bsdf {
            pdf_w: sample.pdf_fwd,
        }
    };
    path.roulette.scattered(&sample, TransportMode::Radiance);
    let rng = &mut path.rng;
    if !path
        .roulette
        .survives(path.segments, &mut path.throughput, || rng.uniform())
    {
        return false;
    }
    path.origin = spawn(sample.wi);
    path.direction = sample.wi;
    path.segments += 1;
    true
}
