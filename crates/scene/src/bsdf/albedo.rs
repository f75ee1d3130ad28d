//! Directional albedo of a Schlick-Fresnel GGX reflection lobe, for the energy-conserving
//! diffuse base (Kelemen & Szirmay-Kalos 2001; Kulla & Conty 2017).
//!
//! With Schlick's F = F0 (1 − w) + F90 w, w = (1 − ωo·m)^5, the directional albedo of the
//! single-scattering GGX lobe is linear in F0 and F90:
//!
//! E(μ) = ∫ F D G2 / (4 μ μi) μi dωi = F0 A(μ, α) + F90 B(μ, α),
//!
//! A(μ, α) = ∫ (1 − w) D G2 / (4 μ) dωi,  B(μ, α) = ∫ w D G2 / (4 μ) dωi,
//!
//! and so is its cosine-weighted average E_avg = 2 ∫₀¹ E(μ) μ dμ = F0 A_avg(α) + F90 B_avg(α).
//!
//! A and B are tabulated once, lazily and deterministically (a rank-1 lattice rule over the
//! visible normals; 64 × 48 entries, about 1 s of CPU spread over the available threads), on
//! a grid over s = √μ ∈ [0, 1] (μ = cos θo) and r = √α ∈ [√MIN_ALPHA, 1], both denser
//! where the albedo changes fastest, and looked up bilinearly in (s, r). The interpolation
//! error is below `TABLE_TOLERANCE` = 2e-3 (asserted by a test against a converged
//! integration). The averages are the exact averages of the bilinear interpolant, so 2 ∫ (1 − E(μ)) μ dμ = 1 − E_avg holds exactly for the looked-up
//! E: the compensated diffuse lobe then has albedo exactly base·(1 − E(μo)).
//! A mirror (roughness 0, no GGX lobe) has the analytic E:
//! E(μ) = F0 + (F90 − F0)(1 − μ)^5, E_avg = F0 · 20/21 + F90 / 21.

use super::fresnel::{reflect, schlick, schlick_weight};
use super::microfacet::Ggx;
use super::{FlatAlbedo, MIN_ALPHA};
use glam::{Vec2, Vec3};
use std::sync::OnceLock;

/// Grid nodes in s = √μ (at μ = (j / (MU_RES − 1))²: dense at grazing angles, where the
/// albedo of smooth-ish lobes changes on the scale μ ~ α).
const MU_RES: usize = 64;
/// Grid nodes in r = √α over [√MIN_ALPHA, 1], at r = r_min + (1 − r_min)(k / (R_RES − 1))²:
/// dense at small roughness, where the grazing-angle albedo changes fastest.
const R_RES: usize = 48;
/// Cosine used for the μ = 0 node (the grazing limit).
const MU_GRAZING: f32 = 1e-5;
/// Integration points per table entry (a Fibonacci number: rank-1 Fibonacci lattice).
const LATTICE_N: usize = 4181;
/// Generator of the Fibonacci lattice (the preceding Fibonacci number).
const LATTICE_G: usize = 2584;

struct Tables {
    /// `a[k][j]` = A(μ_j, α_k), `b` likewise.
    a: [[f32; MU_RES]; R_RES],
    b: [[f32; MU_RES]; R_RES],
    /// Exact 2 ∫ A μ dμ of row k's interpolant (piecewise linear in √μ); `b_avg` likewise.
    a_avg: [f32; R_RES],
    b_avg: [f32; R_RES],
}

fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(build_tables)
}

fn node(i: usize, res: usize) -> f32 {
    i as f32 / (res - 1) as f32
}

/// A and B at one (μ, α) by quasi-Monte Carlo over a Fibonacci lattice, importance sampling
/// visible normals: for reflected ωi the estimator of D G2 / (4 μ) is G2 / G1 (Heitz 2018).
fn integrate_entry(mu: f32, alpha: f32, n: usize, g: usize) -> (f32, f32) {
    let ggx = Ggx { alpha };
    let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
    let (mut a, mut b) = (0.0f64, 0.0f64);
    for i in 0..n {
        let u = Vec2::new(
            (i as f32 + 0.5) / n as f32,
            (((i * g) % n) as f32 + 0.5) / n as f32,
        );
        let Some(m) = ggx.sample_visible(wo, u) else {
            continue;
        };
        let wi = reflect(wo, m);
        if wi.z <= 0.0 {
            continue;
        }
        let weight = (ggx.g2(wo, wi) / ggx.g1(wo)) as f64;
        let w = schlick_weight(wo.dot(m)) as f64;
        a += weight * (1.0 - w);
        b += weight * w;
    }
    ((a / n as f64) as f32, (b / n as f64) as f32)
}

