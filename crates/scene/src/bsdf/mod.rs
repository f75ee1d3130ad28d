//! The surface scattering model: glTF metallic-roughness with the KHR_materials_specular,
//! KHR_materials_transmission, KHR_materials_ior and (thin-walled vs volume)
//! KHR_materials_volume extensions.
//!
//! # Model
//!
//! With m = metallic, t = transmission and α = roughness² (GGX width):
//!
//! f = m·conductor + (1 − m)·[ t·dielectric_interface + (1 − t)·dielectric_base ]
//!
//! * **conductor**: GGX reflection with Schlick Fresnel F0 = base_color, F90 = 1:
//!   f = F(ωo·h) D(h) G2(ωo, ωi) / (4 cos θo cos θi) (Walter et al. 2007, eq. 20), with the
//!   Trowbridge-Reitz D and the **height-correlated** Smith G2 = 1/(1 + Λ(ωo) + Λ(ωi))
//!   (Heitz 2014) (`microfacet.rs`).
//! * **dielectric_base**: a GGX specular layer with Schlick F0 = min(((ior−1)/(ior+1))²·
//!   specular_color, 1)·specular, F90 = specular, over a Lambertian base with albedo ρ =
//!   base_color, scaled reciprocally for energy conservation (Kelemen & Szirmay-Kalos 2001,
//!   Kulla & Conty 2017) instead of glTF's non-conserving fresnel_mix:
//!   f_diffuse = ρ/π · (1 − E(μo))(1 − E(μi)) / (1 − E_avg), where E(μ) = F0·A(μ, α) +
//!   F90·B(μ, α) is the specular layer's directional albedo (tabulated, `albedo.rs`) and
//!   E_avg = 2∫E(μ)μ dμ. The diffuse albedo is exactly ρ(1 − E(μo)), so white base + layer
//!   reflects E + (1 − E) = 1 at every angle. specular = 0 gives exactly Lambert.
//!   (The conductor and the specular layer are merged into one Schlick lobe, `specular.rs`.)
//! * **dielectric_interface**: exact dielectric Fresnel; reflection plus refraction through
//!   the relative IOR (rough: Walter et al. 2007), transmission tinted by base_color
//!   (`dielectric.rs`). Radiance transport scales refracted light by 1/η² (pbrt-v4
//!   convention), importance transport does not. Thin-walled: no bending, the sheet's
//!   multiple-reflection R' = R + T²R/(1 − R²) (`thin_dielectric.rs`). The specular and
//!   specular_color factors do not affect the interface.
//!
//! Roughness 0 makes every lobe a Dirac delta: mirror reflection with the same Fresnel, or
//! ideal refraction. Any roughness r > 0 is GGX with α = max(r², [`MIN_ALPHA`])
//! ([`ggx_alpha`]), as the scene conventions ask: a polished surface (r = 0.02, α = 4·10⁻⁴)
//! shows a point light's highlight, which a delta lobe cannot.
//!
//! # Sampling
//! One lobe is chosen with probability proportional to its albedo estimate at ωo (the
//! tabulated E for the Schlick lobe, ρ(1 − E(μo)) for the diffuse, R + T·tint for the
//! interface), then GGX lobes sample visible normals (Dupuy & Benyoub 2023), the diffuse
//! the cosine-weighted hemisphere. Non-delta pdfs are exact mixture pdfs (`mixture.rs`).
//!
//! # Conventions
//! * `wo` points away from the surface toward the previous path vertex, `wi` toward the
//!   next; world space, unit length. pdfs are per steradian (delta lobes: discrete
//!   probabilities).
//! * `f_cos` = f(ωo, ωi)·|ωi·n_s| in radiance mode, f(ωo, ωi)·|ωo·n_s||ωi·n_g|/|ωo·n_g| in
//!   importance mode (Veach 1997, §5.3). For delta lobes it is the delta's coefficient
//!   (with the same correction).
//! * Reflection vs transmission is decided by the geometric normal n_g; a pair that n_s
//!   classifies differently is black. ωo below the shading hemisphere (after orienting by
//!   n_g) is black too.
//! * Sides: an opaque material with `double_sided == false` is black for ωo behind n_g; a
//!   double-sided one mirrors both normals toward ωo. Transmissive materials always work
//!   from both sides; through a (thick) interface the relative IOR η = η(ωi side)/η(ωo side)
//!   is `ior` from the front and 1/`ior` from the back (thin-walled: no bending, η = 1).
//! * Cosines below [`GRAZING_COS`] give zero / `None`, as do NaN inputs.

mod albedo;
mod dielectric;
mod diffuse;
mod flat;
mod fresnel;
mod lobe;
mod microfacet;
mod mixture;
mod specular;
mod surface;
mod thin_dielectric;

#[cfg(test)]
mod tests;

pub use albedo::{ALBEDO_TABLE_SIZE, AlbedoTables, albedo_tables};
pub use flat::{FlatAlbedo, FlatDiffuse, FlatInterface, FlatLobes, FlatSchlick};
pub use surface::{Bsdf, FixedOutgoing, GRAZING_COS, Lobes};

