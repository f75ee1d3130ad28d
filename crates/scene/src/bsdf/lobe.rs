//! The interface between the BSDF mixture and its lobes.
//!
//! Lobes work in the local shading frame with the outgoing direction `wo` in the upper
//! hemisphere (`wo.z > 0`; the caller mirrors the frame when `wo` is on the back side).
//! `eta` is the relative IOR η(wi side) / η(wo side) of a refracting interface (only the
//! thick dielectric uses it). Every lobe value already includes the lobe's mixture weight.

use super::microfacet::Ggx;
use super::{LobeKind, TransportMode};
use glam::{Vec2, Vec3};

/// The class of a microfacet lobe: glossy with a GGX distribution, a delta (specular) without.
pub(super) fn microfacet_kind(ggx: Option<&Ggx>) -> LobeKind {
    if ggx.is_some() {
        LobeKind::Glossy
    } else {
        LobeKind::Specular
    }
}

/// Discrete probability that a smooth interface with reflectance `r` picks its reflected
/// (`r`) or transmitted (1 − r) delta; 0 for rough interfaces, which have no deltas.
pub(super) fn interface_delta_prob(ggx: Option<&Ggx>, r: f32, transmitted: bool) -> f32 {
    match (ggx, transmitted) {
        (Some(_), _) => 0.0,
        (None, true) => 1.0 - r,
        (None, false) => r,
    }
}

/// Selection weight of an interface lobe: its reflectance `r` plus the tinted transmittance,
/// times the lobe's mixture weight.
pub(super) fn interface_selection_weight(weight: f32, tint: Vec3, r: f32) -> f32 {
    weight * (r + (1.0 - r) * mean(tint))
}

/// Direction drawn by a lobe.
pub(super) enum LobeSample {
    /// A direction from a non-delta lobe; its value and pdf are evaluated afterwards by
    /// summing all non-delta lobes ([`Mixture::eval`](super::mixture::Mixture::eval)).
    Direction(Vec3),
    /// A direction of a Dirac delta lobe.
    Delta {
        /// Local incident direction.
        wi: Vec3,
        /// Coefficient of the delta: ∫ f |cos θi| over the delta's support, RGB.
        weight: Vec3,
        /// Discrete probability with which the lobe chose this delta (given it was selected).
        prob: f32,
        /// Whether `wi` is on the other side of the surface.
        transmitted: bool,
        /// Relative IOR crossed (1 for reflection and thin sheets).
        eta: f32,
    },
}

/// One lobe (or pair of reflection/transmission lobes sharing one sampling routine).
pub(super) trait Lobe {
    /// Non-delta value f(wo, wi)·|cos θi| (RGB) and the lobe's own sampling pdf (solid angle)
    /// of `wi`. Zero for delta lobes.
    fn eval(&self, wo: Vec3, wi: Vec3, eta: f32, mode: TransportMode) -> (Vec3, f32);

    /// The pdf [`eval`](Lobe::eval) returns, without the value: reverse pdfs need only
    /// this, and lobes whose value costs more than their pdf skip that work.
    fn pdf(&self, wo: Vec3, wi: Vec3, eta: f32) -> f32 {
        self.eval(wo, wi, eta, TransportMode::Radiance).1
    }

    /// Draws a direction with the remapped lobe-selection number `u_sub` ∈ [0, 1) (for
    /// reflection/transmission choices) and `u` ∈ [0, 1)².
    fn sample(
        &self,
        wo: Vec3,
        eta: f32,
        u_sub: f32,
        u: Vec2,
        mode: TransportMode,
    ) -> Option<LobeSample>;

    /// Discrete probability of choosing the delta (reflected or `transmitted`) from `wo`;
    /// 0 for non-delta lobes.
    fn delta_prob(&self, wo: Vec3, eta: f32, transmitted: bool) -> f32;

    /// Selection weight at `wo` (an estimate of the lobe's albedo, > 0 wherever the lobe can
    /// be non-zero).
    fn selection_weight(&self, wo: Vec3, eta: f32) -> f32;

    /// [`selection_weight`](Lobe::selection_weight) where it is the same for every `wo` and
    /// `eta` (a plain Lambert lobe), bit for bit; `None` where it depends on them.
    fn constant_selection_weight(&self) -> Option<f32> {
        None
    }

    /// Class of the lobe ([`LobeKind::Specular`] for delta lobes).
    fn kind(&self) -> LobeKind;
}

/// Mean of the RGB channels (used for scalar selection weights).
pub(super) fn mean(v: Vec3) -> f32 {
    v.element_sum() / 3.0
}
