//! Multiple importance sampling weights of VCM, computed recursively along each subpath.
//!
//! Georgiev et al. 2012 ("Light Transport Simulation with Vertex Connection and Merging") and
//! the tech report "Implementing Vertex Connection and Merging" (Georgiev 2012; equation
//! numbers below refer to it) show that the balance-heuristic weight of every technique can be
//! computed from three running quantities per subpath vertex, d_VCM, d_VC and d_VM, updated
//! once per segment. The weight of a technique is 1 / (w_light + 1 + w_camera), where each
//! side's partial sum w comes from its subpath's quantities and the pdfs at the joining vertex.
//!
//! Conventions:
//! * pdfs in solid angle are per steradian; area pdfs convert with |cos θ| / d² using the
//!   **geometric** normal at the receiving vertex, the same everywhere, so that all techniques
//!   see the same density for the same path.
//! * A light tracing splat ("connect a light vertex to the camera") is one technique used by
//!   every one of the frame's N_p light paths, merging counts as N_p paths times the disk area
//!   π r² (η = π r² N_p, eq. 20), and every vertex connection counts once.
//! * Russian roulette is left out of the weights: every technique computes the same quantities
//!   for the same path, so the weights still sum to one and the estimate stays unbiased.
//! * Specular (delta) vertices cannot be connected or merged: d_VCM becomes 0 there and d_VC,
//!   d_VM are carried on, scaled by the delta's pdf ratio (eqs. 53–55) — never zeroed.
//! * Emission found by the camera path (the unidirectional technique) is weighted in BPM
//!   too, not only on purely specular paths as in the tech report's BPM: merging alone
//!   samples a path whose last scattering is glossy only through a light vertex falling into
//!   the lobe, an unbiased estimate whose mass sits in samples a render never draws (a glossy
//!   mirror lit by a furnace came out 25% dark after 100 frames). In d_VC and in the light
//!   subpath's starting d_VM the emission hit is kept while connections are dropped
//!   ([`MisFactors::hit`], [`MisFactors::connections`]).
//! * Where connections run (VCM), merging is no technique at a vertex next to a light: light
//!   samples and emission hits find that light, and merging its direct light only added a
//!   density estimate's noise (on a point light's highlights on the glossy WaterBottle merges
//!   took 7–22% of the weight, each from one light vertex in the disk or none). A light
//!   path's first vertex is not merged and its terms leave the weights
//!   ([`MisFactors::beside_light`]); a camera path keeps d_VC as it is without its latest
//!   vertex's merge for the emission its next segment finds ([`CameraMis`]). In BPM merging
//!   is the only way such a vertex meets a point light and stays.

use vcm_scene::bsdf::{BsdfSample, LobeKind};

use crate::lanes::{F32s, Real};
use crate::surface_hit::SurfaceHit;

/// Per-frame constants of the weights: which technique families exist and how many samples
/// each takes (`T`: one frame's, or [`F32s`] of the frames of a lane group's paths).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MisFactors<T = f32> {
    /// η_VCM = π r² N_p when merging is used, else 0: the weight of a merge relative to a
    /// connection or an emission hit.
    pub merge: T,
    /// 1 / η_VCM when connections are used (and merging too), else 0: the weight of a
    /// connection relative to a merge.
    pub connect: T,
    /// 1 / η_VCM when merging is used, else 0: the weight of an emission hit relative to a
    /// merge (it starts a light subpath's d_VM).
    pub hit: T,
    /// 1 when connections (light samples, connections to light vertices, light tracing
    /// splats) are used, else 0: whether d_VCM, which stands for them, enters d_VC and the
    /// weight of an emission hit.
    pub connections: T,
    /// N_p, the number of light paths per frame (the sample count of light tracing splats).
    pub light_paths: T,
    /// 1 where merging is a technique at the vertex these factors are for, else 0: the
    /// merge's own term of d_VM.
    pub merges: T,
}

