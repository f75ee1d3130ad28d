//! Shadow rays for next event estimation: from an offset receiver to a light sample.

use glam::Vec3;
use vcm_scene::light::{Illumination, Light};

use crate::ray_offset::{barycentric_error, offset_ray_origin};

/// Fraction of a finite shadow ray left out at the light's end, so that the light's own
/// surface (or a point light's position) never counts as a blocker. Relative to the ray
/// length, hence scale independent.
const SHADOW_END_EPSILON: f32 = 1e-4;

/// Direction and `tmax` of a shadow ray from `origin` (already offset off the
/// receiving surface) toward the light sample `illumination` of `light`, seen from the
/// un-offset receiving point `receiver`.
///
/// Finite lights: the direction reaches the light sample at t = 1 and the ray stops at
/// t = 1 − [`SHADOW_END_EPSILON`]; an area light's sample point is first offset off the
/// emitting triangle toward the receiver by its own error bound. Distant lights: a unit
/// direction and an unbounded ray.
pub(crate) fn shadow_segment(
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
/// off their surfaces): the direction reaches `target` at t = 1 and the ray stops at
/// t = 1 − [`SHADOW_END_EPSILON`].
pub(crate) fn segment_to(origin: Vec3, target: Vec3) -> (Vec3, f32) {
    (target - origin, 1.0 - SHADOW_END_EPSILON)
}
