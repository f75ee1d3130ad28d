//! Pearson chi-square test of a direction sampler against its pdf.

use super::integrate::integrate_cell;
use crate::frame::Frame;
use crate::sampling::Rng;
use glam::Vec3;
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::f64::consts::PI;

/// Parameters of [`chi2_test`].
#[derive(Clone, Debug)]
pub struct Chi2Config {
    /// Bins are (cos θ, φ) cells in this frame (put its z on the surface normal so that the
    /// hemisphere boundary falls on a bin boundary).
    pub frame: Frame,
    /// Number of bins in cos θ over [-1, 1] (even, so cos θ = 0 is a bin boundary).
    pub cos_theta_bins: usize,
    /// Number of bins in φ over [0, 2π).
    pub phi_bins: usize,
    /// Number of calls of the sampler.
    pub sample_count: usize,
    /// Cells (and the "no direction" category) with a smaller expected count are pooled.
    pub min_expected: f64,
    /// Family-wise significance level; corrected per test by [`sidak_significance`].
    pub significance: f64,
    /// Seed of the [`Rng`] passed to the sampler.
    pub seed: u64,
}

impl Default for Chi2Config {
    /// 24 × 48 cells, 10⁶ samples, pooling below 5, significance 0.01, frame around +z.
    fn default() -> Chi2Config {
        Chi2Config {
            frame: Frame::from_z(Vec3::Z),
            cos_theta_bins: 24,
            phi_bins: 48,
            sample_count: 1_000_000,
            min_expected: 5.0,
            significance: 0.01,
            seed: 0x5EED,
        }
    }
}

/// Outcome of [`chi2_test`].
#[derive(Clone, Debug)]
pub struct Chi2Result {
    /// Whether the sampler is consistent with the pdf at the corrected significance level.
    pub passed: bool,
    /// Pearson statistic Σ (observed − expected)² / expected over the pooled categories.
    pub statistic: f64,
    /// Degrees of freedom (categories − 1).
    pub dof: usize,
    /// Probability of a statistic at least this large under the null hypothesis.
    pub p_value: f64,
    /// Šidák-corrected significance level the p-value was compared with.
    pub corrected_significance: f64,
    /// ∫ pdf dω over the sphere (the probability of a non-delta direction).
    pub pdf_integral: f64,
    /// Fraction of sampler calls that returned no direction (delta lobe or failure).
    pub no_direction_fraction: f64,
    /// Explanation of a failure, with the worst cells.
    pub message: String,
}

/// Per-test significance so that `num_tests` independent tests together reject a correct
/// sampler with probability `significance` (Šidák correction): 1 − (1 − α)^(1/n).
pub fn sidak_significance(significance: f64, num_tests: usize) -> f64 {
    1.0 - (1.0 - significance).powf(1.0 / num_tests.max(1) as f64)
}

/// One category of the test: a cell (row, column) or the "no direction" outcome.
struct Category {
    observed: f64,
    expected: f64,
    label: String,
}

/// Chi-square goodness-of-fit test of `sample_fn` against `pdf_fn`.
///
/// `sample_fn` is called `sample_count` times with a fixed-seed [`Rng`] and returns a unit
/// world direction, or `None` when it produced no non-delta direction (a delta lobe was
/// selected, or the sample was rejected). `pdf_fn` is the solid-angle density of the
/// returned directions per sampler call, so its integral over the sphere is the probability
/// of a non-delta direction: for a BSDF with delta lobes this is the mixture pdf that sums
/// the non-delta lobes only. The "no direction" outcome is an extra category with expected
/// probability 1 − ∫ pdf, which checks the delta-selection probability too.
///
/// Expected counts are integrated numerically per cell ([`integrate_cell`]); cells with an
/// expected count below `min_expected` are pooled; a cell with zero expectation but some
/// observations fails outright. `num_tests` is the number of chi-square tests in the family
/// (for the Šidák correction).
pub fn chi2_test(
    mut sample_fn: impl FnMut(&mut Rng) -> Option<Vec3>,
    pdf_fn: impl Fn(Vec3) -> f64,
    config: &Chi2Config,
    num_tests: usize,
) -> Chi2Result {
    let (rows, cols) = (config.cos_theta_bins, config.phi_bins);
    let n = config.sample_count as f64;
    let mut observed = vec![0u64; rows * cols];
    let mut no_direction = 0u64;
    let mut rng = Rng::new(config.seed, 0);
    for _ in 0..config.sample_count {
        match sample_fn(&mut rng) {
            Some(w) if w.is_finite() => {
                let l = config.frame.to_local(w);
                let c = (l.z as f64).clamp(-1.0, 1.0);
                let phi = (l.y as f64).atan2(l.x as f64).rem_euclid(2.0 * PI);
                let row = (((c + 1.0) * 0.5 * rows as f64) as usize).min(rows - 1);
                let col = ((phi / (2.0 * PI) * cols as f64) as usize).min(cols - 1);
                observed[row * cols + col] += 1;
            }
            Some(_) => {
                return failure(config, num_tests, "sampler returned a non-finite direction");
            }
            None => no_direction += 1,
        }
    }

    // Absolute tolerance per cell: 1e-4 of an expected count.
    let abs_tol = 1e-4 / n;
    let mut categories = Vec::with_capacity(rows * cols + 1);
    let mut pdf_integral = 0.0;
    for row in 0..rows {
        let c = (
            -1.0 + 2.0 * row as f64 / rows as f64,
            -1.0 + 2.0 * (row + 1) as f64 / rows as f64,
        );
        for col in 0..cols {
            let phi = (
                2.0 * PI * col as f64 / cols as f64,
                2.0 * PI * (col + 1) as f64 / cols as f64,
            );
            let integral = integrate_cell(&config.frame, &pdf_fn, c, phi, abs_tol);
            if !(integral.is_finite() && integral >= 0.0) {
                return failure(
                    config,
                    num_tests,
                    &format!("pdf integral {integral} in cell ({row}, {col})"),
                );
            }
            pdf_integral += integral;
            categories.push(Category {
                observed: observed[row * cols + col] as f64,
                expected: n * integral,
                label: format!(
                    "cell cosθ∈[{:.3},{:.3}] φ∈[{:.3},{:.3}]",
                    c.0, c.1, phi.0, phi.1
                ),
            });
        }
    }
    categories.push(Category {
        observed: no_direction as f64,
        expected: n * (1.0 - pdf_integral).max(0.0),
        label: "no direction (delta or rejected)".to_string(),
    });

    if let Some(bad) = categories
        .iter()
        .find(|c| c.expected == 0.0 && c.observed > 0.0)
    {
        return failure(
            config,
            num_tests,
            &format!(
                "{}: {} samples where the pdf integrates to 0",
                bad.label, bad.observed
            ),
        );
    }
    let pooled = pool(categories, config.min_expected);
    let statistic: f64 = pooled
        .iter()
        .map(|c| (c.observed - c.expected).powi(2) / c.expected)
        .sum();
    let dof = pooled.len().saturating_sub(1).max(1);
    let p_value = ChiSquared::new(dof as f64)
        .map(|d| d.sf(statistic))
        .unwrap_or(0.0);
    let corrected_significance = sidak_significance(config.significance, num_tests);
    let passed = p_value >= corrected_significance;
    let message = if passed {
        String::new()
    } else {
        worst_cells(&pooled)
    };
    Chi2Result {
        passed,
        statistic,
        dof,
        p_value,
        corrected_significance,
        pdf_integral,
        no_direction_fraction: no_direction as f64 / n,
        message,
    }
}

