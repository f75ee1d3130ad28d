//! Path tracing vertices on plain Lambertian surfaces under area lights, [`LANES`] paths at
//! a time.
//!
//! The general vertex ([`crate::shade::shade`]) goes through the layered glTF BSDF one path
//! at a time: a long chain of dependent steps, most of them there for lobes a plain diffuse
//! surface does not have. Where every light of a scene is a constant, uncut area light and no
//! volume absorbs, a vertex on a material whose lobes are one plain Lambert lobe
//! ([`Lobes::lambert`](vcm_scene::bsdf::Lobes::lambert)) is shaded here instead, eight paths
//! per instruction: the surface point, the BSDF's sides and frame, the light sample and its
//! MIS weight (power heuristic, Veach 1997 eq. 9.13), the shadow ray, the cosine-weighted
//! continuation and the ray offsets.
//!
//! Each lane performs the operations the general vertex performs for such a surface, in the
//! same order, on the same random numbers, so a path's result is bit for bit the same
//! whichever way it is shaded (the tests render both ways and compare the films).

use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};

use glam::Vec3;
use vcm_scene::Scene;
use vcm_scene::bsdf::GRAZING_COS;
use vcm_scene::light::Light;
use vcm_scene::sampling::SobolSampler;

use crate::lanes::{F32s, LANES, Mask, Vec3s};
use crate::path_state::{PathState, SegmentOrigin, ShadowRay};
use crate::ray_offset::{barycentric_error, gamma, offset_ray_origins};
use crate::shade::vertex_sampler;
use crate::shadow::segment_to;
use crate::surface_hit::Hit;
use crate::wave::LaneShading;

/// A material whose lobes are one plain Lambert lobe.
#[derive(Clone, Copy, Debug)]
struct LambertMaterial {
    /// f = albedo/π.
    f: Vec3,
    /// Whether it scatters from the back side too.
    double_sided: bool,
}

/// An area light as light sampling reads it.
#[derive(Clone, Copy, Debug)]
struct LaneLight {
    corners: [Vec3; 3],
    /// Unit front-face normal.
    normal: Vec3,
    /// 1 / area.
    inv_area: f32,
    /// Emitted radiance.
    emission: Vec3,
    /// Error bound of any point computed on the triangle.
    error: Vec3,
}

/// What shading in lanes needs of a scene that allows it ([`LambertLanes::for_scene`]).
#[derive(Clone, Debug)]
pub(crate) struct LambertLanes {
    /// Per material, where it is plain Lambert.
    materials: Vec<Option<LambertMaterial>>,
    /// Per light (all of them area lights).
    lights: Vec<LaneLight>,
}

