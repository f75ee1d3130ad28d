//! Piecewise-constant discrete distribution, e.g. for selecting lights proportionally to
//! their power.

/// Discrete distribution over `0..len()` with probabilities proportional to the weights.
///
/// The prefix sums are kept in `f64` so that millions of entries with widely varying
/// weights keep their relative probabilities.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    /// `cdf[i]` = sum of the weights before entry `i`; `cdf[len]` = total.
    cdf: Vec<f64>,
    /// Probability of each entry, (cdf[i + 1] − cdf[i]) / total, computed once.
    pmf: Vec<f32>,
}

impl Distribution1D {
    /// Builds the distribution. Negative and non-finite weights count as zero. Returns `None`
    /// when there is no entry or no positive finite weight.
    pub fn new(weights: &[f32]) -> Option<Distribution1D> {
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        let mut sum = 0.0f64;
        cdf.push(sum);
        for &w in weights {
            if w.is_finite() && w > 0.0 {
                sum += w as f64;
            }
            cdf.push(sum);
        }
        let pmf = cdf
            .windows(2)
            .map(|w| ((w[1] - w[0]) / sum) as f32)
            .collect();
        (sum > 0.0).then_some(Distribution1D { cdf, pmf })
    }

    /// Number of entries (including zero-weight ones).
    pub fn len(&self) -> usize {
        self.cdf.len() - 1
    }

    /// Always false: an empty distribution cannot be built.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sum of the (sanitized) weights.
    pub fn total(&self) -> f64 {
        self.cdf[self.len()]
    }

    /// Probability of selecting entry `i` (0 for zero weights and out-of-range indices).
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// Per entry, the smallest number in [0, 1) that [`sample`](Self::sample) maps to it or
    /// a later entry (infinity where none does): an entry is picked by the numbers from its
    /// own to the next entry's. For code that samples without f64 (the GPU), which then picks
    /// the last entry whose number is at most its own, as this f64 search does.
    pub fn first_numbers(&self) -> Vec<f32> {
        let total = self.total();
        // `find` picks entry ≥ i exactly where u · total reaches cdf[i].
        let reaches = |u: f32, i: usize| f64::from(u) * total >= self.cdf[i];
        (0..self.len())
            .map(|i| {
                let mut u = ((self.cdf[i] / total) as f32).clamp(0.0, 1.0);
                while u > 0.0 && reaches(u.next_down(), i) {
                    u = u.next_down();
                }
                while u < 1.0 && !reaches(u, i) {
                    u = u.next_up();
                }
                if u < 1.0 { u } else { f32::INFINITY }
            })
            .collect()
    }

    /// Selects an entry with `u` in [0, 1) (clamped into it) and returns it with its
    /// probability. An entry with zero weight is never selected: the result is the first
    /// entry whose cumulative sum exceeds `u · total`.
    #[inline]
    pub fn sample(&self, u: f32) -> (usize, f32) {
        let (i, _) = self.find(u);
        (i, self.pmf(i))
    }

    /// [`sample`](Self::sample), also returning where `u` fell within the entry's share, a
    /// fresh uniform number in [0, 1) (for choosing a point inside the entry).
    #[inline]
    pub fn sample_remapped(&self, u: f32) -> (usize, f32, f32) {
        let (i, target) = self.find(u);
        let (start, end) = (self.cdf[i], self.cdf[i + 1]);
        let remapped = if end > start {
            ((target - start) / (end - start)).max(0.0) as f32
        } else {
            0.0
        };
        (i, self.pmf(i), remapped.min(1.0 - f32::EPSILON / 2.0))
    }

    /// The entry `u` selects and the point `u · total` it selects it by.
    #[inline]
    fn find(&self, u: f32) -> (usize, f64) {
        let target = (u as f64).clamp(0.0, 1.0) * self.total();
        // First i with cdf[i + 1] > target; partition_point over cdf[1..].
        let i = self.cdf[1..].partition_point(|&c| c <= target);
        // target == total (u clamped to 1) would run past the end: use the last entry with
        // positive weight instead.
        let i = if i < self.len() {
            i
        } else {
            (0..self.len())
                .rev()
                .find(|&j| self.cdf[j + 1] > self.cdf[j])
                .unwrap_or(0)
        };
        (i, target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, Sampler};

    /// Picking the last entry whose first number is at most u is `sample`, for every u:
    /// weights with zeros inside and at both ends, tiny and huge ones.
    #[test]
    fn first_numbers_pick_what_sample_picks() {
        let mut rng = Rng::from_key(&[41]);
        let weights = [0.0, 3.0, 0.0, 0.0, 1e-6, 7.5, 1e6, 0.0, 2.0, 0.0];
        let d = Distribution1D::new(&weights).unwrap();
        let first = d.first_numbers();
        let picked = |u: f32| first.iter().rposition(|&f| f <= u).unwrap();
        let edges = first
            .iter()
            .filter(|f| f.is_finite())
            .flat_map(|&f| [f.next_down().max(0.0), f, f.next_up()]);
        let random = (0..100_000).map(|_| rng.uniform());
        for u in edges.chain(random).chain([0.0, 1.0f32.next_down()]) {
            assert_eq!(picked(u), d.sample(u).0, "u = {u:e}");
        }
    }

    #[test]
    fn rejects_empty_and_zero() {
        assert!(Distribution1D::new(&[]).is_none());
        assert!(Distribution1D::new(&[0.0, 0.0]).is_none());
        assert!(Distribution1D::new(&[f32::NAN, f32::INFINITY, -1.0]).is_none());
        let d = Distribution1D::new(&[0.0, f32::NAN, 2.0]).unwrap();
        assert_eq!(d.len(), 3);
        assert_eq!(d.total(), 2.0);
        assert_eq!(d.pmf(2), 1.0);
    }

    #[test]
    fn never_selects_zero_weight_entries() {
        let d = Distribution1D::new(&[0.0, 1.0, 0.0, 0.0, 3.0, 0.0]).unwrap();
        for u in [
            0.0,
            0.25 - 1e-7,
            0.25,
            0.5,
            1.0 - f32::EPSILON / 2.0,
            1.0,
            2.0,
            -1.0,
        ] {
            let (i, p) = d.sample(u);
            assert!(i == 1 || i == 4, "u = {u} selected {i}");
            assert_eq!(p, d.pmf(i));
        }
        assert_eq!(d.sample(0.0).0, 1);
        assert_eq!(d.sample(0.25).0, 4);
    }

    #[test]
    fn frequencies_match_pmf() {
        let weights = [0.5, 0.0, 3.0, 1e-3, 2.0, 7.0, 0.25];
        let d = Distribution1D::new(&weights).unwrap();
        let sum: f32 = (0..d.len()).map(|i| d.pmf(i)).sum();
        assert!((sum - 1.0).abs() < 1e-6);
        let n = 1_000_000;
        let mut counts = vec![0u32; d.len()];
        let mut rng = Rng::new(5, 1);
        for _ in 0..n {
            counts[d.sample(rng.uniform()).0] += 1;
        }
        for (i, &c) in counts.iter().enumerate() {
            let p = d.pmf(i) as f64;
            let sigma = (n as f64 * p * (1.0 - p)).sqrt();
            assert!(
                (c as f64 - n as f64 * p).abs() <= 5.0 * sigma + 1.0,
                "entry {i}: {c}"
            );
        }
    }
}
