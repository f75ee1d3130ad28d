//! The weighted sum of lobes in the local shading frame, with one-sample lobe selection.
//!
//! Lobe k is selected with probability p_k = w_k(ωo) / Σ w_j(ωo) (its estimated albedo,
//! [`Lobe::selection_weight`]), so the pdf of a non-delta direction is the exact mixture
//! pdf Σ_{k non-delta} p_k pdf_k(ωi) and a delta direction has the discrete probability
//! p_k · (the lobe's own choice probability).

use super::albedo::SpecularAlbedo;
use super::dielectric::Dielectric;
use super::diffuse::CompensatedDiffuse;
use super::lobe::{Lobe, LobeSample};
use super::microfacet::Ggx;
use super::specular::SchlickReflection;
use super::thin_dielectric::ThinDielectric;
use super::{BsdfParams, FlatInterface, FlatLobes, LobeKind, TransportMode, ggx_alpha};
use glam::{Vec2, Vec3};

/// Number of lobe slots.
const LOBES: usize = 4;

/// Lobe selection probabilities at one `wo` (see [`Mixture::selection`]), one per lobe slot.
pub(super) type Selection = [f32; LOBES];

/// Largest `f32` below 1.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Lobes of a material; absent lobes have zero weight.
#[derive(Clone, Debug)]
pub(super) struct Mixture {
    /// Sanitized IOR (of the interface and of the specular layer's F0).
    ior: f32,
    specular: Option<SchlickReflection>,
    diffuse: Option<CompensatedDiffuse>,
    dielectric: Option<Dielectric>,
    thin: Option<ThinDielectric>,
    /// The selection at every `wo`, where no lobe's weight depends on it (plain Lambert).
    constant_selection: Option<Selection>,
}

/// A direction sampled from the mixture, in the local frame.
pub(super) struct MixtureSample {
    pub wi: Vec3,
    pub kind: LobeKind,
    pub transmitted: bool,
    /// Relative IOR crossed (1 for reflection and thin sheets).
    pub eta: f32,
    /// Set for a delta lobe's sample (non-delta samples are evaluated by the caller).
    pub delta: Option<DeltaSample>,
}

/// Value of a delta sample.
pub(super) struct DeltaSample {
    /// Coefficient of the delta (∫ f |cos θi| over its support), RGB.
    pub f_cos: Vec3,
    /// Discrete probability of the delta: p_lobe(ωo) times the lobe's own choice.
    pub prob: f32,
    /// Slot of the lobe (for the reverse probability, [`Mixture::delta_pdf`]).
    pub lobe: usize,
}

/// Replaces NaN/inf by `default` and clamps into [lo, hi].
fn sanitize(x: f32, default: f32, lo: f32, hi: f32) -> f32 {
    if x.is_finite() {
        x.clamp(lo, hi)
    } else {
        default
    }
}

fn sanitize3(v: Vec3, default: f32, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(
        sanitize(v.x, default, lo, hi),
        sanitize(v.y, default, lo, hi),
        sanitize(v.z, default, lo, hi),
    )
}

/// Selection probabilities from selection weights `w` (all zero unless their sum is
/// positive and finite).
#[inline]
fn normalized(mut w: [f32; LOBES]) -> Selection {
    let total: f32 = w.iter().sum();
    if total > 0.0 && total.is_finite() {
        w.iter_mut().for_each(|wk| *wk /= total);
        w
    } else {
        [0.0; LOBES]
    }
}