impl<T: Real> MisFactors<T> {
    /// The factors at a vertex next to a light (a light path's first hit; a camera vertex
    /// that takes a light sample, or whose next segment finds emission): without the merge
    /// there where connections run (the module's notes).
    #[inline(always)]
    pub fn beside_light(&self) -> MisFactors<T> {
        let kept = T::splat(1.0) - self.connections;
        MisFactors {
            merge: self.merge * kept,
            merges: self.merges * kept,
            ..*self
        }
    }
}

impl MisFactors<F32s> {
    /// The factors of lane `lane`'s frame, `of(lane)`, in each lane.
    #[inline(always)]
    pub fn lanes<'a>(of: impl Fn(usize) -> &'a MisFactors) -> MisFactors<F32s> {
        let lanes = |field: fn(&MisFactors) -> f32| F32s::from_fn(|lane| field(of(lane)));
        MisFactors {
            merge: lanes(|f| f.merge),
            connect: lanes(|f| f.connect),
            hit: lanes(|f| f.hit),
            connections: lanes(|f| f.connections),
            light_paths: lanes(|f| f.light_paths),
            merges: lanes(|f| f.merges),
        }
    }
}

impl MisFactors {
    /// The factors for a frame with `light_paths` light paths and merge radius `radius`,
    /// with or without connections and merging.
    pub fn new(connections: bool, merging: bool, radius: f32, light_paths: f32) -> MisFactors {
        let eta = std::f32::consts::PI * radius * radius * light_paths;
        MisFactors {
            merge: if merging { eta } else { 0.0 },
            connect: if connections && merging {
                1.0 / eta
            } else {
                0.0
            },
            hit: if merging { 1.0 / eta } else { 0.0 },
            connections: if connections { 1.0 } else { 0.0 },
            light_paths,
            merges: 1.0,
        }
    }

    /// Whether light tracing splats the first vertex of a delta light's path: not where
    /// connections run. A light sample at a camera path's first vertex finds every such path
    /// with no noise in the light's direction, where a splat is a count of the light vertices
    /// that land in the pixel (BPT on the bulb-lit Khronos Avocado: 60% of the variance came
    /// from splats); the light sample is then the only technique of those paths, weight 1.
    pub fn splats_first_of_delta(&self) -> bool {
        self.connections == 0.0
    }

    /// Whether a delta light's sample at a camera path's vertex `segments` segments from the
    /// camera is its path's only technique (weight 1): at the first vertex, where the light
    /// path's first vertex is not splatted ([`MisFactors::splats_first_of_delta`]).
    pub fn only_delta_light_sample(&self, segments: u32) -> bool {
        segments == 1 && !self.splats_first_of_delta()
    }

    /// The fewest segments a light vertex that merges lies from its light: 2 where merging
    /// beside a light is no technique ([`MisFactors::beside_light`]), else 1.
    pub fn shortest_merged(&self) -> u32 {
        if self.beside_light().merges == 0.0 {
            2
        } else {
            1
        }
    }

    /// The factors at a light vertex `path_length` segments from its light.
    #[inline(always)]
    pub fn at_light_vertex(&self, path_length: u32) -> MisFactors {
        if path_length == 1 {
            self.beside_light()
        } else {
            *self
        }
    }
}

/// The recursive MIS quantities a subpath carries to its next vertex (thesis Fig. 4.4), of
/// one subpath (`T = f32`) or of a lane group's ([`F32s`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct SubpathMis<T = f32> {
    /// d_VCM: the reverse density of the vertex's own sampling, relative to the forward one.
    pub d_vcm: T,
    /// d_VC: the partial weight sum of the connection techniques along the subpath.
    pub d_vc: T,
    /// d_VM: the partial weight sum of the merging techniques along the subpath.
    pub d_vm: T,
}

impl SubpathMis {
    /// A camera subpath's start (eqs. 31–33 for the camera): `camera_pdf_w` is the solid-angle
    /// pdf of the primary ray's direction.
    pub fn camera(camera_pdf_w: f32, factors: &MisFactors) -> SubpathMis {
        SubpathMis {
            d_vcm: factors.light_paths / camera_pdf_w,
            d_vc: 0.0,
            d_vm: 0.0,
        }
    }

