//! Warps from [0,1)² to common domains, with their pdfs.
//!
//! Direction pdfs are with respect to solid angle (1/sr); disk and triangle warps are
//! uniform with respect to area.

use crate::real::Real;
use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4, PI};

/// Uniform point on the unit disk by Shirley & Chiu's concentric mapping (1997), which keeps
/// strata compact (low distortion). Pdf 1/π per unit area.
///
/// Written without branches on which coordinate dominates (a coin flip for random input):
/// the angle within the dominant axis's quadrant, φ = π/4 · minor / major, always lies in
/// [−π/4, π/4], and the half where y dominates, at angle π/2 − φ, takes sin φ and cos φ
/// swapped.
#[inline]
pub fn sample_concentric_disk(u: Vec2) -> Vec2 {
    let p = 2.0 * u - Vec2::ONE;
    if p.x == 0.0 && p.y == 0.0 {
        return Vec2::ZERO;
    }
    let x_major = p.x.abs() > p.y.abs();
    let (major, minor) = if x_major { (p.x, p.y) } else { (p.y, p.x) };
    let (sin, cos) = sin_cos_octant(FRAC_PI_4 * (minor / major));
    let (x, y) = if x_major { (cos, sin) } else { (sin, cos) };
    major * Vec2::new(x, y)
}

/// sin x and cos x for |x| ≤ π/4, the angles of one octant, by polynomials that the same
/// code evaluates on one number or on SIMD lanes ([`Real`]), so that a warp computed for
/// several samples at once gives each the numbers it gives alone. The coefficients are the
/// minimax fits of Moshier's Cephes `sinf` and `cosf` kernels on that interval: both within
/// 6·10⁻⁸ of the exact values (half an ulp of 1; tested against `f64`).
#[inline(always)]
pub fn sin_cos_octant<T: Real>(x: T) -> (T, T) {
    let c = T::splat;
    let z = x * x;
    let sin = ((c(-1.951_529_6e-4) * z + c(8.332_161e-3)) * z + c(-1.666_665_5e-1)) * z * x + x;
    let cos = ((c(2.443_315_7e-5) * z + c(-1.388_731_6e-3)) * z + c(4.166_664_6e-2)) * z * z
        - c(0.5) * z
        + c(1.0);
    (sin, cos)
}

/// Cosine-weighted direction on the hemisphere around +z (Malley's method: a concentric-disk
/// sample lifted onto the hemisphere). Pdf: [`cosine_hemisphere_pdf`].
#[inline]
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Solid-angle pdf of [`sample_cosine_hemisphere`]: cos θ / π (0 below the horizon).
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Uniform direction on the unit sphere. Pdf: [`uniform_sphere_pdf`].
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Solid-angle pdf of [`sample_uniform_sphere`]: 1/(4π).
pub fn uniform_sphere_pdf() -> f32 {
    0.25 * FRAC_1_PI
}

/// Uniform direction inside the cone around +z with half-angle θmax, given `cos_max` =
/// cos θmax (in [-1, 1]). Pdf: [`uniform_cone_pdf`].
pub fn sample_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_theta = (1.0 - u.x) + u.x * cos_max;
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

/// Solid-angle pdf of [`sample_uniform_cone`]: 1 / (2π (1 − cos θmax)). Infinite for a
/// degenerate cone (cos θmax = 1), which is then effectively a delta direction.
pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// Uniform point on a triangle as barycentrics (b0, b1, b2), summing to 1, by the
/// area-preserving square-root parameterization (Shirley 1992):
/// b0 = 1 − √u₀, b1 = u₁ √u₀. Pdf 1/area.
#[inline]
pub fn sample_uniform_triangle(u: Vec2) -> Vec3 {
    let su = u.x.sqrt();
    let b0 = 1.0 - su;
    let b1 = u.y * su;
    Vec3::new(b0, b1, 1.0 - b0 - b1)
}