impl Mixture {
    /// Lobes and weights of the glTF model (see the [module docs](super)).
    pub fn new(params: &BsdfParams) -> Mixture {
        let base = sanitize3(params.base_color, 0.0, 0.0, 1.0);
        let metallic = sanitize(params.metallic, 0.0, 0.0, 1.0);
        let roughness = sanitize(params.roughness, 1.0, 0.0, 1.0);
        let specular = sanitize(params.specular, 1.0, 0.0, 1.0);
        let specular_color = sanitize3(params.specular_color, 1.0, 0.0, f32::MAX);
        let transmission = sanitize(params.transmission, 0.0, 0.0, 1.0);
        let ior = if params.ior.is_finite() && params.ior >= 1.0 {
            params.ior
        } else {
            1.5
        };

        let ggx = ggx_alpha(roughness).map(|alpha| Ggx { alpha });
        let w_interface = (1.0 - metallic) * transmission;
        let w_base = (1.0 - metallic) * (1.0 - transmission);

        // Specular layer of the dielectric base (KHR_materials_specular).
        let r0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
        let layer_f0 = (r0 * specular_color).min(Vec3::ONE) * specular;
        let layer_f90 = Vec3::splat(specular);
        let layer = SpecularAlbedo::new(layer_f0, layer_f90, ggx);

        let f0 = metallic * base + w_base * layer_f0;
        let f90 = metallic * Vec3::ONE + w_base * layer_f90;
        let diffuse_albedo = w_base * base;
        let index_matched = (ior - 1.0).abs() < 1e-4;
        let mut mixture = Mixture {
            ior,
            specular: (f0.max(f90).max_element() > 0.0)
                .then(|| SchlickReflection::new(f0, f90, ggx)),
            diffuse: (diffuse_albedo.max_element() > 0.0)
                .then(|| CompensatedDiffuse::new(diffuse_albedo, layer)),
            dielectric: (w_interface > 0.0 && !params.thin_walled).then_some(Dielectric {
                weight: w_interface,
                tint: base,
                ggx: if index_matched { None } else { ggx },
            }),
            thin: (w_interface > 0.0 && params.thin_walled).then_some(ThinDielectric {
                weight: w_interface,
                tint: base,
                ior,
                ggx,
            }),
            constant_selection: None,
        };
        mixture.constant_selection = mixture
            .weights(|lobe| lobe.constant_selection_weight())
            .map(normalized);
        mixture
    }

    /// IOR of the material (non-finite or < 1 replaced by 1.5).
    pub fn ior(&self) -> f32 {
        self.ior
    }

    /// The lobes as plain numbers ([`FlatLobes`]).
    pub fn flat(&self) -> FlatLobes {
        FlatLobes {
            ior: self.ior,
            specular: self.specular.as_ref().map(SchlickReflection::flat),
            diffuse: self.diffuse.as_ref().map(CompensatedDiffuse::flat),
            dielectric: self.dielectric.as_ref().map(|d| FlatInterface {
                weight: d.weight,
                tint: d.tint,
                alpha: d.ggx.map(|g| g.alpha),
            }),
            thin: self.thin.as_ref().map(|t| FlatInterface {
                weight: t.weight,
                tint: t.tint,
                alpha: t.ggx.map(|g| g.alpha),
            }),
            constant_selection: self.constant_selection,
        }
    }

    /// f of a mixture that is one plain Lambert lobe (no layer above it, no other lobe):
    /// the value [`Mixture::eval`] divides by |cos θi| for every pair of directions in the
    /// upper hemisphere, where its lobe is selected with probability 1.
    pub fn lambert(&self) -> Option<Vec3> {
        match self {
            Mixture {
                specular: None,
                diffuse: Some(diffuse),
                dielectric: None,
                thin: None,
                ..
            } => diffuse.lambert(),
            _ => None,
        }
    }

    fn lobes(&self) -> [Option<&dyn Lobe>; LOBES] {
        [
            self.specular.as_ref().map(|l| l as &dyn Lobe),
            self.diffuse.as_ref().map(|l| l as &dyn Lobe),
            self.dielectric.as_ref().map(|l| l as &dyn Lobe),
            self.thin.as_ref().map(|l| l as &dyn Lobe),
        ]
    }

    /// Whether a transmitting interface is present (the material then works from both sides).
    pub fn transmits(&self) -> bool {
        self.dielectric.is_some() || self.thin.is_some()
    }

    /// Whether some lobe is not a Dirac delta.
    pub fn has_non_delta(&self) -> bool {
        self.lobes()
            .into_iter()
            .flatten()
            .any(|l| l.kind() != LobeKind::Specular)
    }

