//! A material's lobes as plain numbers, for shading code outside this crate (the GPU path
//! tracer's WGSL): the same lobes, weights and selection [`Lobes`](super::Lobes) builds, so
//! that such code need not rebuild them from the material.

use glam::Vec3;

/// The lobes of one material ([`Lobes::flat`](super::Lobes::flat)); `None` where the
/// material has no such lobe. Lobe k of the selection is, in order: `specular`, `diffuse`,
/// `dielectric`, `thin`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatLobes {
    /// Index of refraction (≥ 1) of the interface and of the specular layer.
    pub ior: f32,
    /// The Schlick reflection lobe (conductor and specular layer merged).
    pub specular: Option<FlatSchlick>,
    /// The diffuse base.
    pub diffuse: Option<FlatDiffuse>,
    /// The refracting interface (thick volume).
    pub dielectric: Option<FlatInterface>,
    /// The thin-walled interface.
    pub thin: Option<FlatInterface>,
    /// The lobe selection probabilities where they do not depend on the outgoing direction.
    pub constant_selection: Option<[f32; 4]>,
}

/// Schlick reflection: F = F0 + (F90 − F0)(1 − cos)⁵.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatSchlick {
    /// Reflectance at normal incidence.
    pub f0: Vec3,
    /// Reflectance at grazing incidence.
    pub f90: Vec3,
    /// GGX α, `None` for a mirror (Dirac delta).
    pub alpha: Option<f32>,
    /// Its directional albedo (its selection weight).
    pub albedo: FlatAlbedo,
}

/// The directional albedo E(μ) = F0·A(μ, α) + F90·B(μ, α) of a Schlick GGX lobe, A and B
/// bilinear in the tables of [`albedo_tables`](super::albedo_tables) (E = the Schlick
/// Fresnel itself for a mirror).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatAlbedo {
    /// The lobe's F0.
    pub f0: Vec3,
    /// The lobe's F90.
    pub f90: Vec3,
    /// The tables' lower row in α and the fraction toward the next; `None` for a mirror.
    pub row: Option<(usize, f32)>,
}

/// The diffuse base.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatDiffuse {
    /// Albedo ρ (selection weight).
    pub albedo: Vec3,
    /// f = scale · (1 − E(μo))(1 − E(μi)); without a specular layer plain Lambert, ρ/π.
    pub scale: Vec3,
    /// The reflecting specular layer over it, whose albedo E compensates the energy;
    /// `None` for plain Lambert.
    pub layer: Option<FlatAlbedo>,
}

/// A dielectric interface, thick or thin-walled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatInterface {
    /// Its share of the material, (1 − metallic) · transmission.
    pub weight: f32,
    /// Transmission tint (the base color).
    pub tint: Vec3,
    /// GGX α, `None` for a smooth interface (Dirac deltas).
    pub alpha: Option<f32>,
}
