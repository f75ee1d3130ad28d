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
    let target = match light {
        // Any barycentrics are ≤ 1, so b = (1, 1, 1) bounds the sample point's error.
        Light::Area(area) => offset_ray_origin(
            target,
            barycentric_error(&area.corners, Vec3::ONE),
            area.normal,
            -illumination.direction,
        ),
        _ => target,
    };
    (target - origin, 1.0 - SHADOW_END_EPSILON)
}