    /// Most specular class among the non-delta lobes; `Specular` when all lobes are deltas.
    pub fn classify(&self) -> LobeKind {
        let kinds = self.lobes().into_iter().flatten().map(|l| l.kind());
        kinds.fold(LobeKind::Specular, |class, kind| match (class, kind) {
            (LobeKind::Glossy, _) | (_, LobeKind::Glossy) => LobeKind::Glossy,
            (LobeKind::Diffuse, _) | (_, LobeKind::Diffuse) => LobeKind::Diffuse,
            _ => LobeKind::Specular,
        })
    }

    /// Selection probabilities at `wo` (all zero when no lobe can scatter): what
    /// [`Mixture::eval`] and [`Mixture::sample`] take, so that one `wo` computes them once.
    #[inline]
    pub fn selection(&self, wo: Vec3, eta: f32) -> Selection {
        match self.constant_selection {
            Some(p) => p,
            None => self.selection_at(wo, eta),
        }
    }

    /// [`Mixture::selection`] computed from the lobes' weights at `wo`.
    #[inline]
    fn selection_at(&self, wo: Vec3, eta: f32) -> Selection {
        let w = self.weights(|lobe| Some(lobe.selection_weight(wo, eta)));
        w.map_or([0.0; LOBES], normalized)
    }

    /// Each lobe slot's selection weight from `weight`, clamped at 0 (absent lobes 0), or
    /// `None` where `weight` gives none for a present lobe.
    #[inline]
    fn weights(&self, weight: impl Fn(&dyn Lobe) -> Option<f32>) -> Option<[f32; LOBES]> {
        let mut w = [0.0; LOBES];
        for (wk, lobe) in w.iter_mut().zip(self.lobes()) {
            if let Some(lobe) = lobe {
                *wk = weight(lobe)?.max(0.0);
            }
        }
        Some(w)
    }

    /// f·|cos θi| of the non-delta lobes and the mixture pdf of `wi` (local, `wo.z > 0`),
    /// `p` being the [selection](Mixture::selection) at `wo`.
    #[inline]
    pub fn eval(
        &self,
        p: &Selection,
        wo: Vec3,
        wi: Vec3,
        eta: f32,
        mode: TransportMode,
    ) -> (Vec3, f32) {
        let (mut f_cos, mut pdf) = (Vec3::ZERO, 0.0);
        for (pk, lobe) in p.iter().zip(self.lobes()) {
            if let Some(lobe) = lobe {
                let (f, lobe_pdf) = lobe.eval(wo, wi, eta, mode);
                f_cos += f;
                pdf += pk * lobe_pdf;
            }
        }
        (f_cos, pdf)
    }

    /// The mixture pdf of [`Mixture::eval`] alone.
    #[inline]
    pub fn pdf(&self, p: &Selection, wo: Vec3, wi: Vec3, eta: f32) -> f32 {
        let lobes = p.iter().zip(self.lobes());
        lobes
            .filter_map(|(pk, lobe)| Some(pk * lobe?.pdf(wo, wi, eta)))
            .sum()
    }

    /// Samples one lobe with `u_lobe` from the [selection](Mixture::selection) `p` at `wo`,
    /// then a direction from it with `u`. Non-delta samples carry no value: the caller
    /// evaluates [`Mixture::eval`] at the final direction.
    #[inline]
    pub fn sample(
        &self,
        p: &Selection,
        wo: Vec3,
        eta: f32,
        u_lobe: f32,
        u: Vec2,
        mode: TransportMode,
    ) -> Option<MixtureSample> {
        // Invert the discrete CDF; the last lobe with p > 0 absorbs rounding at u_lobe ≈ 1.
        let (mut cdf, mut chosen) = (0.0, None);
        for (k, &pk) in p.iter().enumerate().filter(|(_, pk)| **pk > 0.0) {
            chosen = Some((k, cdf, pk));
            if u_lobe < cdf + pk {
                break;
            }
            cdf += pk;
        }
        let (k, start, pk) = chosen?;
        // Remap u_lobe onto [0, 1) within the chosen interval for the lobe's own choices.
        let u_sub = ((u_lobe - start) / pk).clamp(0.0, ONE_MINUS_EPSILON);
        let lobe = self.lobes()[k]?;
        match lobe.sample(wo, eta, u_sub, u, mode)? {
            LobeSample::Delta {
                wi,
                weight,
                prob,
                transmitted,
                eta,
            } => {
                let prob = p[k] * prob;
                (prob > 0.0).then_some(MixtureSample {
                    wi,
                    kind: LobeKind::Specular,
                    transmitted,
                    eta,
                    delta: Some(DeltaSample {
                        f_cos: weight,
                        prob,
                        lobe: k,
                    }),
                })
            }
            LobeSample::Direction(wi) => {
                let transmitted = wi.z < 0.0;
                Some(MixtureSample {
                    wi,
                    kind: lobe.kind(),
                    transmitted,
                    eta: if transmitted && self.dielectric.is_some() {
                        eta
                    } else {
                        1.0
                    },
                    delta: None,
                })
            }
        }
    }