/// Veach's power heuristic (β = 2) for `nf` samples from a technique with pdf `f_pdf`
/// combined with `ng` samples from one with pdf `g_pdf`: (nf·f)² / ((nf·f)² + (ng·g)²).
/// Returns 1 when `f_pdf` is infinite (delta) and 0 when both pdfs are zero.
/// Written once for one weight and for SIMD lanes ([`Real`]).
#[inline(always)]
pub fn power_heuristic<T: Real>(nf: f32, f_pdf: T, ng: f32, g_pdf: T) -> T {
    let f = T::splat(nf) * f_pdf;
    let g = T::splat(ng) * g_pdf;
    let (f2, g2) = (f * f, g * g);
    let sum = f2 + g2;
    let weight = T::select(sum.gt(T::splat(0.0)), f2 / sum, T::splat(0.0));
    T::select(f.is_infinite(), T::splat(1.0), weight)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Frame;
    use crate::sampling::{Rng, Sampler};
    use crate::testing::{Chi2Config, chi2_test, integrate_sphere};

    fn chi2_direction_warp(sample: impl Fn(Vec2) -> Vec3, pdf: impl Fn(Vec3) -> f64) {
        let config = Chi2Config {
            frame: Frame::from_z(Vec3::Z),
            ..Chi2Config::default()
        };
        let result = chi2_test(
            |rng: &mut Rng| Some(sample(rng.uniform2())),
            &pdf,
            &config,
            3,
        );
        assert!(result.passed, "{result:?}");
    }

    #[test]
    fn cosine_hemisphere_matches_pdf() {
        let pdf = |w: Vec3| cosine_hemisphere_pdf(w.z) as f64;
        assert!((integrate_sphere(&Frame::from_z(Vec3::Z), pdf) - 1.0).abs() < 1e-6);
        chi2_direction_warp(sample_cosine_hemisphere, pdf);
    }

    #[test]
    fn uniform_sphere_matches_pdf() {
        let pdf = |_: Vec3| uniform_sphere_pdf() as f64;
        assert!((integrate_sphere(&Frame::from_z(Vec3::Z), pdf) - 1.0).abs() < 1e-6);
        chi2_direction_warp(sample_uniform_sphere, pdf);
    }

    #[test]
    fn uniform_cone_matches_pdf() {
        let cos_max = 0.3f32;
        let pdf = |w: Vec3| {
            if w.z >= cos_max {
                uniform_cone_pdf(cos_max) as f64
            } else {
                0.0
            }
        };
        assert!((integrate_sphere(&Frame::from_z(Vec3::Z), pdf) - 1.0).abs() < 1e-5);
        chi2_direction_warp(|u| sample_uniform_cone(u, cos_max), pdf);
    }

    /// Counts of uniform points in a k×k grid over the square [-1,1]² restricted to cells
    /// fully inside the shape `inside`; returns the chi-square statistic and the cell count.
    fn grid_chi2(
        points: &[Vec2],
        inside: impl Fn(Vec2) -> bool,
        cell_area_pdf: f64,
    ) -> (f64, usize) {
        const K: usize = 16;
        let mut counts = [[0u32; K]; K];
        for p in points {
            let i = (((p.x + 1.0) * 0.5 * K as f32) as usize).min(K - 1);
            let j = (((p.y + 1.0) * 0.5 * K as f32) as usize).min(K - 1);
            counts[i][j] += 1;
        }
        let h = 2.0 / K as f32;
        let (mut stat, mut cells) = (0.0, 0);
        for (i, row) in counts.iter().enumerate() {
            for (j, &c) in row.iter().enumerate() {
                let lo = Vec2::new(-1.0 + i as f32 * h, -1.0 + j as f32 * h);
                let corners = [lo, lo + Vec2::X * h, lo + Vec2::Y * h, lo + Vec2::splat(h)];
                if corners.iter().all(|&c| inside(c)) {
                    let expected = points.len() as f64 * cell_area_pdf * (h * h) as f64;
                    stat += (c as f64 - expected).powi(2) / expected;
                    cells += 1;
                }
            }
        }
        (stat, cells)
    }

    fn assert_chi2_ok(stat: f64, cells: usize) {
        use statrs::distribution::{ChiSquared, ContinuousCDF};
        // Cells are a subset of a multinomial: statistic ~ chi2 with `cells` dof (approx.).
        let p = ChiSquared::new(cells as f64).unwrap().sf(stat);
        assert!(p > 1e-3, "chi2 {stat} with {cells} cells, p = {p}");
    }

    #[test]
    fn concentric_disk_is_uniform() {
        let mut rng = Rng::new(11, 0);
        let pts: Vec<Vec2> = (0..200_000)
            .map(|_| sample_concentric_disk(rng.uniform2()))
            .collect();
        assert!(pts.iter().all(|p| p.length() <= 1.0 + 1e-6));
        let (stat, cells) = grid_chi2(&pts, |p| p.length() <= 1.0, 1.0 / std::f64::consts::PI);
        assert_chi2_ok(stat, cells);
    }

    #[test]
    fn octant_sine_and_cosine_are_within_half_an_ulp_of_one() {
        let steps = 100_000;
        let (mut sin_err, mut cos_err) = (0.0f64, 0.0f64);
        for i in 0..=steps {
            let x = (i as f32 / steps as f32 * 2.0 - 1.0) * FRAC_PI_4;
            let (sin, cos) = sin_cos_octant(x);
            sin_err = sin_err.max((f64::from(sin) - f64::from(x).sin()).abs());
            cos_err = cos_err.max((f64::from(cos) - f64::from(x).cos()).abs());
        }
        assert!(sin_err < 6e-8 && cos_err < 6e-8, "{sin_err:e} {cos_err:e}");
    }

    #[test]
    fn triangle_barycentrics_are_uniform() {
        // Map barycentrics onto the triangle (-1,-1), (1,-1), (-1,1) of area 2.
        let (a, b, c) = (
            Vec2::new(-1.0, -1.0),
            Vec2::new(1.0, -1.0),
            Vec2::new(-1.0, 1.0),
        );
        let mut rng = Rng::new(12, 0);
        let pts: Vec<Vec2> = (0..200_000)
            .map(|_| {
                let bary = sample_uniform_triangle(rng.uniform2());
                assert!(bary.min_element() >= 0.0 && (bary.element_sum() - 1.0).abs() < 1e-6);
                bary.x * a + bary.y * b + bary.z * c
            })
            .collect();
        let (stat, cells) = grid_chi2(&pts, |p| p.x + p.y <= 0.0, 0.5);
        assert_chi2_ok(stat, cells);
    }

    #[test]
    fn power_heuristic_limits() {
        assert_eq!(power_heuristic(1.0, 0.0, 1.0, 0.0), 0.0);
        assert_eq!(power_heuristic(1.0, f32::INFINITY, 1.0, 3.0), 1.0);
        assert!((power_heuristic(1.0, 2.0, 1.0, 2.0) - 0.5).abs() < 1e-7);
        let w = power_heuristic(1.0, 1.0, 2.0, 1.5);
        assert!((w + power_heuristic(2.0, 1.5, 1.0, 1.0) - 1.0).abs() < 1e-6);
    }
}