impl LambertLanes {
    /// The tables for `scene`, or why no vertex of it can be shaded in lanes.
    pub fn for_scene(scene: &Scene) -> Result<LambertLanes, &'static str> {
        if !scene.shading.lambert_lanes {
            return Err("pruning is off: every vertex goes through the general BSDF");
        }
        if scene.features.absorbing_volumes {
            return Err("a volume absorbs");
        }
        if scene.light_sampler.sample(0.5).is_none() {
            return Err("no light to sample");
        }
        let lights = scene
            .lights
            .iter()
            .map(|light| match light {
                Light::Area(area) if area.texture.is_none() && area.cut_out.is_none() => {
                    Some(LaneLight {
                        corners: area.corners,
                        normal: area.normal,
                        inv_area: 1.0 / area.area,
                        emission: area.emission,
                        error: barycentric_error(&area.corners, Vec3::ONE),
                    })
                }
                _ => None,
            })
            .collect::<Option<Vec<_>>>()
            .ok_or("a light is not a constant, uncut area light")?;
        let materials: Vec<_> = scene
            .materials
            .iter()
            .zip(&scene.material_lobes)
            .map(|(material, lobes)| {
                let f = lobes.as_ref()?.lambert()?;
                material
                    .normal_texture
                    .is_none()
                    .then_some(LambertMaterial {
                        f,
                        double_sided: material.double_sided,
                    })
            })
            .collect();
        if !materials.iter().any(Option::is_some) {
            return Err("no material is plain Lambert");
        }
        Ok(LambertLanes { materials, lights })
    }

    /// Whether `path`'s vertex at `hit` is shaded here: a plain Lambert surface that does
    /// not emit, with room left for another segment.
    #[inline]
    fn takes(&self, scene: &Scene, path: &PathState, hit: Hit, max_segments: u32) -> bool {
        let triangle = hit.triangle as usize;
        let material = scene.mesh.material_ids[triangle] as usize;
        path.segments < max_segments
            && self.materials[material].is_some()
            && scene
                .light_sampler
                .light_of_triangle(hit.triangle)
                .is_none()
    }

    /// Shades `paths[i]` at `hit` for each `(i, hit)` of `group` (at most [`LANES`], each
    /// taken by [`LambertLanes::takes`]), as [`crate::shade::shade`] would.
    fn shade(&self, scene: &Scene, paths: &mut [PathState], group: &[(usize, Hit)]) {
        debug_assert!(!group.is_empty() && group.len() <= LANES);
        let active = Mask::first(group.len());
        for &(i, _) in group {
            vertex_sampler(&mut paths[i]);
        }
        // Lanes past the group repeat its last path; their results are dropped.
        let at = |lane: usize| group[lane.min(group.len() - 1)];
        let samplers = std::array::from_fn(|lane| &paths[at(lane).0].rng);
        let numbers: [[[f32; LANES]; 2]; 5] = SobolSampler::peek_lanes(samplers);
        let mut inputs = Inputs {
            numbers: numbers.map(|pair| pair.map(F32s)),
            ..Inputs::default()
        };
        for lane in 0..LANES {
            let (i, hit) = at(lane);
            inputs.gather(self, scene, lane, &paths[i], hit);
        }
        let vertex = Vertex::new(&inputs, active);
        let shadow = vertex.light_sample(&inputs);
        let next = vertex.scatter(&inputs);
        for (lane, &(i, _)) in group.iter().enumerate() {
            next.write(&mut paths[i], lane, &shadow);
        }
    }
}

/// [`LambertLanes`] at work in one pass of the path tracer.
pub(crate) struct LambertShading<'a> {
    /// The tables, where the scene allows shading in lanes.
    pub tables: Option<&'a LambertLanes>,
    /// The scene being rendered.
    pub scene: &'a Scene,
    /// Longest path in segments (`u32::MAX`: unlimited).
    pub max_segments: u32,
}

impl LaneShading<PathState> for LambertShading<'_> {
    #[inline]
    fn takes(&self, path: &PathState, hit: Hit) -> bool {
        self.tables
            .is_some_and(|t| t.takes(self.scene, path, hit, self.max_segments))
    }

    fn shade(&self, paths: &mut [PathState], group: &[(usize, Hit)]) {
        if let Some(tables) = self.tables {
            tables.shade(self.scene, paths, group);
        }
    }
}

/// What the lanes read from their paths and the scene.
#[derive(Default)]
struct Inputs {
    corners: [Vec3s; 3],
    normals: [Vec3s; 3],
    /// Barycentrics of the hit's second and third corners.
    u: F32s,
    v: F32s,
    f: Vec3s,
    double_sided: [bool; LANES],
    direction: Vec3s,
    throughput: Vec3s,
    /// The vertex's numbers, a pair each: light pick (first number), point on the light,
    /// lobe (unused: there is one), direction, Russian roulette (first number).
    numbers: [[F32s; 2]; 5],
    /// The picked light's selection probability, and the light.
    pick_pmf: F32s,
    light_corners: [Vec3s; 3],
    light_normal: Vec3s,
    light_inv_area: F32s,
    light_emission: Vec3s,
    light_error: Vec3s,
}