    /// A light subpath's start (eqs. 31–33, 48–50 for delta lights; d_VM carries the emission
    /// hit, so it uses [`MisFactors::hit`], which VCM's 1 / η_VCM equals). `direct_pdf` is the pdf
    /// of light sampling picking the start point and `emission_pdf_w` that of emitting the
    /// ray (position × direction), both including the light's selection probability;
    /// `cos_at_light` is the emission cosine.
    pub fn light(
        direct_pdf: f32,
        emission_pdf_w: f32,
        cos_at_light: f32,
        is_delta: bool,
        is_finite: bool,
        factors: &MisFactors,
    ) -> SubpathMis {
        let d_vc = if is_delta {
            0.0
        } else if is_finite {
            cos_at_light / emission_pdf_w
        } else {
            1.0 / emission_pdf_w
        };
        SubpathMis {
            d_vcm: direct_pdf / emission_pdf_w,
            d_vc,
            d_vm: d_vc * factors.hit,
        }
    }

    /// [`SubpathMis::scatter`] for the BSDF sample `sample` drawn at `surface` (returning
    /// d_VC without the merge there).
    pub fn scattered(
        &mut self,
        surface: &SurfaceHit,
        sample: &BsdfSample,
        factors: &MisFactors,
    ) -> f32 {
        let specular = sample.lobe == LobeKind::Specular;
        let cos_out = surface.cos_geometric(sample.wi);
        self.scatter(cos_out, sample.pdf_fwd, sample.pdf_rev, specular, factors)
    }
}

impl SubpathMis<F32s> {
    /// Sets lane `lane` to one subpath's quantities.
    #[inline(always)]
    pub fn set(&mut self, lane: usize, mis: &SubpathMis) {
        (self.d_vcm.0[lane], self.d_vc.0[lane], self.d_vm.0[lane]) =
            (mis.d_vcm, mis.d_vc, mis.d_vm);
    }

    /// Lane `lane`'s quantities.
    #[inline(always)]
    pub fn lane(&self, lane: usize) -> SubpathMis {
        SubpathMis {
            d_vcm: self.d_vcm.0[lane],
            d_vc: self.d_vc.0[lane],
            d_vm: self.d_vm.0[lane],
        }
    }
}

/// A camera subpath's quantities: [`SubpathMis`], and d_VC as it is without the merge at the
/// path's latest vertex, which the emission that the next segment finds weighs: that vertex
/// lies next to the light there ([`MisFactors::beside_light`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct CameraMis {
    /// The quantities every other technique weighs.
    pub subpath: SubpathMis,
    /// d_VC without the merge at the latest vertex.
    pub d_vc_beside_light: f32,
}

impl CameraMis {
    /// A camera subpath's start ([`SubpathMis::camera`]).
    pub fn camera(camera_pdf_w: f32, factors: &MisFactors) -> CameraMis {
        CameraMis::from(SubpathMis::camera(camera_pdf_w, factors))
    }

    /// The quantities for the emission the latest segment found.
    pub fn beside_light(&self) -> SubpathMis {
        SubpathMis {
            d_vc: self.d_vc_beside_light,
            ..self.subpath
        }
    }

    /// [`SubpathMis::arrive`].
    pub fn arrive(&mut self, distance_sq: Option<f32>, cos_in: f32) {
        self.subpath.arrive(distance_sq, cos_in);
        self.d_vc_beside_light *= 1.0 / cos_in.abs();
    }

    /// [`SubpathMis::scattered`], and d_VC as it is without the merge at `surface`.
    pub fn scattered(&mut self, surface: &SurfaceHit, sample: &BsdfSample, factors: &MisFactors) {
        self.d_vc_beside_light = self.subpath.scattered(surface, sample, factors);
    }
}

