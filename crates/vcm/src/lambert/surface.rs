//! A plain Lambert surface point in lanes: `SurfaceHit::new`, `Bsdf::from_lobes`,
//! `Bsdf::fix_outgoing`, `FixedOutgoing::eval` and `FixedOutgoing::sample` for eight
//! vertices at once, operation for operation.

use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};

use glam::Vec3;
use vcm_scene::Scene;
use vcm_scene::bsdf::{GRAZING_COS, TransportMode};
use vcm_scene::sampling::sin_cos_octant;

use super::LambertLanes;
use crate::lanes::{F32s, LANES, Mask, Vec3s};
use crate::ray_offset::{gamma, offset_ray_origins};

/// The triangles, barycentrics and materials of eight Lambert vertices.
#[derive(Default)]
pub(crate) struct SurfaceInputs {
    corners: [Vec3s; 3],
    normals: [Vec3s; 3],
    /// Barycentrics of the hit's second and third corners.
    u: F32s,
    v: F32s,
    /// f = albedo/π.
    pub f: Vec3s,
    double_sided: [bool; LANES],
}

impl SurfaceInputs {
    /// Reads lane `lane`'s point at barycentrics (`u`, `v`) of `triangle`, whose material
    /// is plain Lambert.
    #[inline(always)]
    pub fn gather(
        &mut self,
        tables: &LambertLanes,
        scene: &Scene,
        lane: usize,
        (triangle, u, v): (u32, f32, f32),
    ) {
        let mesh = &scene.mesh;
        for (c, &vertex) in mesh.triangles[triangle as usize].iter().enumerate() {
            self.corners[c].set(lane, mesh.positions[vertex as usize]);
            self.normals[c].set(lane, mesh.normals[vertex as usize]);
        }
        (self.u.0[lane], self.v.0[lane]) = (u, v);
        let material = tables
            .material_of(scene, triangle)
            .expect("a plain Lambert material");
        self.f.set(lane, material.f);
        self.double_sided[lane] = material.double_sided;
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

/// Eight Lambert vertices as their BSDFs see them from the previous path vertex.
pub(crate) struct Vertex {
    /// The surface point.
    pub position: Vec3s,
    /// Error bound of `position` (the same on every axis).
    error: Vec3s,
    /// Geometric normal (front orientation).
    pub n_g: Vec3s,
    frame: Frame,
    /// f = albedo/π of each lane's Lambert lobe.
    f: Vec3s,
    /// The direction toward the previous vertex (unit).
    pub wo: Vec3s,
    /// `wo · n_g`.
    cos_g_out: F32s,
    /// `wo` in the shading frame of its side: its z.
    wo_z: F32s,
    /// `wo` is behind n_g: the local frame is mirrored.
    back: Mask,
    /// Lanes where the BSDF scatters toward `wo` (`fix_outgoing` gives a value).
    pub alive: Mask,
}

/// A Lambert evaluation of a direction: `f_cos` and the pdfs, in the lanes where it is
/// valid (`Bsdf::eval_from`; elsewhere `FixedOutgoing::eval` gives zeros).
pub(crate) struct Evaluation {
    /// f·|cos| with the convention of the transport mode.
    pub f_cos: Vec3s,
    /// Pdf of the direction.
    pub pdf: F32s,
    /// Pdf of the reverse direction (where asked for, else zero).
    pub pdf_rev: F32s,
    /// Lanes whose pair of directions the BSDF scatters.
    pub valid: Mask,
}

/// A sampled continuation (`FixedOutgoing::sample` of the Lambert lobe).
pub(crate) struct Scattered {
    /// The sampled direction (world, unit).
    pub wi: Vec3s,
    /// Its evaluation.
    pub eval: Evaluation,
    /// Lanes where the sample is valid.
    pub valid: Mask,
}

impl Vertex {
    /// The surface points of `surface` seen from `wo` (unit, toward the previous vertex), in
    /// the `active` lanes: `SurfaceHit::new`, `Bsdf::from_lobes` and `Bsdf::fix_outgoing`.
    #[inline(always)]
    pub fn new(surface: &SurfaceInputs, wo: Vec3s, active: Mask) -> Vertex {
        let zero = F32s::splat(0.0);
        let grazing = F32s::splat(GRAZING_COS);
        let (u, v) = (surface.u, surface.v);
        let w = F32s::splat(1.0) - u - v;
        let [c0, c1, c2] = surface.corners;
        let (b0, b1, b2) = (c0.scale(w), c1.scale(u), c2.scale(v));
        let position = b0 + b1 + b2;
        let bound = (b0.abs() + b1.abs() + b2.abs()).max_element() * F32s::splat(gamma(7));
        let n_g = (c1 - c0)
            .cross(c2 - c0)
            .normalize_or(Vec3s::splat(Vec3::ZERO));
        // Mesh::surface_point: the interpolated normal, turned to n_g's side.
        let [n0, n1, n2] = surface.normals;
        let shading = (n0.scale(w) + n1.scale(u) + n2.scale(v)).normalize_or(n_g);
        let shading = shading.dot(n_g).lt(zero).select3(-shading, shading);
        // Bsdf::placed: an unusable shading normal gives way to n_g.
        let usable = shading.is_finite() & !shading.length_squared().lt(F32s::splat(0.25));
        let flipped = shading.dot(n_g).lt(zero).select3(-shading, shading);
        let n_s = usable.select3(flipped, n_g);
        let frame = Frame::from_z(n_s);
        // Bsdf::outgoing: the side of wo and wo in that side's frame.
        let cos_g_out = wo.dot(n_g);
        let back = cos_g_out.lt(zero);
        let seen = !cos_g_out.is_nan() & !cos_g_out.abs().le(grazing);
        let scatters = !back | Mask::from_bools(surface.double_sided);
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
            f: surface.f,
            wo,
            cos_g_out,
            wo_z,
            back,
            alive: active & seen & scatters & wo_z.ge(grazing),
        }
    }

    /// |cos| between `w` (unit) and the geometric normal (`SurfaceHit::cos_geometric`).
    #[inline(always)]
    pub fn cos_geometric(&self, w: Vec3s) -> F32s {
        self.n_g.dot(w).abs()
    }

    /// |cos| between `wo` and the geometric normal.
    #[inline(always)]
    pub fn cos_geometric_out(&self) -> F32s {
        self.cos_geometric(self.wo)
    }

    /// Origin of a ray leaving the surface in direction `w` (`SurfaceHit::spawn`).
    #[inline(always)]
    pub fn spawn(&self, w: Vec3s) -> Vec3s {
        offset_ray_origins(self.position, self.error, self.n_g, w)
    }

    /// `FixedOutgoing::eval` toward `wi` (world, unit) in `mode`, with the reverse pdf where
    /// `reverse` (`Pdfs::Both`).
    #[inline(always)]
    pub fn eval(&self, wi: Vec3s, mode: TransportMode, reverse: bool) -> Evaluation {
        let zero = F32s::splat(0.0);
        let grazing = F32s::splat(GRAZING_COS);
        // Bsdf::incoming and Bsdf::consistent.
        let wi_z = mirror(self.back, self.frame.to_local(wi).z);
        let cos_g = wi.dot(self.n_g);
        let cos_g = self.back.select(-cos_g, cos_g);
        let same_side = !(cos_g.gt(zero) ^ wi_z.gt(zero));
        let consistent = cos_g.abs().ge(grazing) & wi_z.abs().ge(grazing) & same_side;
        let cos_g = cos_g.abs();
        // The lobe's value and pdf, then Bsdf::adjoint.
        let f_cos = self.f.scale(wi_z);
        let f_cos = match mode {
            TransportMode::Radiance => f_cos,
            TransportMode::Importance => {
                f_cos.scale(self.wo_z * cos_g / (self.cos_g_out.abs() * wi_z.abs()))
            }
        };
        let pdf = wi_z * F32s::splat(FRAC_1_PI);
        let finite = f_cos.is_finite() & pdf.is_finite() & pdf.gt(zero);
        // Bsdf::reverse_pdf: wo's cosine pdf seen from wi, zero where wi is grazing by n_g.
        let pdf_rev = if reverse {
            let reflected = wi_z.gt(zero) & cos_g.gt(grazing);
            reflected.select(self.wo_z * F32s::splat(FRAC_1_PI), zero)
        } else {
            zero
        };
        Evaluation {
            f_cos,
            pdf,
            pdf_rev,
            valid: consistent & wi_z.gt(zero) & finite,
        }
    }

    /// `FixedOutgoing::sample` of the Lambert lobe with the direction numbers (`ux`, `uy`):
    /// the cosine-weighted hemisphere of `wo`'s side, evaluated at the final direction.
    #[inline(always)]
    pub fn sample(&self, (ux, uy): (F32s, F32s), mode: TransportMode, reverse: bool) -> Scattered {
        let zero = F32s::splat(0.0);
        let (dx, dy) = concentric_disk(ux, uy);
        let dz = (F32s::splat(1.0) - (dx * dx + dy * dy)).max(zero).sqrt();
        let local = Vec3s {
            x: dx,
            y: dy,
            z: mirror(self.back, dz),
        };
        let wi = self.frame.to_world(local).normalize();
        let eval = self.eval(wi, mode, reverse);
        let transmitted = (wi.dot(self.n_g) * self.cos_g_out).lt(zero);
        Scattered {
            valid: self.alive & dz.gt(zero) & eval.valid & !transmitted & wi.is_finite(),
            wi,
            eval,
        }
    }
}

/// `l` with its sign flipped in the `back` lanes (`Bsdf::to_local` / `to_world` mirroring
/// the frame for the back side).
#[inline(always)]
fn mirror(back: Mask, l: F32s) -> F32s {
    back.select(-l, l)
}

/// `sample_concentric_disk` in each lane.
#[inline(always)]
fn concentric_disk(ux: F32s, uy: F32s) -> (F32s, F32s) {
    let (two, one, zero) = (F32s::splat(2.0), F32s::splat(1.0), F32s::splat(0.0));
    let (px, py) = (two * ux - one, two * uy - one);
    let x_major = px.abs().gt(py.abs());
    let (major, minor) = (x_major.select(px, py), x_major.select(py, px));
    let (sin, cos) = sin_cos_octant(F32s::splat(FRAC_PI_4) * (minor / major));
    let (x, y) = (x_major.select(cos, sin), x_major.select(sin, cos));
    let center = px.eq(zero) & py.eq(zero);
    (
        center.select(zero, major * x),
        center.select(zero, major * y),
    )
}