impl Inputs {
    /// Reads lane `lane`'s inputs for `path` at `hit`, each once, after its numbers.
    #[inline(always)]
    fn gather(
        &mut self,
        tables: &LambertLanes,
        scene: &Scene,
        lane: usize,
        path: &PathState,
        hit: Hit,
    ) {
        let mesh = &scene.mesh;
        let triangle = hit.triangle as usize;
        for (c, &vertex) in mesh.triangles[triangle].iter().enumerate() {
            self.corners[c].set(lane, mesh.positions[vertex as usize]);
            self.normals[c].set(lane, mesh.normals[vertex as usize]);
        }
        (self.u.0[lane], self.v.0[lane]) = (hit.u, hit.v);
        let material = tables.materials[mesh.material_ids[triangle] as usize]
            .expect("a plain Lambert material");
        self.f.set(lane, material.f);
        self.double_sided[lane] = material.double_sided;
        self.direction.set(lane, path.direction);
        self.throughput.set(lane, path.throughput);
        let (light, pmf) = scene
            .light_sampler
            .sample(self.numbers[0][0].0[lane])
            .expect("the scene has a light to sample");
        let light = &tables.lights[light];
        self.pick_pmf.0[lane] = pmf;
        for (c, &corner) in light.corners.iter().enumerate() {
            self.light_corners[c].set(lane, corner);
        }
        self.light_normal.set(lane, light.normal);
        self.light_inv_area.0[lane] = light.inv_area;
        self.light_emission.set(lane, light.emission);
        self.light_error.set(lane, light.error);
    }
}

/// The shading frame of [`vcm_scene::frame::Frame::from_z`], in lanes.
struct Frame {
    x: Vec3s,
    y: Vec3s,
    z: Vec3s,
}

impl Frame {
    /// Duff et al. 2017's branchless basis around `n`, as `Frame::from_z` computes it.
    #[inline(always)]
    fn from_z(n: Vec3s) -> Frame {
        let one = F32s::splat(1.0);
        let sign = n.z.sign_of();
        let a = -one / (sign + n.z);
        let b = n.x * n.y * a;
        Frame {
            x: Vec3s {
                x: one + sign * n.x * n.x * a,
                y: sign * b,
                z: -sign * n.x,
            },
            y: Vec3s {
                x: b,
                y: sign + n.y * n.y * a,
                z: -n.y,
            },
            z: n,
        }
    }

    #[inline(always)]
    fn to_local(&self, v: Vec3s) -> Vec3s {
        Vec3s {
            x: v.dot(self.x),
            y: v.dot(self.y),
            z: v.dot(self.z),
        }
    }

    #[inline(always)]
    fn to_world(&self, l: Vec3s) -> Vec3s {
        self.x.scale(l.x) + self.y.scale(l.y) + self.z.scale(l.z)
    }
}

/// The vertex as the BSDF sees it from the path's side (`Bsdf::fix_outgoing`).
struct Vertex {
    position: Vec3s,
    /// Error bound of `position` (the same on every axis).
    error: Vec3s,
    n_g: Vec3s,
    frame: Frame,
    /// `wo · n_g`.
    cos_g_out: F32s,
    /// `wo` is behind n_g: the local frame is mirrored.
    back: Mask,
    /// Lanes where the BSDF scatters toward `wo`.
    alive: Mask,
}

/// A Lambert evaluation of a direction: `f·|cos|` and the pdf, in the lanes where it is
/// valid (`Bsdf::eval_from`).
struct Evaluation {
    f_cos: Vec3s,
    pdf: F32s,
    valid: Mask,
}

impl Vertex {
    /// `SurfaceHit::new`, `Bsdf::from_lobes` and `Bsdf::fix_outgoing` for the lanes.
    #[inline(always)]
    fn new(inputs: &Inputs, active: Mask) -> Vertex {
        let zero = F32s::splat(0.0);
        let grazing = F32s::splat(GRAZING_COS);
        let (u, v) = (inputs.u, inputs.v);
        let w = F32s::splat(1.0) - u - v;
        let [c0, c1, c2] = inputs.corners;
        let (b0, b1, b2) = (c0.scale(w), c1.scale(u), c2.scale(v));
        let position = b0 + b1 + b2;
        let bound = (b0.abs() + b1.abs() + b2.abs()).max_element() * F32s::splat(gamma(7));
        let n_g = (c1 - c0)
            .cross(c2 - c0)
            .normalize_or(Vec3s::splat(Vec3::ZERO));
        // Mesh::surface_point: the interpolated normal, turned to n_g's side.
        let [n0, n1, n2] = inputs.normals;
        let shading = (n0.scale(w) + n1.scale(u) + n2.scale(v)).normalize_or(n_g);
        let shading = shading.dot(n_g).lt(zero).select3(-shading, shading);
        // Bsdf::placed: an unusable shading normal gives way to n_g.
        let usable = shading.is_finite() & !shading.length_squared().lt(F32s::splat(0.25));
        let flipped = shading.dot(n_g).lt(zero).select3(-shading, shading);
        let n_s = usable.select3(flipped, n_g);
        let frame = Frame::from_z(n_s);
        // Bsdf::outgoing: the side of wo and wo in that side's frame.
        let wo = -inputs.direction;
        let cos_g_out = wo.dot(n_g);
        let back = cos_g_out.lt(zero);
        let seen = !cos_g_out.is_nan() & !cos_g_out.abs().le(grazing);
        let scatters = !back | Mask::from_bools(inputs.double_sided);
        let wo_z = mirror(back, frame.to_local(wo).z);
        Vertex {
            position,
            error: Vec3s {
                x: bound,
                y: bound,
                z: bound,
            },
            n_g,
            frame,
            cos_g_out,
            back,
            alive: active & seen & scatters & wo_z.ge(grazing),
        }
    }

