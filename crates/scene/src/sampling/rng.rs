//! PCG32 random number generator (O'Neill 2014, "PCG: A Family of Simple Fast
//! Space-Efficient Statistically Good Algorithms for Random Number Generation"),
//! variant XSH-RR with 64-bit state and a selectable odd increment (the stream).

use super::Sampler;

/// LCG multiplier of PCG32.
const PCG_MULT: u64 = 6_364_136_223_846_793_005;

/// 2^-24: maps the top 24 bits of a `u32` onto [0, 1) exactly representable in `f32`.
const F32_FROM_24_BITS: f32 = 1.0 / 16_777_216.0;

/// Small-state PCG32 generator (16 bytes). Deterministic for a given seed and stream.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

/// splitmix64 finalizer (Steele et al. 2014): a bijective 64-bit mixer with good avalanche,
/// so keys differing in a single bit give unrelated outputs.
pub(super) fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Rng {
    /// Generator with the given `seed` (initial state) and `stream` (selects one of 2^63
    /// independent sequences); the standard PCG32 seeding procedure.
    pub fn new(seed: u64, stream: u64) -> Rng {
        let mut rng = Rng {
            state: 0,
            inc: (stream << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }

    /// Generator for a tuple key such as `(seed, iteration, pixel, sample)`.
    ///
    /// The key is hashed with splitmix64 (each element mixed, then folded into the running
    /// hash, so the order matters), and the hash derives both the seed and the stream:
    /// nearby keys give statistically independent sequences.
    #[inline]
    pub fn from_key(key: &[u64]) -> Rng {
        let h = hash_key(key);
        Rng::new(splitmix64(h), splitmix64(h ^ 0x1357_9BDF_2468_ACE0))
    }

    /// Next uniformly distributed 32-bit value.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }
}

impl Sampler for Rng {
    /// Multiples of 2^-24, so the largest value is 1 − 2^-24 and 1.0 is never returned.
    #[inline]
    fn uniform(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * F32_FROM_24_BITS
    }
}

/// Hash of a tuple key such as `(seed, iteration, pixel, sample)`: each element mixed with
/// splitmix64, then folded into the running hash, so the order matters.
pub(super) fn hash_key(key: &[u64]) -> u64 {
    // Digits of pi: an arbitrary non-zero start.
    key.iter()
        .fold(0x243F_6A88_85A3_08D3, |h, &k| splitmix64(h ^ splitmix64(k)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg32_reference_sequence() {
        // Reference output of the PCG32 demo (pcg32-global-demo, seed 42, stream 54).
        let mut rng = Rng::new(42, 54);
        let expected = [
            0xa15c_02b7_u32,
            0x7b47_f409,
            0xba1d_3330,
            0x83d2_f293,
            0xbfa4_784b,
            0xcbed_606e,
        ];
        for e in expected {
            assert_eq!(rng.next_u32(), e);
        }
    }

    #[test]
    fn uniform_stays_below_one() {
        assert!(((u32::MAX >> 8) as f32 * F32_FROM_24_BITS) < 1.0);
        let mut rng = Rng::new(7, 3);
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let u = rng.uniform();
            assert!((0.0..1.0).contains(&u));
            sum += u as f64;
        }
        // Mean of U[0,1): standard error 1/sqrt(12 n).
        let sigma = (1.0 / (12.0 * n as f64)).sqrt();
        assert!((sum / n as f64 - 0.5).abs() < 5.0 * sigma);
    }

    #[test]
    fn streams_and_keys_differ() {
        let seq = |mut rng: Rng| (0..8).map(|_| rng.next_u32()).collect::<Vec<_>>();
        assert_ne!(seq(Rng::new(1, 0)), seq(Rng::new(1, 1)));
        assert_ne!(seq(Rng::new(1, 0)), seq(Rng::new(2, 0)));
        assert_eq!(
            seq(Rng::from_key(&[1, 2, 3])),
            seq(Rng::from_key(&[1, 2, 3]))
        );
        assert_ne!(
            seq(Rng::from_key(&[1, 2, 3])),
            seq(Rng::from_key(&[1, 2, 4]))
        );
        assert_ne!(
            seq(Rng::from_key(&[1, 2, 3])),
            seq(Rng::from_key(&[3, 2, 1]))
        );
    }

    #[test]
    fn neighbouring_keys_are_uncorrelated() {
        // Pearson correlation of the first uniform of keys (0, 0, i) and (0, 0, i + 1).
        let n = 100_000u64;
        let first = |i: u64| Rng::from_key(&[0, 0, i]).uniform() as f64;
        let (mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for i in 0..n {
            let (x, y) = (first(i), first(i + 1));
            sx += x;
            sy += y;
            sxx += x * x;
            syy += y * y;
            sxy += x * y;
        }
        let nf = n as f64;
        let cov = sxy / nf - sx * sy / (nf * nf);
        let corr = cov / ((sxx / nf - (sx / nf).powi(2)) * (syy / nf - (sy / nf).powi(2))).sqrt();
        // Under independence the sample correlation has standard deviation ~ 1/sqrt(n).
        assert!(corr.abs() < 5.0 / nf.sqrt(), "correlation {corr}");
    }
}
