//! World-space BSDF: sides, shading normals and the adjoint correction around the local
//! [`Mixture`].

use super::mixture::{Mixture, Selection};
use super::{BsdfEval, BsdfParams, BsdfSample, FlatLobes, LobeKind, Pdfs, TransportMode};
use crate::frame::Frame;
use glam::{Vec2, Vec3};

/// Cosines (with n_g or n_s) below this are treated as grazing: no scattering.
pub const GRAZING_COS: f32 = 1e-6;

/// The scattering function at one surface point (see the [module docs](super)).
#[derive(Clone, Debug)]
pub struct Bsdf {
    /// Shading frame, z = n_s (front orientation).
    frame: Frame,
    /// Geometric normal (front orientation).
    n_g: Vec3,
    double_sided: bool,
    /// IOR of the dielectric interface (relative IOR `ior` from the front, `1/ior` behind).
    ior: f32,
    mixture: Mixture,
}

/// The lobes of one set of [`BsdfParams`], before they are placed at a surface point: a
/// material whose parameters no texture changes builds them once and every hit on it
/// reuses them ([`Bsdf::from_lobes`]).
#[derive(Clone, Debug)]
pub struct Lobes(Mixture);

impl Lobes {
    /// The lobes of `params` (see the [module docs](super)).
    pub fn new(params: &BsdfParams) -> Lobes {
        Lobes(Mixture::new(params))
    }

    /// f (= albedo/π, RGB, sr⁻¹) where the lobes are one plain Lambert lobe: no reflecting
    /// layer above it, no conductor, no transmission. A [`Bsdf`] placed from such lobes
    /// evaluates f·|cos θi| with pdf |cos θi|/π for every consistent pair of directions on
    /// the same side, and samples the cosine-weighted hemisphere.
    pub fn lambert(&self) -> Option<Vec3> {
        self.0.lambert()
    }

    /// The lobes as plain numbers, for shading code outside this crate.
    pub fn flat(&self) -> FlatLobes {
        self.0.flat()
    }
}

/// Which side of the surface a direction is on, and what follows from it.
#[derive(Clone, Copy)]
struct Side {
    /// The direction is behind n_g: the local frame is mirrored (z → −z).
    back: bool,
    /// Relative IOR η(other side) / η(this side) of the refracting interface.
    eta: f32,
}

/// `wo` as the mixture sees it: its side, its local direction and the lobe selection there.
struct Outgoing {
    world: Vec3,
    side: Side,
    local: Vec3,
    selection: Selection,
}

/// A direction `wi` toward the next vertex that is consistent with an [`Outgoing`] (see
/// [`Bsdf::consistent`]), in the frame of that outgoing direction's side.
struct Incoming {
    world: Vec3,
    local: Vec3,
    /// |wi·n_g|.
    cos_g: f32,
}

/// A [`Bsdf`] with its outgoing direction `wo` fixed ([`Bsdf::fix_outgoing`]): evaluations
/// and samples that share `wo` find its side, local direction and lobe selection once.
pub struct FixedOutgoing<'a> {
    bsdf: &'a Bsdf,
    out: Outgoing,
}

impl Bsdf {
    /// BSDF of `params` at a point with geometric normal `n_g` (the front side, from the
    /// winding order) and shading normal `n_s` (interpolated or normal-mapped, flipped into
    /// n_g's hemisphere by the caller; it is flipped here too if it is not; a zero or
    /// non-finite n_s is replaced by n_g). Both unit.
    /// `double_sided`: a non-transmissive material also scatters from the back side (glTF
    /// `doubleSided`); materials with transmission always scatter from both sides.
    pub fn new(params: &BsdfParams, n_g: Vec3, n_s: Vec3, double_sided: bool) -> Bsdf {
        Bsdf::placed(Mixture::new(params), n_g, n_s, double_sided)
    }

    /// [`Bsdf::new`] with lobes built beforehand: the same BSDF as `Bsdf::new` with the
    /// parameters `lobes` was built from, without building them again.
    #[inline]
    pub fn from_lobes(lobes: &Lobes, n_g: Vec3, n_s: Vec3, double_sided: bool) -> Bsdf {
        Bsdf::placed(lobes.0.clone(), n_g, n_s, double_sided)
    }

    /// `mixture` placed at a surface point (see [`Bsdf::new`]).
    #[inline]
    fn placed(mixture: Mixture, n_g: Vec3, n_s: Vec3, double_sided: bool) -> Bsdf {
        let n_s = if !n_s.is_finite() || n_s.length_squared() < 0.25 {
            n_g
        } else if n_s.dot(n_g) < 0.0 {
            -n_s
        } else {
            n_s
        };
        Bsdf {
            frame: Frame::from_z(n_s),
            n_g,
            double_sided,
            ior: mixture.ior(),
            mixture,
        }
    }