impl From<SubpathMis> for CameraMis {
    /// `subpath`, whose latest vertex has no merge.
    fn from(subpath: SubpathMis) -> CameraMis {
        CameraMis {
            subpath,
            d_vc_beside_light: subpath.d_vc,
        }
    }
}

impl<T: Real> SubpathMis<T> {
    /// Completes the quantities on arriving at the next vertex: the squared segment length
    /// (`None` for the first segment of a light at infinity, whose pdfs are in solid angle)
    /// and the cosine at the new vertex.
    pub fn arrive(&mut self, distance_sq: Option<T>, cos_in: T) {
        if let Some(d2) = distance_sq {
            self.d_vcm = self.d_vcm * d2;
        }
        let inv_cos = T::splat(1.0) / cos_in.abs();
        self.d_vcm = self.d_vcm * inv_cos;
        self.d_vc = self.d_vc * inv_cos;
        self.d_vm = self.d_vm * inv_cos;
    }

    /// Updates the quantities for a scattering at the current vertex (eqs. 34–36, 53–55):
    /// `cos_out` is the cosine of the sampled direction, `pdf_fwd` / `pdf_rev` the BSDF's pdfs
    /// of the sampled direction and of the reverse one. Returns the new d_VC as it is without
    /// the merge at this vertex (the factors [`MisFactors::beside_light`] give), which differs
    /// only in the merge's term.
    pub fn scatter(
        &mut self,
        cos_out: T,
        pdf_fwd: T,
        pdf_rev: T,
        specular: bool,
        factors: &MisFactors<T>,
    ) -> T {
        let ratio = cos_out.abs() / pdf_fwd;
        if specular {
            self.d_vcm = T::splat(0.0);
            self.d_vc = self.d_vc * (ratio * pdf_rev);
            self.d_vm = self.d_vm * (ratio * pdf_rev);
            return self.d_vc;
        }
        // d_VC's terms but the merge's: the connections' along the subpath and this vertex's.
        let connected = self.d_vc * pdf_rev + self.d_vcm * factors.connections;
        let d_vc = ratio * (connected + factors.merge);
        let d_vm = ratio * (self.d_vm * pdf_rev + self.d_vcm * factors.connect + factors.merges);
        *self = SubpathMis {
            d_vcm: T::splat(1.0) / pdf_fwd,
            d_vc,
            d_vm,
        };
        ratio * (connected + factors.beside_light().merge)
    }
}

/// Weight of emission found by a camera path that hits an area light (eqs. 42–43; the light
/// sample's term only with connections): `camera` holds the quantities without the merge at
/// the vertex before the light ([`CameraMis::beside_light`]). `direct_pdf_a` and
/// `emission_pdf_w` include the light's selection probability.
pub(crate) fn emission_hit_weight(
    camera: &SubpathMis,
    direct_pdf_a: f32,
    emission_pdf_w: f32,
    factors: &MisFactors,
) -> f32 {
    let w_camera = factors.connections * direct_pdf_a * camera.d_vcm + emission_pdf_w * camera.d_vc;
    1.0 / (1.0 + w_camera)
}

/// The pdfs of a light sample (next event estimation) that its weight needs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightSamplePdfs<T = f32> {
    /// Solid-angle pdf of the sample at the receiver, with the light's selection probability.
    pub direct_pdf_w: T,
    /// Pdf of emitting the same segment from the light, with the selection probability.
    pub emission_pdf_w: T,
    /// Emission cosine at the light (1 for point-like and distant lights).
    pub cos_at_light: T,
    /// Cosine at the receiver toward the light (geometric normal).
    pub cos_at_receiver: T,
    /// BSDF pdf of sampling the light direction (0 for delta lights, which no BSDF sample hits).
    pub bsdf_fwd_pdf_w: T,
    /// BSDF pdf of sampling the camera direction from the light direction.
    pub bsdf_rev_pdf_w: T,
}