    /// `FixedOutgoing::eval` of the Lambert lobe toward `wi` (world, unit), radiance mode.
    #[inline(always)]
    fn eval(&self, f: Vec3s, wi: Vec3s) -> Evaluation {
        let zero = F32s::splat(0.0);
        let grazing = F32s::splat(GRAZING_COS);
        let wi_z = mirror(self.back, self.frame.to_local(wi).z);
        let cos_g = wi.dot(self.n_g);
        let cos_g = self.back.select(-cos_g, cos_g);
        let same_side = !(cos_g.gt(zero) ^ wi_z.gt(zero));
        let consistent = cos_g.abs().ge(grazing) & wi_z.abs().ge(grazing) & same_side;
        let f_cos = f.scale(wi_z);
        let pdf = wi_z * F32s::splat(FRAC_1_PI);
        let finite = f_cos.is_finite() & pdf.is_finite() & pdf.gt(zero);
        Evaluation {
            f_cos,
            pdf,
            valid: consistent & wi_z.gt(zero) & finite,
        }
    }

    /// `next_event`: one light sample, its contribution and its shadow ray.
    #[inline(always)]
    fn light_sample(&self, inputs: &Inputs) -> LaneShadow {
        let zero = F32s::splat(0.0);
        // AreaLight::illuminate at a uniform point of the picked triangle.
        let [ux, uy] = inputs.numbers[1];
        let su = ux.sqrt();
        let one = F32s::splat(1.0);
        let b0 = one - su;
        let b1 = uy * su;
        let b2 = one - b0 - b1;
        let [l0, l1, l2] = inputs.light_corners;
        let point = l0.scale(b0) + l1.scale(b1) + l2.scale(b2);
        let to_light = point - self.position;
        let distance_sq = to_light.length_squared();
        let distance = distance_sq.sqrt();
        let direction = to_light.div(distance);
        let cos_at_light = inputs.light_normal.dot(-direction);
        let lit = cos_at_light.gt(zero) & distance.gt(zero);
        let direct_pdf_w = inputs.light_inv_area * distance_sq / cos_at_light;
        let eval = self.eval(inputs.f, direction);
        let light_pdf_w = direct_pdf_w * inputs.pick_pmf;
        let weight = power_heuristic(light_pdf_w, eval.pdf);
        let contribution = inputs
            .throughput
            .mul(inputs.light_emission)
            .mul(eval.f_cos)
            .scale(weight / light_pdf_w);
        // LightSample::shadow_ray: from the offset receiver to the offset light point.
        let origin = offset_ray_origins(self.position, self.error, self.n_g, direction);
        let target = self.position + direction.scale(distance);
        let target =
            offset_ray_origins(target, inputs.light_error, inputs.light_normal, -direction);
        LaneShadow {
            queued: self.alive & lit & eval.valid & eval.f_cos.is_nonzero(),
            origin,
            target,
            contribution,
        }
    }

    /// `scatter` up to Russian roulette: the cosine-weighted direction, its throughput
    /// factor and the next segment's origin.
    #[inline(always)]
    fn scatter(&self, inputs: &Inputs) -> Continuation {
        let zero = F32s::splat(0.0);
        let [ux, uy] = inputs.numbers[3];
        let (dx, dy) = concentric_disk(ux, uy);
        let dz = (F32s::splat(1.0) - (dx * dx + dy * dy)).max(zero).sqrt();
        let local = Vec3s {
            x: dx,
            y: dy,
            z: mirror(self.back, dz),
        };
        let wi = self.frame.to_world(local).normalize();
        let eval = self.eval(inputs.f, wi);
        let transmitted = (wi.dot(self.n_g) * self.cos_g_out).lt(zero);
        let alive = self.alive & dz.gt(zero) & eval.valid & !transmitted & wi.is_finite();
        Continuation {
            alive,
            throughput: inputs.throughput.mul(eval.f_cos.div(eval.pdf)),
            pdf: eval.pdf,
            direction: wi,
            origin: offset_ray_origins(self.position, self.error, self.n_g, wi),
            roulette_numbers: inputs.numbers[4][0],
        }
    }
}