    /// Side of `w`, or `None` when `w` is grazing/NaN, or behind a one-sided opaque material.
    #[inline]
    fn side(&self, w: Vec3) -> Option<Side> {
        let cos_g = w.dot(self.n_g);
        if cos_g.is_nan() || cos_g.abs() <= GRAZING_COS {
            return None;
        }
        let back = cos_g < 0.0;
        if back && !(self.double_sided || self.mixture.transmits()) {
            return None;
        }
        Some(Side {
            back,
            eta: if back { 1.0 / self.ior } else { self.ior },
        })
    }

    /// `w` in the shading frame of `side` (mirrored for the back side).
    #[inline]
    fn to_local(&self, side: Side, w: Vec3) -> Vec3 {
        let l = self.frame.to_local(w);
        if side.back {
            Vec3::new(l.x, l.y, -l.z)
        } else {
            l
        }
    }

    #[inline]
    fn to_world(&self, side: Side, l: Vec3) -> Vec3 {
        self.frame.to_world(if side.back {
            Vec3::new(l.x, l.y, -l.z)
        } else {
            l
        })
    }

    /// `wo` seen from the surface, if it is in the upper shading hemisphere of its side (not
    /// grazing) and the material scatters from that side.
    #[inline]
    fn outgoing(&self, wo: Vec3) -> Option<Outgoing> {
        let side = self.side(wo)?;
        let local = self.to_local(side, wo);
        (local.z >= GRAZING_COS).then(|| Outgoing {
            world: wo,
            side,
            local,
            selection: self.mixture.selection(local, side.eta),
        })
    }

    /// Whether (wo, wi_local) is a consistent pair: `wi` not grazing, and reflection vs
    /// transmission the same by n_g and by n_s. Returns |wi·n_g| when consistent.
    #[inline]
    fn consistent(&self, side: Side, wi: Vec3, wi_local: Vec3) -> Option<f32> {
        let cos_gi = if side.back {
            -wi.dot(self.n_g)
        } else {
            wi.dot(self.n_g)
        };
        let ok = cos_gi.abs() >= GRAZING_COS
            && wi_local.z.abs() >= GRAZING_COS
            && (cos_gi > 0.0) == (wi_local.z > 0.0);
        ok.then_some(cos_gi.abs())
    }

    /// Multiplies by Veach's shading-normal correction in importance mode (Veach 1997,
    /// §5.3): f·|wi·n_s| becomes f·|wo·n_s||wi·n_g| / |wo·n_g|.
    #[inline]
    fn adjoint(
        &self,
        f_cos: Vec3,
        mode: TransportMode,
        wo: Vec3,
        wo_local: Vec3,
        wi_local: Vec3,
        cos_gi: f32,
    ) -> Vec3 {
        match mode {
            TransportMode::Radiance => f_cos,
            TransportMode::Importance => {
                f_cos * (wo_local.z * cos_gi / (wo.dot(self.n_g).abs() * wi_local.z.abs()))
            }
        }
    }