/// Weight of a light sample taken at a camera vertex (eqs. 44–45; the vertex lies next to the
/// light, [`MisFactors::beside_light`]).
pub(crate) fn light_sample_weight<T: Real>(
    camera: &SubpathMis<T>,
    pdfs: &LightSamplePdfs<T>,
    factors: &MisFactors<T>,
) -> T {
    let w_light = pdfs.bsdf_fwd_pdf_w / pdfs.direct_pdf_w;
    let merge = factors.beside_light().merge;
    let w_camera = (pdfs.emission_pdf_w * pdfs.cos_at_receiver
        / (pdfs.direct_pdf_w * pdfs.cos_at_light))
        * (merge + camera.d_vcm + camera.d_vc * pdfs.bsdf_rev_pdf_w);
    T::splat(1.0) / (w_light + T::splat(1.0) + w_camera)
}

/// Weight of a light vertex connected to the camera (a light tracing splat, eqs. 46–47):
/// `camera_pdf_a` is the area pdf of the camera sampling the light vertex, `bsdf_rev_pdf_w`
/// the light vertex's BSDF pdf of sampling its incoming direction from the camera direction;
/// `factors` those at the light vertex (beside the light on its path's first hit).
pub(crate) fn camera_connection_weight<T: Real>(
    light: &SubpathMis<T>,
    camera_pdf_a: T,
    bsdf_rev_pdf_w: T,
    factors: &MisFactors<T>,
) -> T {
    let w_light = (camera_pdf_a / factors.light_paths)
        * (factors.merge + light.d_vcm + light.d_vc * bsdf_rev_pdf_w);
    T::splat(1.0) / (w_light + T::splat(1.0))
}

/// The pdfs at both ends of a connection between a camera vertex and a light vertex.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ConnectionPdfs<T = f32> {
    /// Area pdf of the camera vertex's BSDF sampling the light vertex.
    pub camera_fwd_pdf_a: T,
    /// The camera vertex's BSDF pdf of sampling its incoming direction from the connection.
    pub camera_rev_pdf_w: T,
    /// Area pdf of the light vertex's BSDF sampling the camera vertex.
    pub light_fwd_pdf_a: T,
    /// The light vertex's BSDF pdf of sampling its incoming direction from the connection.
    pub light_rev_pdf_w: T,
}

/// Weight of a connection between a camera vertex and a light vertex (eqs. 40–41):
/// `light_factors` are those at the light vertex (beside the light on its path's first hit).
pub(crate) fn connection_weight<T: Real>(
    (camera, light): (&SubpathMis<T>, &SubpathMis<T>),
    pdfs: &ConnectionPdfs<T>,
    (factors, light_factors): (&MisFactors<T>, &MisFactors<T>),
) -> T {
    let w_light = pdfs.camera_fwd_pdf_a
        * (light_factors.merge + light.d_vcm + light.d_vc * pdfs.light_rev_pdf_w);
    let w_camera =
        pdfs.light_fwd_pdf_a * (factors.merge + camera.d_vcm + camera.d_vc * pdfs.camera_rev_pdf_w);
    T::splat(1.0) / (w_light + T::splat(1.0) + w_camera)
}

/// Weight of merging a camera vertex with a light vertex (eqs. 38–39): `camera_fwd_pdf_w` is
/// the camera BSDF's pdf of the light vertex's incoming direction, `camera_rev_pdf_w` its pdf
/// of the camera direction given that one.
pub(crate) fn merge_weight<T: Real>(
    camera: &SubpathMis<T>,
    light: &SubpathMis<T>,
    camera_fwd_pdf_w: T,
    camera_rev_pdf_w: T,
    factors: &MisFactors<T>,
) -> T {
    let w_light = light.d_vcm * factors.connect + light.d_vm * camera_fwd_pdf_w;
    let w_camera = camera.d_vcm * factors.connect + camera.d_vm * camera_rev_pdf_w;
    T::splat(1.0) / (w_light + T::splat(1.0) + w_camera)
}

#[cfg(test)]
#[path = "mis_tests.rs"]
mod tests;