/// 2 ∫₀¹ y(μ) μ dμ = 4 ∫₀¹ y(s) s³ ds of the interpolant of `row`, piecewise linear in s = √μ.
fn cosine_weighted_average(row: &[f32; MU_RES]) -> f32 {
    let mut sum = 0.0f64;
    for j in 0..MU_RES - 1 {
        let (a, b) = (node(j, MU_RES) as f64, node(j + 1, MU_RES) as f64);
        let (ya, yb) = (row[j] as f64, row[j + 1] as f64);
        let slope = (yb - ya) / (b - a);
        // ∫_a^b (ya + slope (s − a)) 4 s³ ds
        let (a4, b4) = (a.powi(4), b.powi(4));
        sum += ya * (b4 - a4) + slope * (0.8 * (b.powi(5) - a.powi(5)) - a * (b4 - a4));
    }
    sum as f32
}

/// Row `k` of the tables: (A, B) at every μ node.
fn build_row(k: usize) -> ([f32; MU_RES], [f32; MU_RES]) {
    let r = r_of_node(node(k, R_RES));
    let (mut a, mut b) = ([0.0; MU_RES], [0.0; MU_RES]);
    for j in 0..MU_RES {
        let mu = node(j, MU_RES).powi(2).max(MU_GRAZING);
        (a[j], b[j]) = integrate_entry(mu, r * r, LATTICE_N, LATTICE_G);
    }
    (a, b)
}

