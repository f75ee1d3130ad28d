//! Fixed-seed Monte Carlo estimates with standard errors.

use crate::sampling::Rng;
use glam::{DVec3, Vec3};

/// Monte Carlo estimate of a mean, per RGB channel.
#[derive(Clone, Copy, Debug)]
pub struct Estimate {
    /// Sample mean.
    pub mean: DVec3,
    /// Standard error of the mean: sample standard deviation / √n.
    pub std_err: DVec3,
}

impl Estimate {
    /// Largest channel of `mean + k · std_err`: a one-sided upper confidence bound for
    /// `k` standard errors.
    pub fn upper_bound(&self, k: f64) -> f64 {
        (self.mean + k * self.std_err).max_element()
    }
}

/// Mean of `sample(rng)` over `n` calls with an [`Rng`] seeded by `seed`.
///
/// With `sample` returning f(ωo, ωi)·|cos θi| / pdf(ωi) for a sampled ωi (zero when
/// sampling fails) this is the directional albedo ∫ f |cos θi| dωi.
pub fn estimate_mean(n: usize, seed: u64, mut sample: impl FnMut(&mut Rng) -> Vec3) -> Estimate {
    let mut rng = Rng::new(seed, 0x0A1B);
    let (mut sum, mut sum_sq) = (DVec3::ZERO, DVec3::ZERO);
    for _ in 0..n {
        let x = sample(&mut rng).as_dvec3();
        sum += x;
        sum_sq += x * x;
    }
    let nf = n as f64;
    let mean = sum / nf;
    let variance = (sum_sq / nf - mean * mean).max(DVec3::ZERO) * (nf / (nf - 1.0).max(1.0));
    Estimate {
        mean,
        std_err: (variance / nf).map(f64::sqrt),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    #[test]
    fn estimates_uniform_mean() {
        let e = estimate_mean(100_000, 1, |rng| Vec3::splat(rng.uniform()));
        let sigma = (1.0f64 / 12.0 / 1e5).sqrt();
        assert!((e.std_err.x - sigma).abs() < 0.05 * sigma);
        assert!((e.mean.x - 0.5).abs() < 4.0 * e.std_err.x);
        assert!(e.upper_bound(4.0) > 0.5);
    }
}