    /// Value and pdfs of the non-delta lobes for the pair (`wo`, `wi`) (world, unit; `wo`
    /// toward the previous path vertex, `wi` toward the next). `f_cos` is f·|wi·n_s| in
    /// radiance mode and f·|wo·n_s||wi·n_g|/|wo·n_g| in importance mode; `pdf_fwd` is the
    /// solid-angle pdf of sampling `wi` from `wo`, `pdf_rev` that of `wo` from `wi`.
    /// All zero for delta-only materials, inconsistent or degenerate pairs.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> BsdfEval {
        self.eval_with(wo, wi, mode, Pdfs::Both)
    }

    /// [`Bsdf::eval`] with only the `pdfs` asked for.
    #[inline]
    pub fn eval_with(&self, wo: Vec3, wi: Vec3, mode: TransportMode, pdfs: Pdfs) -> BsdfEval {
        self.fix_outgoing(wo)
            .map_or_else(BsdfEval::default, |fixed| fixed.eval(wi, mode, pdfs))
    }

    /// The BSDF seen from `wo` (world, unit, toward the previous path vertex), for several
    /// evaluations or a sample from the same `wo`; `None` when nothing scatters toward `wo`
    /// (it is grazing, below the shading hemisphere, or on the black side of a one-sided
    /// material), where every evaluation would be zero and every sample `None`.
    #[inline]
    pub fn fix_outgoing(&self, wo: Vec3) -> Option<FixedOutgoing<'_>> {
        Some(FixedOutgoing {
            bsdf: self,
            out: self.outgoing(wo)?,
        })
    }

    /// `wi` in the shading frame of `out`'s side and |wi·n_g|, when (`out`, `wi`) is a
    /// consistent pair ([`Bsdf::consistent`]).
    #[inline]
    fn incoming(&self, out: &Outgoing, wi: Vec3) -> Option<(Vec3, f32)> {
        let wi_l = self.to_local(out.side, wi);
        Some((wi_l, self.consistent(out.side, wi, wi_l)?))
    }

    /// f_cos and the forward pdf of the pair (`out`, `wi`), if both are non-zero and finite,
    /// with the [`Incoming`] direction they were evaluated at.
    #[inline]
    fn eval_from(
        &self,
        out: &Outgoing,
        wi: Vec3,
        mode: TransportMode,
    ) -> Option<(Vec3, f32, Incoming)> {
        let (wi_l, cos_gi) = self.incoming(out, wi)?;
        let (f_cos, pdf) = self
            .mixture
            .eval(&out.selection, out.local, wi_l, out.side.eta, mode);
        let f_cos = self.adjoint(f_cos, mode, out.world, out.local, wi_l, cos_gi);
        let incoming = Incoming {
            world: wi,
            local: wi_l,
            cos_g: cos_gi,
        };
        (f_cos.is_finite() && pdf.is_finite() && pdf > 0.0).then_some((f_cos, pdf, incoming))
    }

    /// [`Bsdf::pdf`] from `wi` back to `out`'s direction, for a `wi` that [`Bsdf::eval_from`]
    /// accepted. A reflection stays on `out`'s side, so the side, its η and both local
    /// directions `Bsdf::pdf` would find again are already known (bit for bit the same: the
    /// same operations on the same inputs); a transmitted `wi` takes the general path.
    #[inline]
    fn reverse_pdf(&self, out: &Outgoing, wi: &Incoming) -> f32 {
        // `side` rejects |wi·n_g| ≤ GRAZING_COS, `consistent` only |wi·n_g| < GRAZING_COS.
        if !(wi.local.z > 0.0 && wi.cos_g > GRAZING_COS) {
            return self.pdf(wi.world, out.world);
        }
        let eta = out.side.eta;
        let selection = self.mixture.selection(wi.local, eta);
        self.mixture_pdf(&selection, wi.local, out.local, eta)
    }

    /// Samples `wi` given `wo` with `u_lobe` (lobe choice) and `u` (direction), both in
    /// [0, 1). `None` when nothing is scattered (black side, degenerate input, or a sampled
    /// direction that is below the surface or inconsistent between n_g and n_s).
    #[inline]
    pub fn sample(
        &self,
        wo: Vec3,
        u_lobe: f32,
        u: Vec2,
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        self.sample_with(wo, u_lobe, u, mode, Pdfs::Both)
    }

    /// [`Bsdf::sample`] with only the `pdfs` asked for.
    #[inline]
    pub fn sample_with(
        &self,
        wo: Vec3,
        u_lobe: f32,
        u: Vec2,
        mode: TransportMode,
        pdfs: Pdfs,
    ) -> Option<BsdfSample> {
        self.fix_outgoing(wo)?.sample(u_lobe, u, mode, pdfs)
    }

    /// Probability of sampling the same delta of lobe slot `lobe` back from `wi` to `wo`.
    fn delta_pdf_rev(&self, wo: Vec3, wi: Vec3, lobe: usize, transmitted: bool) -> f32 {
        let Some(side) = self.side(wi) else {
            return 0.0;
        };
        // The reverse sample starts at wi and must reach wo.
        let (wo_rev, wi_rev) = (self.to_local(side, wi), self.to_local(side, wo));
        if wo_rev.z < GRAZING_COS || wi_rev.z.abs() < GRAZING_COS {
            return 0.0;
        }
        self.mixture.delta_pdf(wo_rev, side.eta, lobe, transmitted)
    }

    /// Solid-angle pdf of sampling `wi` from `wo` (the `pdf_fwd` of [`Bsdf::eval`], without
    /// the reverse pdf); it does not depend on the transport mode.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.outgoing(wo)
            .and_then(|out| {
                let (wi_l, _) = self.incoming(&out, wi)?;
                Some(self.mixture_pdf(&out.selection, out.local, wi_l, out.side.eta))
            })
            .unwrap_or(0.0)
    }

    /// The mixture's pdf of local `wi` from local `wo` with lobe selection `selection`, or 0
    /// where it is not positive and finite.
    #[inline]
    fn mixture_pdf(&self, selection: &Selection, wo: Vec3, wi: Vec3, eta: f32) -> f32 {
        let pdf = self.mixture.pdf(selection, wo, wi, eta);
        if pdf.is_finite() && pdf > 0.0 {
            pdf
        } else {
            0.0
        }
    }

    /// The shading normal (front orientation): radiance-mode `f_cos` is f·|ωi·n_s|, so
    /// f alone (density estimation) is `f_cos / |ωi·n_s|`.
    #[inline]
    pub fn shading_normal(&self) -> Vec3 {
        self.frame.z
    }

    /// Whether every lobe is a Dirac delta (also true for a black material): no connection
    /// or merge is possible at this vertex.
    #[inline]
    pub fn is_delta(&self) -> bool {
        !self.mixture.has_non_delta()
    }

    /// Whether some lobe is not a delta (the negation of [`Bsdf::is_delta`]).
    #[inline]
    pub fn has_non_delta(&self) -> bool {
        self.mixture.has_non_delta()
    }

    /// Vertex class for integrators: [`LobeKind::Specular`] iff [`Bsdf::is_delta`];
    /// otherwise the most specular class among the non-delta lobes ([`LobeKind::Glossy`] if
    /// any rough GGX lobe exists, else [`LobeKind::Diffuse`]). Delta lobes of a mixed
    /// material (a smooth coat over diffuse) are ignored: connections use the rest.
    #[inline]
    pub fn classify(&self) -> LobeKind {
        self.mixture.classify()
    }
}

