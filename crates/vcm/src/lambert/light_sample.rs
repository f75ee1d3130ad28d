//! Light samples from eight vertices at once: a light picked by power, a uniform point on
//! its triangle (`AreaLight::illuminate`), the BSDF toward it, and the shadow ray that
//! carries its MIS-weighted contribution (`LightSample::shadow_ray`).

use std::f32::consts::FRAC_1_PI;

use vcm_scene::Scene;
use vcm_scene::bsdf::TransportMode;

use super::LambertLanes;
use super::shadow_rays::ShadowLanes;
use super::surface::{Evaluation, Vertex};
use crate::lanes::{F32s, Mask, Vec3s};
use crate::ray_offset::offset_ray_origins;

/// The lights eight vertices picked.
#[derive(Default)]
pub(crate) struct LightInputs {
    /// The picked light's selection probability.
    pub pick_pmf: F32s,
    corners: [Vec3s; 3],
    normal: Vec3s,
    inv_area: F32s,
    /// Emitted radiance.
    pub emission: Vec3s,
    error: Vec3s,
}

impl LightInputs {
    /// Picks lane `lane`'s light by power with `u_pick`.
    #[inline(always)]
    pub fn gather(&mut self, tables: &LambertLanes, scene: &Scene, lane: usize, u_pick: f32) {
        let (light, pmf) = scene
            .light_sampler
            .sample(u_pick)
            .expect("the scene has a light to sample");
        let light = &tables.lights[light];
        self.pick_pmf.0[lane] = pmf;
        for (c, &corner) in light.corners.iter().enumerate() {
            self.corners[c].set(lane, corner);
        }
        self.normal.set(lane, light.normal);
        self.inv_area.0[lane] = light.inv_area;
        self.emission.set(lane, light.emission);
        self.error.set(lane, light.error);
    }
}

/// Points on the picked lights as the vertices see them (`Illumination`).
pub(crate) struct Illumination {
    /// Unit direction toward the point.
    pub direction: Vec3s,
    /// Cosine at the light.
    pub cos_at_light: F32s,
    /// Area to solid angle at the receiver: p_w = p_a · d² / cos θ_light (no pick).
    pub direct_pdf_w: F32s,
    /// Lanes where the point faces the receiver.
    pub lit: Mask,
    /// The light's area pdf of emitting the segment (no pick).
    pub emission_pdf_w: F32s,
    /// The shadow ray's end: the point offset off its triangle toward the receiver.
    pub target: Vec3s,
}

/// A uniform point of each lane's light triangle with the numbers (`ux`, `uy`), seen from
/// `vertex` (`AreaLight::illuminate`).
#[inline(always)]
pub(crate) fn illuminate(
    light: &LightInputs,
    vertex: &Vertex,
    (ux, uy): (F32s, F32s),
) -> Illumination {
    let (zero, one) = (F32s::splat(0.0), F32s::splat(1.0));
    let su = ux.sqrt();
    let b0 = one - su;
    let b1 = uy * su;
    let b2 = one - b0 - b1;
    let [l0, l1, l2] = light.corners;
    let point = l0.scale(b0) + l1.scale(b1) + l2.scale(b2);
    let to_light = point - vertex.position;
    let distance_sq = to_light.length_squared();
    let distance = distance_sq.sqrt();
    let direction = to_light.div(distance);
    let cos_at_light = light.normal.dot(-direction);
    // LightSample::shadow_ray's end point.
    let target = vertex.position + direction.scale(distance);
    Illumination {
        direction,
        cos_at_light,
        direct_pdf_w: light.inv_area * distance_sq / cos_at_light,
        lit: cos_at_light.gt(zero) & distance.gt(zero),
        emission_pdf_w: light.inv_area * (cos_at_light.max(zero) * F32s::splat(FRAC_1_PI)),
        target: offset_ray_origins(target, light.error, light.normal, -direction),
    }
}

/// One light sample per lane, with the numbers `numbers`, from `vertex`, for paths with
/// throughput `throughput` (the path tracer's `next_event`, the camera pass's
/// `light_sample`): the BSDF toward the point in radiance transport (`reverse`: with the
/// reverse pdf), weighted by `weight` of the point, the BSDF's values and p_light = pick pmf
/// · the point's solid-angle pdf. The shadow ray carries β · L_e · f·|cos| · w / p_light.
#[inline(always)]
pub(crate) fn light_samples(
    (vertex, light): (&Vertex, &LightInputs),
    throughput: Vec3s,
    (numbers, reverse): ((F32s, F32s), bool),
    weight: impl FnOnce(&Illumination, &Evaluation, F32s) -> F32s,
) -> ShadowLanes {
    let illumination = illuminate(light, vertex, numbers);
    let direction = illumination.direction;
    let eval = vertex.eval(direction, TransportMode::Radiance, reverse);
    let light_pdf_w = illumination.direct_pdf_w * light.pick_pmf;
    let weight = weight(&illumination, &eval, light_pdf_w);
    ShadowLanes {
        queued: vertex.alive & illumination.lit & eval.valid & eval.f_cos.is_nonzero(),
        origin: vertex.spawn(direction),
        target: illumination.target,
        contribution: throughput
            .mul(light.emission)
            .mul(eval.f_cos)
            .scale(weight / light_pdf_w),
    }
}