    /// Discrete probability of sampling the delta of lobe slot `lobe` (reflected or
    /// `transmitted`) from `wo`: p_lobe(wo) times the lobe's own choice probability.
    pub fn delta_pdf(&self, wo: Vec3, eta: f32, lobe: usize, transmitted: bool) -> f32 {
        let p = self.selection(wo, eta);
        self.lobes()[lobe].map_or(0.0, |l| p[lobe] * l.delta_prob(wo, eta, transmitted))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plain Lambert material selects its lobe the same way at every `wo` and computes that
    /// once, bit for bit what the lobes' weights give at each `wo`; a dielectric base, whose
    /// reflecting layer weighs more at grazing angles, computes it at each `wo`.
    #[test]
    fn constant_selection_is_the_selection_at_every_direction() {
        let lambert = Mixture::new(&BsdfParams {
            base_color: Vec3::new(0.8, 0.5, 0.2),
            metallic: 0.0,
            roughness: 1.0,
            specular: 0.0,
            ..BsdfParams::default()
        });
        let constant = lambert.constant_selection.expect("a plain Lambert lobe");
        for wo in [
            Vec3::Z,
            Vec3::new(0.3, 0.1, 0.9),
            Vec3::new(0.99, 0.0, 0.05),
        ] {
            let wo = wo.normalize();
            assert_eq!(lambert.selection_at(wo, 1.5), constant, "wo {wo}");
        }
        let layered = Mixture::new(&BsdfParams {
            metallic: 0.0,
            roughness: 0.5,
            ..BsdfParams::default()
        });
        assert!(layered.constant_selection.is_none());
        let (head_on, grazing) = (Vec3::Z, Vec3::new(0.99, 0.0, 0.05).normalize());
        assert_ne!(
            layered.selection(head_on, 1.5),
            layered.selection(grazing, 1.5)
        );
    }

    /// Only a lone plain Lambert lobe reports its f, and it is the f its evaluation gives.
    #[test]
    fn only_plain_lambert_reports_its_f() {
        let plain = BsdfParams {
            base_color: Vec3::new(0.8, 0.5, 0.2),
            metallic: 0.0,
            roughness: 1.0,
            specular: 0.0,
            ..BsdfParams::default()
        };
        let lambert = Mixture::new(&plain);
        let f = lambert.lambert().expect("a plain Lambert lobe");
        let (wo, wi) = (
            Vec3::new(0.3, 0.1, 0.9).normalize(),
            Vec3::new(-0.5, 0.2, 0.6),
        );
        let wi = wi.normalize();
        let selection = lambert.selection(wo, 1.5);
        let (f_cos, pdf) = lambert.eval(&selection, wo, wi, 1.5, TransportMode::Radiance);
        assert_eq!(f_cos, f * wi.z);
        assert_eq!(pdf, wi.z * std::f32::consts::FRAC_1_PI);
        let others = [
            BsdfParams {
                specular: 0.5,
                ..plain
            },
            BsdfParams {
                metallic: 1.0,
                ..plain
            },
            BsdfParams {
                transmission: 0.5,
                ..plain
            },
        ];
        for params in others {
            assert_eq!(Mixture::new(&params).lambert(), None, "{params:?}");
        }
    }
}