impl FixedOutgoing<'_> {
    /// The BSDF.
    #[inline]
    pub fn bsdf(&self) -> &Bsdf {
        self.bsdf
    }

    /// [`Bsdf::eval_with`] at the fixed `wo`.
    #[inline]
    pub fn eval(&self, wi: Vec3, mode: TransportMode, pdfs: Pdfs) -> BsdfEval {
        let Some((f_cos, pdf_fwd, incoming)) = self.bsdf.eval_from(&self.out, wi, mode) else {
            return BsdfEval::default();
        };
        BsdfEval {
            f_cos,
            pdf_fwd,
            pdf_rev: match pdfs {
                Pdfs::Forward => 0.0,
                Pdfs::Both => self.bsdf.reverse_pdf(&self.out, &incoming),
            },
        }
    }

    /// [`Bsdf::sample_with`] at the fixed `wo`.
    #[inline]
    pub fn sample(
        &self,
        u_lobe: f32,
        u: Vec2,
        mode: TransportMode,
        pdfs: Pdfs,
    ) -> Option<BsdfSample> {
        let (bsdf, out) = (self.bsdf, &self.out);
        let (side, wo, wo_l) = (out.side, out.world, out.local);
        let s = bsdf
            .mixture
            .sample(&out.selection, wo_l, side.eta, u_lobe, u, mode)?;
        let wi = bsdf.to_world(side, s.wi).normalize();
        let reverse = pdfs == Pdfs::Both;
        let (f_cos, pdf_fwd, pdf_rev) = match s.delta {
            Some(delta) => {
                let cos_gi = bsdf.consistent(side, wi, s.wi)?;
                let f_cos = bsdf.adjoint(delta.f_cos, mode, wo, wo_l, s.wi, cos_gi);
                let pdf_rev = if reverse {
                    bsdf.delta_pdf_rev(wo, wi, delta.lobe, s.transmitted)
                } else {
                    0.0
                };
                (f_cos, delta.prob, pdf_rev)
            }
            // Evaluated at the final world direction, so that the sample agrees with eval().
            None => {
                let (f_cos, pdf_fwd, incoming) = bsdf.eval_from(out, wi, mode)?;
                let pdf_rev = if reverse {
                    bsdf.reverse_pdf(out, &incoming)
                } else {
                    0.0
                };
                (f_cos, pdf_fwd, pdf_rev)
            }
        };
        let transmitted = wi.dot(bsdf.n_g) * wo.dot(bsdf.n_g) < 0.0;
        let valid = f_cos.is_finite() && pdf_fwd.is_finite() && pdf_fwd > 0.0 && wi.is_finite();
        (valid && transmitted == s.transmitted).then_some(BsdfSample {
            wi,
            f_cos,
            pdf_fwd,
            pdf_rev,
            lobe: s.kind,
            transmitted,
            eta: s.eta,
        })
    }
}
