//! Vertices on plain Lambertian surfaces, [`LANES`](crate::lanes::LANES) paths at a time.
//!
//! The general vertex goes through the layered glTF BSDF one path at a time: a long chain of
//! dependent steps, most of them there for lobes a plain diffuse surface does not have. Where
//! no volume absorbs, vertices on materials whose lobes are one plain Lambert lobe
//! ([`Lobes::lambert`](vcm_scene::bsdf::Lobes::lambert)) are shaded in SIMD lanes instead,
//! eight paths per instruction: the surface point, the BSDF's sides, frame, values and pdfs
//! ([`surface`]), the light sample ([`light_sample`]: constant area lights, point, spot and
//! directional lights in the lanes, every other light by its own `Light::illuminate`), the
//! cosine-weighted continuation and the ray offsets. The integrators build their vertices
//! from these parts ([`path_tracing`] here, the camera and light passes of the VCM family in
//! [`crate::bidir`]).
//!
//! Each lane performs the operations the general vertex performs for such a surface, in the
//! same order, on the same random numbers, so a path's result is bit for bit the same
//! whichever way it is shaded (the tests render both ways and compare the films).

pub(crate) mod continuation;
pub(crate) mod light_sample;
pub(crate) mod path_tracing;
pub(crate) mod shadow_rays;
pub(crate) mod surface;

use glam::{Vec2, Vec3};
use vcm_scene::Scene;
use vcm_scene::light::{Illumination, Light};
use vcm_scene::sampling::SobolSampler;

use crate::lanes::{F32s, LANES, Mask, Vec3s};
use crate::ray_offset::barycentric_error;
use crate::surface_hit::Hit;
use crate::vertex_numbers::{Draw, LaneDraws};
#[cfg(doc)]
use crate::walk::Walk;
use crate::walk::Walker;
use surface::{SurfaceInputs, Vertex};
#[cfg(doc)]
use vcm_scene::light::SpotLight;

/// A material whose lobes are one plain Lambert lobe.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LambertMaterial {
    /// f = albedo/π.
    pub f: Vec3,
    /// Whether it scatters from the back side too.
    pub double_sided: bool,
}

/// A constant, uncut area light as light sampling in lanes reads it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LaneAreaLight {
    pub corners: [Vec3; 3],
    /// Unit front-face normal.
    pub normal: Vec3,
    /// 1 / area.
    pub inv_area: f32,
    /// Emitted radiance.
    pub emission: Vec3,
    /// Error bound of any point computed on the triangle.
    pub error: Vec3,
}

/// A point or spot light as light sampling in lanes reads it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LanePunctualLight {
    pub position: Vec3,
    /// Radiant intensity (on the axis, for a spot).
    pub intensity: Vec3,
    /// The pdf of emitting any one direction (uniform over the sphere or the spot's cone).
    pub emission_pdf_w: f32,
    /// A spot's falloff ([`SpotLight::falloff`]): its axis, cos(outer angle) and
    /// [`SpotLight::falloff_slope`]. None for a point light.
    pub spot: Option<(Vec3, f32, f32)>,
}

/// A light that light sampling in lanes samples itself.
#[derive(Clone, Copy, Debug)]
pub(crate) enum LaneLight {
    Area(LaneAreaLight),
    Punctual(LanePunctualLight),
    /// A directional light, by its illumination (the same at every receiver).
    Directional(Illumination),
}

impl LaneLight {
    /// `light` as the lanes sample it, if they do: a constant, uncut area light, a point or
    /// spot light or a directional light.
    fn of(light: &Light) -> Option<LaneLight> {
        Some(match light {
            Light::Area(area) if area.texture.is_none() && area.cut_out.is_none() => {
                LaneLight::Area(LaneAreaLight {
                    corners: area.corners,
                    normal: area.normal,
                    inv_area: 1.0 / area.area,
                    emission: area.emission,
                    error: barycentric_error(&area.corners, Vec3::ONE),
                })
            }
            Light::Point(point) => LaneLight::Punctual(LanePunctualLight {
                position: point.position,
                intensity: point.intensity,
                emission_pdf_w: point.emission_pdf_w(),
                spot: None,
            }),
            Light::Spot(spot) => LaneLight::Punctual(LanePunctualLight {
                position: spot.position,
                intensity: spot.intensity,
                emission_pdf_w: spot.emission_pdf_w(),
                spot: Some((spot.direction, spot.cos_outer, spot.falloff_slope())),
            }),
            Light::Directional(_) => {
                LaneLight::Directional(light.illuminate(&[], Vec3::ZERO, Vec2::ZERO)?)
            }
            _ => return None,
        })
    }
}

/// What shading in lanes needs of a scene that allows it ([`LambertLanes::for_scene`]).
#[derive(Clone, Debug)]
pub(crate) struct LambertLanes {
    /// Per material, where it is plain Lambert.
    pub materials: Vec<Option<LambertMaterial>>,
    /// Per light, where the lanes sample it ([`LaneLight::of`]; other lights sample their
    /// own, one lane at a time).
    pub lights: Vec<Option<LaneLight>>,
    /// Per triangle, whether vertices on it are shaded in lanes: a plain Lambert surface
    /// that does not emit. One load per vertex where the two tests behind it take three,
    /// two of them dependent (the triangle's material, then that material's entry).
    lane_surfaces: Vec<bool>,
}

