//! Light samples for next event estimation and the shadow rays that test them: from an
//! offset receiver to a light sample.

use glam::Vec3;
use vcm_scene::Scene;
use vcm_scene::bsdf::{BsdfEval, FixedOutgoing, Pdfs, TransportMode};
use vcm_scene::light::{Illumination, Light};
use vcm_scene::sampling::Sampler;

use crate::medium::Medium;
use crate::path_state::ShadowRay;
use crate::ray_offset::{barycentric_error, offset_ray_origin};
use crate::surface_hit::SurfaceHit;

/// A light sample seen from a camera path's vertex, with the BSDF's response toward it.
pub(crate) struct LightSample<'a> {
    /// The light picked.
    pub light: &'a Light,
    /// Probability of picking `light`.
    pub pick_pmf: f32,
    /// The sampled point on the light as seen from the receiver.
    pub illumination: Illumination,
    /// The receiver's BSDF (radiance transport) toward the light, with the pdfs asked for.
    pub eval: BsdfEval,
}

impl LightSample<'_> {
    /// Picks a light by power and a point on it with three numbers from `rng`, seen from
    /// `surface` whose BSDF `seen` has its outgoing direction toward the previous vertex,
    /// evaluating the BSDF's `pdfs`; `None` when the sample cannot contribute.
    pub fn sample<'a>(
        scene: &'a Scene,
        rng: &mut impl Sampler,
        surface: &SurfaceHit,
        seen: &FixedOutgoing,
        pdfs: Pdfs,
    ) -> Option<LightSample<'a>> {
        let (u_pick, u_light) = (rng.uniform(), rng.uniform2());
        let (index, pick_pmf) = scene.light_sampler.sample(u_pick)?;
        let light = &scene.lights[index];
        let receiver = surface.point.position;
        let illumination = light.illuminate(&scene.textures, receiver, u_light)?;
        let eval = seen.eval(illumination.direction, TransportMode::Radiance, pdfs);
        (eval.f_cos != Vec3::ZERO).then_some(LightSample {
            light,
            pick_pmf,
            illumination,
            eval,
        })
    }

    /// The fraction of the light that crosses the segment from `surface` to the sample, for
    /// a path that reached `surface` through `medium`.
    pub fn transmittance(&self, scene: &Scene, surface: &SurfaceHit, medium: Medium) -> Vec3 {
        let to_light = self.illumination.direction;
        medium
            .toward(scene, &surface.point, to_light)
            .transmittance(self.illumination.distance)
    }

    /// Solid-angle pdf of the sample at the receiver, with the light's selection probability.
    pub fn direct_pdf_w(&self) -> f32 {
        self.illumination.direct_pdf_w * self.pick_pmf
    }

    /// The shadow ray from `surface` to the sample, adding `contribution` when unoccluded.
    pub fn shadow_ray(&self, surface: &SurfaceHit, contribution: Vec3) -> ShadowRay {
        let origin = surface.spawn(self.illumination.direction);
        let receiver = surface.point.position;
        let (direction, tmax) = shadow_segment(self.light, &self.illumination, receiver, origin);
        ShadowRay {
            origin,
            direction,
            tmax,
            contribution,
        }
    }
}

/// Direction and `tmax` of a shadow ray from `origin` (already offset off the
/// receiving surface) toward the light sample `illumination` of `light`, seen from the
/// un-offset receiving point `receiver`.
///
/// Finite lights: the direction reaches the light sample at t = 1, where the ray stops; an
/// area light's sample point is first offset off the emitting triangle toward the receiver by
/// its own error bound. Distant lights: a unit direction and an unbounded ray.
fn shadow_segment(
    light: &Light,
    illumination: &Illumination,
    receiver: Vec3,
    origin: Vec3,
) -> (Vec3, f32) {
    match shadow_target(light, illumination, receiver) {
        Some(target) => segment_to(origin, target),
        None => (illumination.direction, f32::INFINITY),
    }
}

/// Where a shadow ray from `receiver` toward the light sample `illumination` of `light` ends:
/// the sample point, offset off an area light's triangle toward the receiver; `None` for
/// distant lights, whose rays are unbounded.
pub(crate) fn shadow_target(
    light: &Light,
    illumination: &Illumination,
    receiver: Vec3,
) -> Option<Vec3> {
    illumination.distance.is_finite().then(|| {
        let target = receiver + illumination.direction * illumination.distance;
        offset_off_light(light, target, -illumination.direction)
    })
}

/// `point` on `light`, offset off an area light's triangle to the side of direction `w` by its
/// error bound (point-like lights have no surface to leave).
pub(crate) fn offset_off_light(light: &Light, point: Vec3, w: Vec3) -> Vec3 {
    match light {
        // Any barycentrics are ≤ 1, so b = (1, 1, 1) bounds the sample point's error.
        Light::Area(area) => offset_ray_origin(
            point,
            barycentric_error(&area.corners, Vec3::ONE),
            area.normal,
            w,
        ),
        _ => point,
    }
}

/// Direction and `tmax` of an occlusion ray from `origin` to `target` (both already offset
/// off their surfaces, or points in space such as a point light or the camera): the direction
/// reaches `target` at t = 1 and the ray stops γ(16) ≈ 10⁻⁶ before it.
///
/// The target's offset keeps its surface beyond t = 1, but the hit distance a traversal
/// computes for that surface carries a rounding error relative to the whole segment, which the
/// offset (relative to the coordinates) does not cover on long rays; γ(16) does. A fixed
/// 10⁻⁴ of the segment used to let light through a wall 10⁻⁵ from a point light.
pub(crate) fn segment_to(origin: Vec3, target: Vec3) -> (Vec3, f32) {
    (target - origin, 1.0 - crate::ray_offset::gamma(16))
}