/// Merges all categories with an expected count below `min_expected` into one (together
/// with the next smallest ones until the pool itself reaches `min_expected`).
fn pool(mut categories: Vec<Category>, min_expected: f64) -> Vec<Category> {
    categories.sort_by(|a, b| a.expected.total_cmp(&b.expected));
    let mut pooled = Category {
        observed: 0.0,
        expected: 0.0,
        label: "pooled".to_string(),
    };
    let mut pool_size = 0;
    let mut kept = Vec::with_capacity(categories.len());
    for c in categories {
        if c.expected < min_expected || (pool_size > 0 && pooled.expected < min_expected) {
            pooled.observed += c.observed;
            pooled.expected += c.expected;
            pool_size += 1;
        } else {
            kept.push(c);
        }
    }
    if pooled.expected > 0.0 {
        pooled.label = format!("pool of {pool_size} categories");
        kept.push(pooled);
    }
    kept
}

fn worst_cells(categories: &[Category]) -> String {
    let mut order: Vec<&Category> = categories.iter().collect();
    let contrib = |c: &Category| (c.observed - c.expected).powi(2) / c.expected;
    order.sort_by(|a, b| contrib(b).total_cmp(&contrib(a)));
    order
        .iter()
        .take(5)
        .map(|c| {
            format!(
                "{}: observed {} expected {:.1}",
                c.label, c.observed, c.expected
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

fn failure(config: &Chi2Config, num_tests: usize, message: &str) -> Chi2Result {
    Chi2Result {
        passed: false,
        statistic: f64::INFINITY,
        dof: 0,
        p_value: 0.0,
        corrected_significance: sidak_significance(config.significance, num_tests),
        pdf_integral: f64::NAN,
        no_direction_fraction: f64::NAN,
        message: message.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{
        Sampler, cosine_hemisphere_pdf, sample_cosine_hemisphere, uniform_sphere_pdf,
    };

    #[test]
    fn detects_a_wrong_pdf() {
        // Cosine-weighted samples tested against the uniform hemisphere pdf must fail.
        let config = Chi2Config {
            sample_count: 200_000,
            ..Chi2Config::default()
        };
        let wrong = |w: Vec3| {
            if w.z > 0.0 {
                2.0 * uniform_sphere_pdf() as f64
            } else {
                0.0
            }
        };
        let result = chi2_test(
            |rng| Some(sample_cosine_hemisphere(rng.uniform2())),
            wrong,
            &config,
            1,
        );
        assert!(!result.passed, "{result:?}");
    }

    #[test]
    fn accounts_for_missing_directions() {
        // Half of the calls produce no direction: the pdf must integrate to 1/2.
        let config = Chi2Config {
            sample_count: 200_000,
            ..Chi2Config::default()
        };
        let sampler = |rng: &mut Rng| {
            let (u_lobe, u) = (rng.uniform(), rng.uniform2());
            (u_lobe < 0.5).then(|| sample_cosine_hemisphere(u))
        };
        let half = |w: Vec3| 0.5 * cosine_hemisphere_pdf(w.z) as f64;
        let result = chi2_test(sampler, half, &config, 2);
        assert!(result.passed, "{result:?}");
        assert!((result.pdf_integral - 0.5).abs() < 1e-6);
        // Claiming the full pdf while dropping half of the samples must fail.
        let full = |w: Vec3| cosine_hemisphere_pdf(w.z) as f64;
        assert!(!chi2_test(sampler, full, &config, 2).passed);
    }
}