impl LambertLanes {
    /// The tables for `scene`, or why no vertex of it is shaded in lanes: the integrator's
    /// settings leave them out (`wanted` false), or the scene allows none.
    pub fn for_scene(scene: &Scene, wanted: bool) -> Result<LambertLanes, &'static str> {
        if !wanted {
            return Err("off in the integrator's settings: every vertex takes the general BSDF");
        }
        if scene.features.absorbing_volumes {
            return Err("a volume absorbs");
        }
        if scene.light_sampler.sample(0.5).is_none() {
            return Err("no light to sample");
        }
        let lights = scene.lights.iter().map(LaneLight::of).collect();
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
        let lane_surfaces = (0..scene.mesh.triangle_count() as u32)
            .map(|triangle| {
                materials[scene.mesh.material_ids[triangle as usize] as usize].is_some()
                    && scene.light_sampler.light_of_triangle(triangle).is_none()
            })
            .collect();
        Ok(LambertLanes {
            materials,
            lights,
            lane_surfaces,
        })
    }

    /// The plain Lambert material of `triangle`, if it has one.
    #[inline]
    pub fn material_of(&self, scene: &Scene, triangle: u32) -> Option<LambertMaterial> {
        self.materials[scene.mesh.material_ids[triangle as usize] as usize]
    }

    /// Whether a vertex at `hit` can be shaded in lanes: a plain Lambert surface that does
    /// not emit.
    #[inline]
    pub fn takes_surface(&self, hit: Hit) -> bool {
        self.lane_surfaces[hit.triangle as usize]
    }
}

/// The path and hit of lane `lane` of `group` (pairs of a path's index and its hit, at most
/// [`LANES`]). Lanes past the group repeat its last path; their results are dropped.
#[inline(always)]
pub(crate) fn lane_of(group: &[(usize, Hit)], lane: usize) -> (usize, Hit) {
    group[lane.min(group.len() - 1)]
}

/// The numbers a lane group's vertices draw, read ahead ([`start_vertices`]).
pub(crate) struct VertexNumbers<const N: usize> {
    /// What the vertices read of their layout.
    pub lane_draws: &'static LaneDraws<N>,
    /// Each of `lane_draws.draws`'s pair in every lane.
    pairs: [[[f32; LANES]; 2]; N],
}

impl<const N: usize> VertexNumbers<N> {
    /// The pair of `draw` in every lane (one the vertices read).
    #[inline(always)]
    pub fn pair(&self, draw: Draw) -> (F32s, F32s) {
        let k = self.lane_draws.draws.iter().position(|&d| d == draw);
        let [first, second] = self.pairs[k.expect("a decision the vertices read")];
        (F32s(first), F32s(second))
    }

    /// The first number of `draw`'s pair in every lane.
    #[inline(always)]
    pub fn first(&self, draw: Draw) -> F32s {
        self.pair(draw).0
    }
}

/// Starts the vertices `group` reached, which read `lane_draws` of their layout: moves each
/// path's numbers to its vertex ([`Walk::start_vertex`]) and reads those pairs of every
/// lane's numbers ahead, all lanes at once.
#[inline(always)]
pub(crate) fn start_vertices<P: Walker, const N: usize>(
    (paths, group): (&mut [P], &[(usize, Hit)]),
    lane_draws: &'static LaneDraws<N>,
) -> VertexNumbers<N> {
    debug_assert!(!group.is_empty() && group.len() <= LANES);
    for &(i, _) in group {
        paths[i].walk_mut().start_vertex(lane_draws.pairs);
    }
    let samplers = std::array::from_fn(|lane| &paths[lane_of(group, lane).0].walk().rng);
    VertexNumbers {
        lane_draws,
        pairs: SobolSampler::peek_lanes(samplers, lane_draws.indices),
    }
}

/// Eight walks arriving at plain Lambert surfaces, as the lanes read them.
pub(crate) struct Arrivals {
    /// The vertices they reached, seen from where they came (in the lanes of the group).
    pub vertex: Vertex,
    /// The walks' throughputs.
    pub throughput: Vec3s,
}

impl Arrivals {
    /// Reads the walk of each lane's path in `group` and the point it reached, and lets
    /// `extra` read what else an integrator's vertex needs of the lane's path; then makes
    /// the vertices (`Vertex::new`).
    #[inline(always)]
    pub fn gather<P: Walker>(
        (tables, scene): (&LambertLanes, &Scene),
        (paths, group): (&[P], &[(usize, Hit)]),
        mut extra: impl FnMut(usize, Hit, &P),
    ) -> Arrivals {
        let mut surface = SurfaceInputs::default();
        let (mut direction, mut throughput) = (Vec3s::default(), Vec3s::default());
        for lane in 0..LANES {
            let (i, hit) = lane_of(group, lane);
            let (path, point) = (&paths[i], (hit.triangle, hit.u, hit.v));
            surface.gather(tables, scene, lane, point);
            direction.set(lane, path.walk().direction);
            throughput.set(lane, path.walk().throughput);
            extra(lane, hit, path);
        }
        Arrivals {
            vertex: Vertex::new(&surface, -direction, Mask::first(group.len())),
            throughput,
        }
    }
}

/// Why the lanes run, for an integrator's decisions.
pub(crate) const LANES_RUN: &str = "some material is plain Lambert and no volume absorbs";

/// The name of the lanes in an integrator's decisions.
pub(crate) const LANES_PART: &str = "plain Lambert vertices in SIMD lanes";
