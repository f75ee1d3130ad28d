//! Tests of the BSDF against its contract: sampling matches the pdf (chi-square), energy
//! conservation, reciprocity and the η² relation, sample/eval consistency, the adjoint
//! shading-normal correction, sides and degenerate inputs.
//!
//! All randomness is seeded; tolerances come from the estimators' standard errors (or
//! documented deterministic error bounds), not from observed outputs.

mod chi2;
mod consistency;
mod energy;
mod reciprocity;
mod sides;

use super::{Bsdf, BsdfParams, TransportMode};
use crate::frame::Frame;
use crate::sampling::{Rng, Sampler};
use glam::Vec3;
use std::f32::consts::TAU;

/// The perceptual roughness sweep: 0 is smooth (delta), 0.05 the narrowest lobe (α =
/// 0.0025) the chi-square test's cells resolve.
const ROUGHNESS_SWEEP: [f32; 6] = [0.0, 0.05, 0.1, 0.3, 0.6, 1.0];
/// The non-delta part of the sweep.
const ROUGH_SWEEP: [f32; 4] = [0.1, 0.3, 0.6, 1.0];
/// Incident cosines cos θo.
const COS_SWEEP: [f32; 5] = [0.05, 0.2, 0.5, 0.8, 1.0];

/// A geometric normal that is not an axis, so that frames are exercised.
fn n_g() -> Vec3 {
    Vec3::new(0.3, -0.5, 0.8).normalize()
}

/// World direction at cos θ = `cos_theta`, azimuth `phi` around `n`.
fn direction(n: Vec3, cos_theta: f32, phi: f32) -> Vec3 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Frame::from_z(n)
        .to_world(Vec3::new(
            sin_theta * phi.cos(),
            sin_theta * phi.sin(),
            cos_theta,
        ))
        .normalize()
}

/// A direction uniform over the sphere (either side of `n_g()`).
fn random_direction(rng: &mut Rng) -> Vec3 {
    let (c, phi) = (2.0 * rng.uniform() - 1.0, TAU * rng.uniform());
    direction(n_g(), c, phi)
}

/// A shading normal tilted away from `n_g()` by `angle` radians.
fn tilted_normal(angle: f32) -> Vec3 {
    let f = Frame::from_z(n_g());
    (f.z * angle.cos() + f.x * angle.sin()).normalize()
}

fn lambert(base: Vec3) -> BsdfParams {
    BsdfParams {
        base_color: base,
        metallic: 0.0,
        roughness: 1.0,
        specular: 0.0,
        ..BsdfParams::default()
    }
}

fn dielectric_base(roughness: f32) -> BsdfParams {
    BsdfParams {
        metallic: 0.0,
        roughness,
        ..BsdfParams::default()
    }
}

fn conductor(roughness: f32) -> BsdfParams {
    BsdfParams {
        base_color: Vec3::new(0.95, 0.64, 0.54),
        metallic: 1.0,
        roughness,
        ..BsdfParams::default()
    }
}

fn glass(roughness: f32, ior: f32) -> BsdfParams {
    BsdfParams {
        metallic: 0.0,
        roughness,
        transmission: 1.0,
        ior,
        thin_walled: false,
        ..BsdfParams::default()
    }
}

fn thin_glass(roughness: f32) -> BsdfParams {
    BsdfParams {
        thin_walled: true,
        ..glass(roughness, 1.5)
    }
}

fn mixture(roughness: f32) -> BsdfParams {
    BsdfParams {
        base_color: Vec3::new(0.8, 0.6, 0.3),
        metallic: 0.5,
        transmission: 0.5,
        thin_walled: false,
        ..dielectric_base(roughness)
    }
}

/// Every material class at `roughness`, with names for messages.
fn material_classes(roughness: f32) -> Vec<(String, BsdfParams)> {
    vec![
        (
            format!("dielectric base r={roughness}"),
            dielectric_base(roughness),
        ),
        (format!("conductor r={roughness}"), conductor(roughness)),
        (format!("glass 1.5 r={roughness}"), glass(roughness, 1.5)),
        (format!("glass 1.33 r={roughness}"), glass(roughness, 1.33)),
        (format!("thin glass r={roughness}"), thin_glass(roughness)),
        (format!("mixture r={roughness}"), mixture(roughness)),
    ]
}

/// One-sided BSDF with n_s = n_g.
fn bsdf(params: &BsdfParams) -> Bsdf {
    Bsdf::new(params, n_g(), n_g(), false)
}

/// Whether the material has a transmitting interface (it then scatters from both sides).
fn is_transmissive(params: &BsdfParams) -> bool {
    params.transmission > 0.0 && params.metallic < 1.0
}

/// Whether a pair is numerically well conditioned in f32: for a transmission pair (a
/// outside, b inside, IOR ratio `ior`) the microfacet normal m ∝ a + ior·b must not be
/// grazing for either direction, where Fresnel transmittance near the critical angle has an
/// unbounded derivative (a 1e-7 error in a cosine changes T by percents).
fn well_conditioned(a: Vec3, b: Vec3, ior: f32) -> bool {
    if a.dot(n_g()) * b.dot(n_g()) > 0.0 {
        return true;
    }
    let (outside, inside) = if a.dot(n_g()) > 0.0 { (a, b) } else { (b, a) };
    let m = (outside + ior * inside).normalize();
    outside.dot(m).abs() > 0.02 && inside.dot(m).abs() > 0.02
}

/// Absolute floor of value comparisons (in units of f, 1/sr): f32 round-off is amplified
/// in the far tails of narrow lobes and near total internal reflection, where values are
/// many orders of magnitude below the lobe's peak.
const ABS_FLOOR: f32 = 1e-6;

/// |a − b| ≤ rel · max(|a|, |b|) + [`ABS_FLOOR`], per channel.
fn close(a: Vec3, b: Vec3, rel: f32) -> bool {
    (a - b).abs().max_element() <= rel * a.abs().max(b.abs()).max_element() + ABS_FLOOR
}

/// Both transport modes.
const MODES: [TransportMode; 2] = [TransportMode::Radiance, TransportMode::Importance];
