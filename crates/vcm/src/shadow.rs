//! Light samples for next event estimation and the shadow rays that test them: from an
//! offset receiver to a light sample.

use glam::Vec3;
use vcm_scene::Scene;
use vcm_scene::bsdf::{Bsdf, BsdfEval, TransportMode};
use vcm_scene::light::{Illumination, Light};
use vcm_scene::sampling::Rng;

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
    /// The receiver's BSDF (radiance transport) toward the light.
    pub eval: BsdfEval,
}

impl LightSample<'_> {
    /// Picks a light by power and a point on it with three numbers from `rng`, seen from
    /// `surface` whose BSDF is `bsdf` (`wo` toward the previous vertex); `None` when the
    /// sample cannot contribute.
    pub fn sample<'a>(
        scene: &'a Scene,
        rng: &mut Rng,
        surface: &SurfaceHit,
        bsdf: &Bsdf,
        wo: Vec3,
    ) -> Option<LightSample<'a>> {
        let (u_pick, u_light) = (rng.uniform(), rng.uniform2());
        let (index, pick_pmf) = scene.light_sampler.sample(u_pick)?;
        let light = &scene.lights[index];
        let receiver = surface.point.position;
        let illumination = light.illuminate(&scene.textures, receiver, u_light)?;
        let eval = bsdf.eval(wo, illumination.direction, TransportMode::Radiance);
        (eval.f_cos != Vec3::ZERO).then_some(LightSample {
            light,
            pick_pmf,
            illumination,
            eval,
        })
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
    if !illumination.distance.is_finite() {
        return (illumination.direction, f32::INFINITY);
    }
    let target = receiver + illumination.direction * illumination.distance;
    let target = offset_off_light(light, target, -illumination.direction);
    segment_to(origin, target)
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
/// reaches `target` at t = 1 and the ray stops there, t ∈ [0, 1).
///
/// No fraction of the segment is left out at the target's end: the offset already keeps its
/// surface beyond t = 1, and a blocker close to the target (a wall 10⁻⁵ from a point light)
/// must still block rays from far away.
pub(crate) fn segment_to(origin: Vec3, target: Vec3) -> (Vec3, f32) {
    (target - origin, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ray_offset::barycentric_error;
    use glam::Vec2;
    use vcm_scene::sampling::{Rng, sample_uniform_triangle};
    use vcm_traversal::{CpuBvh, CpuBvhOptions, RayBatch, Traversal};

    #[test]
    fn segments_to_offset_points_are_not_blocked_by_the_target_triangle_at_any_scale() {
        let mut rng = Rng::from_key(&[13]);
        for exponent in -4..=5 {
            let scale = 10f32.powi(exponent);
            let tri = [
                Vec3::new(0.1, 0.2, 0.3),
                Vec3::new(1.3, -0.4, 0.9),
                Vec3::new(-0.2, 1.1, -0.7),
            ]
            .map(|c| (c + Vec3::splat(3.0)) * scale);
            let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
            let bvh = CpuBvh::new(&[tri], CpuBvhOptions::default()).unwrap();
            let mut rays = RayBatch::default();
            for _ in 0..2000 {
                let b = sample_uniform_triangle(rng.uniform2());
                let p = tri[0] * b.x + tri[1] * b.y + tri[2] * b.z;
                // Origins in front of the triangle, from grazing to steep, near and far.
                let Vec2 { x: lift, y: reach } = rng.uniform2();
                let tangent = (tri[1] - tri[0]).normalize();
                let away = (tangent + n * (1e-4 + lift)).normalize();
                let origin = p + away * scale * (1e-3 + 10.0 * reach);
                let target = offset_ray_origin(p, barycentric_error(&tri, b), n, origin - p);
                let (direction, tmax) = segment_to(origin, target);
                rays.push(origin, direction, 0.0, tmax);
            }
            let mut occluded = Vec::new();
            bvh.occluded(&rays, &mut occluded);
            let blocked = occluded.iter().filter(|&&o| o).count();
            assert_eq!(blocked, 0, "scale {scale}");
        }
    }
}