use glam::Vec3;

/// Smallest GGX α of a rough lobe (roughness r > 0 gives α = max(r², `MIN_ALPHA`), so
/// r < 0.01 renders as r = 0.01). Mitsuba 3 clamps its microfacet α to the same floor; below
/// it, f32 half vectors would resolve the lobe poorly and its pdfs (≈ 1/(πα²)) approach
/// the range where MIS squares overflow.
pub const MIN_ALPHA: f32 = 1e-4;

/// The GGX α of a lobe with glTF perceptual `roughness`: r² at least [`MIN_ALPHA`]; `None`
/// for roughness 0 (or below), a perfectly smooth (Dirac delta) lobe.
pub fn ggx_alpha(roughness: f32) -> Option<f32> {
    (roughness > 0.0).then(|| (roughness * roughness).max(MIN_ALPHA))
}

/// Material inputs after texture lookup (glTF metallic-roughness and extensions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfParams {
    /// Linear RGB base color in [0, 1] (diffuse albedo, metal F0, transmission tint).
    pub base_color: Vec3,
    /// Metalness in [0, 1].
    pub metallic: f32,
    /// Perceptual roughness in [0, 1]; GGX α = roughness².
    pub roughness: f32,
    /// KHR_materials_specular `specularFactor` in [0, 1] (default 1).
    pub specular: f32,
    /// KHR_materials_specular `specularColorFactor`, linear RGB (default 1).
    pub specular_color: Vec3,
    /// KHR_materials_transmission `transmissionFactor` in [0, 1] (default 0).
    pub transmission: f32,
    /// KHR_materials_ior index of refraction (default 1.5; values below 1 or non-finite
    /// fall back to 1.5).
    pub ior: f32,
    /// True unless KHR_materials_volume `thicknessFactor` > 0 (a thin sheet, no refraction).
    pub thin_walled: bool,
}

impl Default for BsdfParams {
    /// glTF defaults: white, metallic 1, roughness 1, specular 1, no transmission, IOR 1.5,
    /// thin-walled.
    fn default() -> BsdfParams {
        BsdfParams {
            base_color: Vec3::ONE,
            metallic: 1.0,
            roughness: 1.0,
            specular: 1.0,
            specular_color: Vec3::ONE,
            transmission: 0.0,
            ior: 1.5,
            thin_walled: true,
        }
    }
}

/// What a path carries: camera paths carry radiance, light paths importance. Only refraction
/// (the 1/η² factor) and the shading-normal correction depend on it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    /// Camera subpaths.
    Radiance,
    /// Light subpaths.
    Importance,
}

/// Which pdfs [`Bsdf::eval_with`] and [`Bsdf::sample_with`] compute. The reverse pdf costs
/// a second evaluation of every lobe; only integrators that weigh a path from both of its
/// ends (the VCM family) need it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pdfs {
    /// Only `pdf_fwd`; `pdf_rev` is left 0.
    Forward,
    /// `pdf_fwd` and `pdf_rev`.
    Both,
}

/// Classification of lobes and vertices for integrators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LobeKind {
    /// Lambertian.
    Diffuse,
    /// Rough GGX (non-delta, possibly narrow).
    Glossy,
    /// Dirac delta (mirror, ideal refraction, thin-sheet pass-through): no connection or
    /// merge possible.
    Specular,
}

/// A sampled direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Sampled direction, world space, unit.
    pub wi: Vec3,
    /// f(wo, wi)·|cos| including the shading-normal / adjoint correction (see the module
    /// docs); for delta lobes the delta's coefficient. Throughput update: f_cos / pdf_fwd.
    pub f_cos: Vec3,
    /// Pdf of `wi` given `wo` (per steradian, mixture of all non-delta lobes); for delta
    /// lobes the discrete probability of having chosen this delta.
    pub pdf_fwd: f32,
    /// Pdf of sampling `wo` given `wi` with the same BSDF (same units as `pdf_fwd`); 0 when
    /// not asked for ([`Pdfs::Forward`]).
    pub pdf_rev: f32,
    /// Class of the lobe that produced the sample.
    pub lobe: LobeKind,
    /// Whether `wi` is on the other side of the surface (by the geometric normal).
    pub transmitted: bool,
    /// Relative IOR crossed, η(wi side) / η(wo side); 1 for reflection and thin sheets.
    pub eta: f32,
}

/// Value of the non-delta lobes for a pair of directions.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BsdfEval {
    /// f(wo, wi)·|cos| with the same convention as [`BsdfSample::f_cos`].
    pub f_cos: Vec3,
    /// Pdf of sampling `wi` from `wo` (per steradian).
    pub pdf_fwd: f32,
    /// Pdf of sampling `wo` from `wi` (per steradian); 0 when not asked for
    /// ([`Pdfs::Forward`]).
    pub pdf_rev: f32,
}
