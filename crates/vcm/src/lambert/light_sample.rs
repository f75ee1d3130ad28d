//! Light samples from eight vertices at once: a light picked by power, a point on it, the
//! BSDF toward it, and the shadow ray that carries its MIS-weighted contribution
//! (`LightSample::shadow_ray`). Constant, uncut area lights, point, spot and directional
//! lights are sampled in the lanes (their `illuminate`, operation for operation; a group's
//! lanes that picked lights of different kinds take each kind's result); a lane that picked
//! any other light (the environment, a textured or cut-out emitter) takes that light's own
//! [`Light::illuminate`](vcm_scene::light::Light::illuminate), and the lanes go on from its
//! sample.

use std::f32::consts::FRAC_1_PI;

use glam::Vec2;
use vcm_scene::Scene;
use vcm_scene::bsdf::TransportMode;

use super::shadow_rays::ShadowLanes;
use super::surface::{Evaluation, Vertex};
use super::{LambertLanes, LaneLight};
use crate::lanes::{F32s, LANES, Mask, Vec3s};
use crate::ray_offset::offset_ray_origins;
use crate::shadow::shadow_target;

/// The lights eight vertices picked.
#[derive(Default)]
pub(crate) struct LightInputs {
    /// The picked light's selection probability.
    pub pick_pmf: F32s,
    /// Where the light is a constant, uncut area light: its triangle, normal, 1/area,
    /// emitted radiance (in `value`) and the error bound of points on it.
    corners: [Vec3s; 3],
    normal: Vec3s,
    inv_area: F32s,
    error: Vec3s,
    /// Lanes whose light is a point or spot light: its position, intensity (in `value`) and
    /// emission pdf; where `spot`, the spot's axis, cos(outer angle) and falloff slope.
    punctual: [bool; LANES],
    position: Vec3s,
    spot: [bool; LANES],
    axis: Vec3s,
    cos_outer: F32s,
    falloff_slope: F32s,
    /// Lanes whose light is directional: its illumination, the same at every receiver.
    directional: [bool; LANES],
    toward: Vec3s,
    /// Emitted radiance of area lights, intensity of point and spot lights, irradiance of
    /// directional ones.
    value: Vec3s,
    /// The emission pdf of point, spot and directional lights.
    emission_pdf_w: F32s,
    /// The picked light's index in the lanes that sample it one lane at a time (the lanes do
    /// not sample it: [`LaneLight::of`](super::LaneLight::of)).
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
        match &tables.lights[index] {
            None => self.general[lane] = Some(index as u32),
            Some(LaneLight::Area(light)) => {
                for (c, &corner) in light.corners.iter().enumerate() {
                    self.corners[c].set(lane, corner);
                }
                self.normal.set(lane, light.normal);
                self.inv_area.0[lane] = light.inv_area;
                self.value.set(lane, light.emission);
                self.error.set(lane, light.error);
            }
            Some(LaneLight::Punctual(light)) => {
                self.punctual[lane] = true;
                self.position.set(lane, light.position);
                self.value.set(lane, light.intensity);
                self.emission_pdf_w.0[lane] = light.emission_pdf_w;
                if let Some((axis, cos_outer, slope)) = light.spot {
                    self.spot[lane] = true;
                    self.axis.set(lane, axis);
                    self.cos_outer.0[lane] = cos_outer;
                    self.falloff_slope.0[lane] = slope;
                }
            }
            Some(LaneLight::Directional(illumination)) => {
                self.directional[lane] = true;
                self.toward.set(lane, illumination.direction);
                self.value.set(lane, illumination.value);
                self.emission_pdf_w.0[lane] = illumination.emission_pdf_w;
            }
        }
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

impl Illumination {
    /// `yes` in the `mask` lanes, `no` in the others.
    #[inline(always)]
    fn select(mask: Mask, yes: Illumination, no: Illumination) -> Illumination {
        let pick = |yes: Mask, no: Mask| (mask & yes) | (!mask & no);
        Illumination {
            direction: mask.select3(yes.direction, no.direction),
            cos_at_light: mask.select(yes.cos_at_light, no.cos_at_light),
            direct_pdf_w: mask.select(yes.direct_pdf_w, no.direct_pdf_w),
            lit: pick(yes.lit, no.lit),
            emission_pdf_w: mask.select(yes.emission_pdf_w, no.emission_pdf_w),
            value: mask.select3(yes.value, no.value),
            delta: pick(yes.delta, no.delta),
            distant: pick(yes.distant, no.distant),
            target: mask.select3(yes.target, no.target),
        }
    }
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
        value: light.value,
        delta: Mask::none(),
        distant: Mask::none(),
        target: offset_ray_origins(target, light.error, light.normal, -direction),
    }
}