/// `l` with its sign flipped in the `back` lanes (`Bsdf::to_local` / `to_world` mirroring
/// the frame for the back side).
#[inline(always)]
fn mirror(back: Mask, l: F32s) -> F32s {
    back.select(-l, l)
}

/// `power_heuristic(1, f_pdf, 1, g_pdf)` in each lane.
#[inline(always)]
fn power_heuristic(f_pdf: F32s, g_pdf: F32s) -> F32s {
    let zero = F32s::splat(0.0);
    let (f2, g2) = (f_pdf * f_pdf, g_pdf * g_pdf);
    let sum = f2 + g2;
    let weight = sum.gt(zero).select(f2 / sum, zero);
    let infinite = F32s::splat(f32::INFINITY);
    f_pdf.abs().eq(infinite).select(F32s::splat(1.0), weight)
}

/// `sample_concentric_disk` in each lane (the sine and cosine one lane at a time).
#[inline(always)]
fn concentric_disk(ux: F32s, uy: F32s) -> (F32s, F32s) {
    let (two, one, zero) = (F32s::splat(2.0), F32s::splat(1.0), F32s::splat(0.0));
    let (px, py) = (two * ux - one, two * uy - one);
    let x_major = px.abs().gt(py.abs());
    let (major, minor) = (x_major.select(px, py), x_major.select(py, px));
    let angle = F32s::splat(FRAC_PI_4) * (minor / major);
    let (mut sin, mut cos) = (zero, zero);
    for lane in 0..LANES {
        (sin.0[lane], cos.0[lane]) = angle.0[lane].sin_cos();
    }
    let (x, y) = (x_major.select(cos, sin), x_major.select(sin, cos));
    let center = px.eq(zero) & py.eq(zero);
    (
        center.select(zero, major * x),
        center.select(zero, major * y),
    )
}

/// The lanes' shadow rays.
struct LaneShadow {
    queued: Mask,
    origin: Vec3s,
    target: Vec3s,
    contribution: Vec3s,
}

/// The lanes' next segments, before Russian roulette.
struct Continuation {
    alive: Mask,
    throughput: Vec3s,
    /// Solid-angle pdf of the sampled direction.
    pdf: F32s,
    direction: Vec3s,
    origin: Vec3s,
    roulette_numbers: F32s,
}

impl Continuation {
    /// Writes lane `lane`'s results into its path: the shadow ray, Russian roulette (which
    /// draws a number only where it plays) and the next segment, and moves the path's
    /// numbers past those it drew.
    fn write(&self, path: &mut PathState, lane: usize, shadow: &LaneShadow) {
        path.shadow = shadow.queued.get(lane).then(|| {
            let origin = shadow.origin.lane(lane);
            let (direction, tmax) = segment_to(origin, shadow.target.lane(lane));
            ShadowRay {
                origin,
                direction,
                tmax,
                contribution: shadow.contribution.lane(lane),
            }
        });
        // Light pick, light point, lobe and direction.
        path.rng.skip(4);
        if !self.alive.get(lane) {
            path.alive = false;
            return;
        }
        let mut throughput = self.throughput.lane(lane);
        path.segment_origin = SegmentOrigin::Bsdf {
            pdf_w: self.pdf.0[lane],
        };
        let roulette_number = self.roulette_numbers.0[lane];
        let mut drawn = false;
        let survives = path.roulette.survives(path.segments, &mut throughput, || {
            drawn = true;
            roulette_number
        });
        path.rng.skip(u32::from(drawn));
        path.throughput = throughput;
        path.alive = survives;
        if survives {
            path.origin = self.origin.lane(lane);
            path.direction = self.direction.lane(lane);
            path.segments += 1;
        }
    }
}
