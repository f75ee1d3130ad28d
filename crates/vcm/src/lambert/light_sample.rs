//! Light samples from eight vertices at once: a light picked by power, a point on it, the
//! BSDF toward it, and the shadow ray that carries its MIS-weighted contribution
//! (`LightSample::shadow_ray`). Points on constant, uncut area lights are sampled in the
//! lanes (`AreaLight::illuminate`, operation for operation); a lane that picked any other
//! light (point, spot, directional, environment, a textured or cut-out emitter) takes that
//! light's own [`Light::illuminate`](vcm_scene::light::Light::illuminate), and the lanes go on
//! from its sample.

use std::f32::consts::FRAC_1_PI;

use glam::Vec2;
use vcm_scene::Scene;
use vcm_scene::bsdf::TransportMode;

use super::LambertLanes;
use super::shadow_rays::ShadowLanes;
use super::surface::{Evaluation, Vertex};
use crate::lanes::{F32s, LANES, Mask, Vec3s};
use crate::ray_offset::offset_ray_origins;
use crate::shadow::shadow_target;

/// The lights eight vertices picked.
#[derive(Default)]
pub(crate) struct LightInputs {
    /// The picked light's selection probability.
    pub pick_pmf: F32s,
    corners: [Vec3s; 3],
    normal: Vec3s,
    inv_area: F32s,
    emission: Vec3s,
    error: Vec3s,
    /// The picked light's index in the lanes that sample it one lane at a time (it is not a
    /// constant, uncut area light).
    general: [Option<u32>; LANES],
}

impl LightInputs {
    /// Picks lane `lane`'s light by power with `u_pick`.
    #[inline(always)]
    pub fn gather(&mut self, tables: &LambertLanes, scene: &Scene, lane: usize, u_pick: f32) {
        let (index, pmf) = scene
            .light_sampler
            .sample(u_pick)
            .expect("the scene has a light to sample");
        self.pick_pmf.0[lane] = pmf;
        let Some(light) = &tables.lights[index] else {
            self.general[lane] = Some(index as u32);
            return;
        };
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
    /// Cosine at the light (1 for point-like lights).
    pub cos_at_light: F32s,
    /// Solid-angle pdf at the receiver, for area lights p_w = p_a · d² / cos θ_light (no
    /// pick).
    pub direct_pdf_w: F32s,
    /// Lanes where the point faces the receiver.
    pub lit: Mask,
    /// The light's pdf of emitting the segment (no pick).
    pub emission_pdf_w: F32s,
    /// Emitted radiance toward the receiver (intensity of point-like lights, irradiance of
    /// directional ones).
    pub value: Vec3s,
    /// Lanes whose light has a delta position or direction: no BSDF sample reaches it.
    pub delta: Mask,
    /// Lanes whose light is distant: `target` holds the unit direction of an unbounded
    /// shadow ray.
    pub distant: Mask,
    /// The shadow ray's end: the point, offset off an area light's triangle toward the
    /// receiver.
    pub target: Vec3s,
}

/// A uniform point of each lane's light triangle with the numbers (`ux`, `uy`), seen from
/// `vertex` (`AreaLight::illuminate`).
#[inline(always)]
fn illuminate_area(light: &LightInputs, vertex: &Vertex, (ux, uy): (F32s, F32s)) -> Illumination {
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
        value: light.emission,
        delta: Mask::none(),
        distant: Mask::none(),
        target: offset_ray_origins(target, light.error, light.normal, -direction),
    }
}

/// A point on each lane's light with the numbers (`ux`, `uy`), seen from `vertex`: in the
/// lanes for constant area lights, by the light's own sampling for the others.
#[inline(always)]
fn illuminate(
    scene: &Scene,
    light: &LightInputs,
    vertex: &Vertex,
    (ux, uy): (F32s, F32s),
) -> Illumination {
    let mut illumination = illuminate_area(light, vertex, (ux, uy));
    if light.general.iter().all(Option::is_none) {
        return illumination;
    }
    let mut lit = illumination.lit.bools();
    let (mut delta, mut distant) = ([false; LANES], [false; LANES]);
    for (lane, index) in light.general.iter().enumerate() {
        let Some(index) = *index else {
            continue;
        };
        let light = &scene.lights[index as usize];
        let receiver = vertex.position.lane(lane);
        let u = Vec2::new(ux.0[lane], uy.0[lane]);
        let Some(sample) = light.illuminate(&scene.textures, receiver, u) else {
            lit[lane] = false;
            continue;
        };
        lit[lane] = true;
        delta[lane] = light.is_delta();
        illumination.direction.set(lane, sample.direction);
        illumination.cos_at_light.0[lane] = sample.cos_at_light;
        illumination.direct_pdf_w.0[lane] = sample.direct_pdf_w;
        illumination.emission_pdf_w.0[lane] = sample.emission_pdf_w;
        illumination.value.set(lane, sample.value);
        let target = shadow_target(light, &sample, receiver);
        distant[lane] = target.is_none();
        illumination
            .target
            .set(lane, target.unwrap_or(sample.direction));
    }
    illumination.lit = Mask::from_bools(lit);
    illumination.delta = Mask::from_bools(delta);
    illumination.distant = Mask::from_bools(distant);
    illumination
}

/// One light sample per lane, with the numbers `numbers`, from `vertex`, for paths with
/// throughput `throughput` (the path tracer's `next_event`, the camera pass's
/// `light_sample`): the BSDF toward the point in radiance transport (`reverse`: with the
/// reverse pdf), weighted by `weight` of the point, the BSDF's values and p_light = pick pmf
/// · the point's solid-angle pdf. The shadow ray carries β · L_e · f·|cos| · w / p_light.
#[inline(always)]
pub(crate) fn light_samples(
    (scene, vertex, light): (&Scene, &Vertex, &LightInputs),
    throughput: Vec3s,
    (numbers, reverse): ((F32s, F32s), bool),
    weight: impl FnOnce(&Illumination, &Evaluation, F32s) -> F32s,
) -> ShadowLanes {
    let illumination = illuminate(scene, light, vertex, numbers);
    let direction = illumination.direction;
    let eval = vertex.eval(direction, TransportMode::Radiance, reverse);
    let light_pdf_w = illumination.direct_pdf_w * light.pick_pmf;
    let weight = weight(&illumination, &eval, light_pdf_w);
    ShadowLanes {
        queued: vertex.alive & illumination.lit & eval.valid & eval.f_cos.is_nonzero(),
        origin: vertex.spawn(direction),
        target: illumination.target,
        distant: illumination.distant,
        contribution: throughput
            .mul(illumination.value)
            .mul(eval.f_cos)
            .scale(weight / light_pdf_w),
    }
}