/// Each lane's point or spot light seen from `vertex` (`PointLight::illuminate`,
/// `SpotLight::illuminate`): the "pdf" is the squared distance, so that value / pdf = I / d².
#[inline(always)]
fn illuminate_punctual(light: &LightInputs, vertex: &Vertex) -> Illumination {
    let (zero, one) = (F32s::splat(0.0), F32s::splat(1.0));
    let to_light = light.position - vertex.position;
    let distance_sq = to_light.length_squared();
    let distance = distance_sq.sqrt();
    let direction = to_light.div(distance);
    // SpotLight::falloff: t = clamp((cos θ − cos θ_outer) · slope, 0, 1), falloff t².
    let t = (light.axis.dot(-direction) - light.cos_outer) * light.falloff_slope;
    let t = t.lt(zero).select(zero, t);
    let t = t.gt(one).select(one, t);
    let spot = Mask::from_bools(light.spot);
    let attenuation = spot.select(t * t, one);
    Illumination {
        direction,
        cos_at_light: one,
        direct_pdf_w: distance_sq,
        lit: distance.gt(zero) & distance.is_finite() & attenuation.gt(zero),
        emission_pdf_w: light.emission_pdf_w,
        // I · 1 is I, bit for bit, for point lights.
        value: light.value.scale(attenuation),
        delta: !Mask::none(),
        distant: Mask::none(),
        target: vertex.position + direction.scale(distance),
    }
}

/// Each lane's directional light (`DirectionalLight::illuminate`): an unbounded shadow ray
/// toward it.
#[inline(always)]
fn illuminate_directional(light: &LightInputs) -> Illumination {
    let one = F32s::splat(1.0);
    Illumination {
        direction: light.toward,
        cos_at_light: one,
        direct_pdf_w: one,
        lit: !Mask::none(),
        emission_pdf_w: light.emission_pdf_w,
        value: light.value,
        delta: !Mask::none(),
        distant: !Mask::none(),
        target: light.toward,
    }
}

/// A point on each lane's light with the numbers (`ux`, `uy`), seen from `vertex`: in the
/// lanes for the lights they sample, by the light's own sampling for the others.
#[inline(always)]
fn illuminate(
    scene: &Scene,
    light: &LightInputs,
    vertex: &Vertex,
    (ux, uy): (F32s, F32s),
) -> Illumination {
    let any = |lanes: &[bool; LANES]| lanes.contains(&true);
    // The area lights' operations run where some lane picked an area light, or where lanes
    // picked none of the kinds sampled here (their results are overwritten below).
    let mut illumination = if light.punctual == [true; LANES] {
        illuminate_punctual(light, vertex)
    } else {
        let area = illuminate_area(light, vertex, (ux, uy));
        match any(&light.punctual) {
            true => {
                let punctual = illuminate_punctual(light, vertex);
                Illumination::select(Mask::from_bools(light.punctual), punctual, area)
            }
            false => area,
        }
    };
    if any(&light.directional) {
        let directional = illuminate_directional(light);
        let lanes = Mask::from_bools(light.directional);
        illumination = Illumination::select(lanes, directional, illumination);
    }
    if light.general.iter().all(Option::is_none) {
        return illumination;
    }
    let mut lit = illumination.lit.bools();
    let mut delta = illumination.delta.bools();
    let mut distant = illumination.distant.bools();
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
