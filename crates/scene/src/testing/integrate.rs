//! Adaptive numerical integration over (cos θ, φ) cells of the sphere.
//!
//! In the coordinates (c = cos θ, φ) the solid-angle measure is dω = dc dφ, so a cell
//! integral is a plain 2-D integral. It is computed by nested adaptive Simpson quadrature
//! (inner over c, outer over φ), each starting from a few panels so that narrow peaks
//! (near-specular lobes) are not skipped, with an absolute-or-relative error criterion that
//! tolerates the `f32` noise of the integrand.

use crate::frame::Frame;
use glam::Vec3;
use std::f64::consts::PI;

/// Panels each 1-D integral starts with before adapting.
const MIN_PANELS: usize = 8;
/// Maximum recursion depth of each 1-D adaptive Simpson integral.
const MAX_DEPTH: u32 = 12;
/// Relative tolerance (with respect to the local integral); above the relative noise of
/// integrands evaluated in `f32` at directions computed in `f32`.
const REL_TOL: f64 = 1e-6;

/// World direction with cos θ = `cos_theta` and azimuth `phi` in `frame`.
pub fn spherical_direction(frame: &Frame, cos_theta: f64, phi: f64) -> Vec3 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let local = Vec3::new(
        (sin_theta * phi.cos()) as f32,
        (sin_theta * phi.sin()) as f32,
        cos_theta as f32,
    );
    frame.to_world(local)
}

struct Panel {
    a: f64,
    b: f64,
    fa: f64,
    fm: f64,
    fb: f64,
}

fn simpson(p: &Panel) -> f64 {
    (p.b - p.a) / 6.0 * (p.fa + 4.0 * p.fm + p.fb)
}

fn adapt(f: &mut impl FnMut(f64) -> f64, p: Panel, whole: f64, abs_tol: f64, depth: u32) -> f64 {
    let m = 0.5 * (p.a + p.b);
    let (flm, frm) = (f(0.5 * (p.a + m)), f(0.5 * (m + p.b)));
    let left = Panel {
        a: p.a,
        b: m,
        fa: p.fa,
        fm: flm,
        fb: p.fm,
    };
    let right = Panel {
        a: m,
        b: p.b,
        fa: p.fm,
        fm: frm,
        fb: p.fb,
    };
    let (sl, sr) = (simpson(&left), simpson(&right));
    let delta = sl + sr - whole;
    // Richardson criterion of adaptive Simpson: error of the refined estimate ≈ delta / 15.
    if depth == 0 || delta.abs() <= 15.0 * abs_tol.max(REL_TOL * (sl + sr).abs()) {
        return sl + sr + delta / 15.0;
    }
    adapt(f, left, sl, 0.5 * abs_tol, depth - 1) + adapt(f, right, sr, 0.5 * abs_tol, depth - 1)
}

/// ∫_a^b f by adaptive Simpson quadrature with absolute tolerance `abs_tol`.
fn integrate_1d(mut f: impl FnMut(f64) -> f64, a: f64, b: f64, abs_tol: f64) -> f64 {
    let h = (b - a) / MIN_PANELS as f64;
    let mut fa = f(a);
    let mut total = 0.0;
    for i in 0..MIN_PANELS {
        let pa = a + i as f64 * h;
        let pb = if i + 1 == MIN_PANELS { b } else { pa + h };
        let (fm, fb) = (f(0.5 * (pa + pb)), f(pb));
        let panel = Panel {
            a: pa,
            b: pb,
            fa,
            fm,
            fb,
        };
        let whole = simpson(&panel);
        total += adapt(&mut f, panel, whole, abs_tol / MIN_PANELS as f64, MAX_DEPTH);
        fa = fb;
    }
    total
}

/// ∫ f dω over the cell cos θ ∈ [c0, c1], φ ∈ [phi0, phi1] of `frame`, with absolute
/// tolerance `abs_tol` (in the units of f · sr).
pub fn integrate_cell(
    frame: &Frame,
    f: &impl Fn(Vec3) -> f64,
    (c0, c1): (f64, f64),
    (phi0, phi1): (f64, f64),
    abs_tol: f64,
) -> f64 {
    let inner_tol = abs_tol / (phi1 - phi0);
    integrate_1d(
        |phi| integrate_1d(|c| f(spherical_direction(frame, c, phi)), c0, c1, inner_tol),
        phi0,
        phi1,
        abs_tol,
    )
}

/// ∫ f dω over the whole sphere (as a sum of 8 × 16 cells of `frame`).
pub fn integrate_sphere(frame: &Frame, f: impl Fn(Vec3) -> f64) -> f64 {
    let (rows, cols) = (8, 16);
    let mut total = 0.0;
    for i in 0..rows {
        let c = (
            -1.0 + 2.0 * i as f64 / rows as f64,
            -1.0 + 2.0 * (i + 1) as f64 / rows as f64,
        );
        for j in 0..cols {
            let phi = (
                2.0 * PI * j as f64 / cols as f64,
                2.0 * PI * (j + 1) as f64 / cols as f64,
            );
            total += integrate_cell(frame, &f, c, phi, 1e-10);
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_known_functions() {
        let frame = Frame::from_z(Vec3::new(0.0, 0.6, 0.8));
        assert!((integrate_sphere(&frame, |_| 1.0) - 4.0 * PI).abs() < 1e-6);
        // ∫ max(0, cos θ) dω = π, around an axis that is not the frame's.
        let n = Vec3::new(1.0, 0.0, 0.0);
        let v = integrate_sphere(&frame, |w| w.dot(n).max(0.0) as f64);
        assert!((v - PI).abs() < 1e-5, "{v}");
        // A sharp peak: normalized exponential lobe exp(k (cos θ − 1)) k / (2π (1 − e^{-2k})),
        // with 1 − cos θ computed as sin²θ / (1 + cos θ) to avoid f32 cancellation.
        let k = 1e4;
        let lobe = |w: Vec3| {
            let l = frame.to_local(w).as_dvec3();
            let one_minus_cos = (l.x * l.x + l.y * l.y) / (1.0 + l.z);
            (-k * one_minus_cos).exp() * k / (2.0 * PI * (1.0 - (-2.0 * k).exp()))
        };
        let v = integrate_sphere(&frame, lobe);
        assert!((v - 1.0).abs() < 1e-4, "{v}");
    }
}