/// Builds all rows, spread over the available threads (the result does not depend on it).
fn build_tables() -> Tables {
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(R_RES);
    let rows: Vec<_> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                scope.spawn(move || {
                    (t..R_RES)
                        .step_by(threads)
                        .map(|k| (k, build_row(k)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("albedo table thread panicked"))
            .collect()
    });
    let mut t = Tables {
        a: [[0.0; MU_RES]; R_RES],
        b: [[0.0; MU_RES]; R_RES],
        a_avg: [0.0; R_RES],
        b_avg: [0.0; R_RES],
    };
    for (k, (a, b)) in rows {
        (t.a[k], t.b[k]) = (a, b);
        t.a_avg[k] = cosine_weighted_average(&a);
        t.b_avg[k] = cosine_weighted_average(&b);
    }
    t
}

/// r = √α of the table coordinate `x` ∈ [0, 1].
fn r_of_node(x: f32) -> f32 {
    let r_min = MIN_ALPHA.sqrt();
    r_min + (1.0 - r_min) * x * x
}

/// Table coordinate of α (inverse of [`r_of_node`]).
fn node_of_alpha(alpha: f32) -> f32 {
    let r_min = MIN_ALPHA.sqrt();
    ((alpha.sqrt() - r_min) / (1.0 - r_min)).max(0.0).sqrt()
}

/// Interpolation position of `x` in [0, 1] on `res` nodes: (lower index, fraction).
fn locate(x: f32, res: usize) -> (usize, f32) {
    let s = x.clamp(0.0, 1.0) * (res - 1) as f32;
    let i = (s as usize).min(res - 2);
    (i, s - i as f32)
}

fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// Albedo of one Schlick-Fresnel GGX lobe (fixed F0, F90 and α), with the roughness
/// interpolation resolved once at construction.
#[derive(Clone, Copy, Debug)]
pub(super) struct SpecularAlbedo {
    f0: Vec3,
    f90: Vec3,
    /// Lower table row and interpolation fraction in α; `None` for a mirror.
    row: Option<(usize, f32)>,
}

/// Entries of the albedo tables in μ (columns, over √μ) and in roughness (rows).
pub const ALBEDO_TABLE_SIZE: (usize, usize) = (MU_RES, R_RES);

/// The tabulated Schlick GGX albedo, for shading code outside this crate.
pub struct AlbedoTables {
    /// A(μ, α), `[row][column]`: rows over the roughness, columns over √μ.
    pub a: &'static [[f32; MU_RES]; R_RES],
    /// B(μ, α), laid out like `a`.
    pub b: &'static [[f32; MU_RES]; R_RES],
    /// The cosine-weighted average of each row of A.
    pub a_average: &'static [f32; R_RES],
    /// The cosine-weighted average of each row of B.
    pub b_average: &'static [f32; R_RES],
}

/// The albedo tables (computed on first use).
pub fn albedo_tables() -> AlbedoTables {
    let t = tables();
    AlbedoTables {
        a: &t.a,
        b: &t.b,
        a_average: &t.a_avg,
        b_average: &t.b_avg,
    }
}

impl SpecularAlbedo {
    /// The albedo as plain numbers.
    pub fn flat(&self) -> FlatAlbedo {
        FlatAlbedo {
            f0: self.f0,
            f90: self.f90,
            row: self.row,
        }
    }

    /// Lobe with Schlick (F0, F90) and the distribution `ggx` (`None`: a mirror).
    pub fn new(f0: Vec3, f90: Vec3, ggx: Option<Ggx>) -> SpecularAlbedo {
        // A layer that reflects nothing (F0 = F90 = 0, e.g. specularFactor 0) has E = 0 at any
        // roughness: the closed form below gives that without touching (or building) the tables.
        let mut albedo = SpecularAlbedo { f0, f90, row: None };
        if let Some(Ggx { alpha }) = ggx.filter(|_| albedo.reflects()) {
            albedo.row = Some(locate(node_of_alpha(alpha), R_RES));
        }
        albedo
    }

    /// Whether the lobe reflects anything (E is zero everywhere when it does not).
    pub fn reflects(&self) -> bool {
        self.f0.max(self.f90).max_element() > 0.0
    }

    /// Directional albedo E(μ) per RGB channel, for μ = cos θo.
    pub fn directional(&self, mu: f32) -> Vec3 {
        let Some((k, tk)) = self.row else {
            return schlick(self.f0, self.f90, mu);
        };
        let t = tables();
        let (j, tj) = locate(mu.max(0.0).sqrt(), MU_RES);
        let bilinear = |table: &[[f32; MU_RES]; R_RES]| {
            lerp(
                lerp(table[k][j], table[k][j + 1], tj),
                lerp(table[k + 1][j], table[k + 1][j + 1], tj),
                tk,
            )
        };
        self.f0 * bilinear(&t.a) + self.f90 * bilinear(&t.b)
    }

    /// Cosine-weighted average E_avg = 2 ∫₀¹ E(μ) μ dμ of [`SpecularAlbedo::directional`].
    pub fn average(&self) -> Vec3 {
        let Some((k, tk)) = self.row else {
            return self.f0 * (20.0 / 21.0) + self.f90 / 21.0;
        };
        let t = tables();
        self.f0 * lerp(t.a_avg[k], t.a_avg[k + 1], tk)
            + self.f90 * lerp(t.b_avg[k], t.b_avg[k + 1], tk)
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// Documented bound on |E_table − E_exact| (interpolation plus integration error),
    /// asserted by `table_matches_converged_integration` and used as a tolerance by the
    /// energy tests of the diffuse base.
    pub const TABLE_TOLERANCE: f32 = 2e-3;

    /// Converged reference for (A, B): the estimator of the tables with 75025 lattice points
    /// (18× more; successive Fibonacci sizes agree to ~1e-5). The estimator itself is
    /// checked independently by the BSDF albedo tests (sampling + evaluation).
    fn reference(mu: f32, alpha: f32) -> (f32, f32) {
        integrate_entry(mu, alpha, 75025, 46368)
    }

    #[test]
    fn table_matches_converged_integration() {
        // Off-grid points (between nodes in both μ and √α), including grazing angles.
        let mut worst = 0.0f32;
        for &r in &[0.013f32, 0.02, 0.04, 0.1, 0.23, 0.37, 0.55, 0.78, 0.95] {
            for &mu in &[0.02f32, 0.05, 0.11, 0.3, 0.52, 0.77, 0.99] {
                let alpha = r * r;
                let (a, b) = reference(mu, alpha);
                let e_a = SpecularAlbedo::new(Vec3::ONE, Vec3::ZERO, Some(Ggx { alpha }))
                    .directional(mu)
                    .x;
                let e_b = SpecularAlbedo::new(Vec3::ZERO, Vec3::ONE, Some(Ggx { alpha }))
                    .directional(mu)
                    .x;
                worst = worst.max((e_a - a).abs()).max((e_b - b).abs());
            }
        }
        assert!(worst <= TABLE_TOLERANCE, "worst table error {worst}");
    }

    #[test]
    fn smooth_limit_is_analytic() {
        let (f0, f90) = (Vec3::splat(0.04), Vec3::ONE);
        assert_eq!(
            SpecularAlbedo::new(f0, f90, None).directional(0.3),
            schlick(f0, f90, 0.3)
        );
        // 2 ∫ (1 − μ)^5 μ dμ = 1/21.
        let avg = SpecularAlbedo::new(Vec3::ZERO, Vec3::ONE, None).average().x;
        assert!((avg - 1.0 / 21.0).abs() < 1e-7);
    }

    #[test]
    fn averages_match_rows() {
        // The tabulated averages are the cosine-weighted means of the interpolated rows.
        for alpha in [2e-4f32, 0.002, 0.05, 0.3, 1.0] {
            let lobe = SpecularAlbedo::new(Vec3::ONE, Vec3::splat(0.5), Some(Ggx { alpha }));
            let n = 20_000;
            let mean: f64 = (0..n)
                .map(|i| {
                    let mu = (i as f32 + 0.5) / n as f32;
                    2.0 * (mu * lobe.directional(mu).x) as f64
                })
                .sum::<f64>()
                / n as f64;
            let avg = lobe.average().x as f64;
            assert!((mean - avg).abs() < 1e-5, "alpha {alpha}: {mean} vs {avg}");
        }
    }

    #[test]
    fn albedo_is_at_most_one() {
        for k in 0..R_RES {
            for j in 0..MU_RES {
                let t = tables();
                assert!(t.a[k][j] + t.b[k][j] <= 1.0 + 1e-4 && t.b[k][j] >= 0.0);
            }
        }
    }
}
