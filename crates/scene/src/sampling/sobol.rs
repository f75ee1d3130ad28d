//! Owen-scrambled, shuffled Sobol points (Burley 2020, "Practical Hash-based Owen
//! Scrambling", JCGT 9(4)), padded in pairs of dimensions.
//!
//! Sample `i` of a pixel is point `i` of that pixel's own randomized sequence: the first two
//! Sobol dimensions (van der Corput and the binary Pascal matrix, a (0, 2)-sequence),
//! index-shuffled and Owen-scrambled by a seed hashed from the pixel's key and the pair's
//! number. Within one pair of dimensions the samples of a pixel are stratified (every
//! aligned power-of-two run of them is a (0, m, 2)-net); different pairs, pixels and keys are
//! independent randomizations. Each number is uniform on [0, 1) for every sample, so
//! estimators stay unbiased; only their error shrinks.
//!
//! The values are those of the `sobol_burley` crate's `sample(i, d, seed)` for d = 0, 1 (the
//! tests check it bit for bit), computed without its table walk: dimension 1 is the
//! superset-XOR transform of the index bits, five shift-and-mask steps. Like that crate, a
//! sequence holds 2^16 points; later samples start independently randomized blocks.

use super::rng::{hash_key, splitmix64};
use super::{Rng, Sampler};
use glam::Vec2;

/// Samples of one sequence before the next block starts.
const BLOCK_BITS: u32 = 16;

/// Pairs of dimensions [`SobolSampler::prefetch`] computes ahead: enough for one path vertex
/// of every integrator here.
pub const PREFETCH_PAIRS: usize = 6;

/// Samplers [`SobolSampler::prefetch`] computes together: eight 32-bit lanes fill one AVX2
/// register.
const LANES: usize = 8;

/// The numbers of one sample of a pixel (or of any other keyed sequence).
#[derive(Clone, Debug)]
pub struct SobolSampler {
    /// Hash of the key and of the sample's block of 2^16 samples.
    seed: u32,
    /// Index of the sample within its block, bit-reversed.
    index_rev: u32,
    /// Next unused pair of dimensions.
    pair: u32,
    /// First pair after those reserved for the current step ([`start_step`](Self::start_step)).
    step_end: u32,
    /// Pairs computed ahead by [`prefetch`](Self::prefetch) (none until it runs).
    ahead: PairsAhead,
}

/// Pairs `first .. first + len` of a sampler, computed before they are drawn.
#[derive(Clone, Debug, Default)]
struct PairsAhead {
    first: u32,
    len: u32,
    values: [Vec2; PREFETCH_PAIRS],
}

impl SobolSampler {
    /// Sample `index` of the sequence keyed by `key` (e.g. `(seed, pixel)`); samples of one
    /// key with consecutive indices are stratified against each other.
    #[inline]
    pub fn new(key: &[u64], index: u64) -> SobolSampler {
        let block = index >> BLOCK_BITS;
        let seed = splitmix64(hash_key(key) ^ splitmix64(block));
        SobolSampler {
            seed: (seed ^ (seed >> 32)) as u32,
            index_rev: ((index & ((1 << BLOCK_BITS) - 1)) as u32).reverse_bits(),
            pair: 0,
            step_end: 0,
            ahead: PairsAhead::default(),
        }
    }

    /// Moves on to the first pair of dimensions reserved for step `step` of a path (`pairs`
    /// each), unless earlier steps used more: paths of one pixel that take the same number of
    /// numbers at each step then draw step k's numbers from the same stratified pairs.
    #[inline]
    pub fn start_step(&mut self, step: u32, pairs: u32) {
        self.pair = self.pair.max(step.saturating_mul(pairs));
        self.step_end = step.saturating_add(1).saturating_mul(pairs);
    }

    /// A random stream of its own in place of the next pair of dimensions, for numbers that
    /// gain nothing from stratification or need more bits (e.g. uniform integer picks).
    #[inline]
    pub fn stream(&mut self) -> Rng {
        let rng = self.next_stream();
        self.pair += 1;
        rng
    }

    /// The stream the next [`stream`](Self::stream) call returns, without moving on: for
    /// work that can start before the numbers are drawn (e.g. fetching what they will pick).
    #[inline]
    pub fn next_stream(&self) -> Rng {
        Rng::from_key(&[
            u64::from(self.seed),
            u64::from(self.index_rev),
            u64::from(self.pair),
        ])
    }

    /// Computes the pairs of dimensions each of `samplers` has left in its current step
    /// before they are drawn, eight samplers at a time in SIMD lanes where the target has
    /// them (at least one pair and at most six; the eight share the longest
    /// count). Draws from those pairs then return them without computing: the same numbers,
    /// which depend only on the sample and the pair.
    pub fn prefetch<'a>(samplers: impl IntoIterator<Item = &'a mut SobolSampler>) {
        let mut group: [Option<&mut SobolSampler>; LANES] = Default::default();
        let mut filled = 0;
        for sampler in samplers {
            group[filled] = Some(sampler);
            filled += 1;
            if filled == LANES {
                prefetch_lanes(&mut group);
                filled = 0;
            }
        }
        if filled > 0 {
            prefetch_lanes(&mut group[..filled]);
        }
    }

    /// Pairs `offsets[k]` after the next of each of `samplers`, as `[k][dimension][lane]`,
    /// computed together in SIMD lanes: the values each sampler's
    /// [`uniform2`](Sampler::uniform2) would return at those draws ([`uniform`](Sampler::uniform)
    /// takes the first number of a pair), without drawing them. For code that shades
    /// several paths at once and then says how many numbers each used ([`skip`](Self::skip)).
    #[inline(always)]
    pub fn peek_lanes<const N: usize, const L: usize>(
        samplers: [&SobolSampler; L],
        offsets: [u32; N],
    ) -> [[[f32; L]; 2]; N] {
        let seed = samplers.map(|s| s.seed);
        let index_rev = samplers.map(|s| s.index_rev);
        let first = samplers.map(|s| s.pair);
        let mut values = [[[0.0f32; L]; 2]; N];
        for ([x, y], offset) in values.iter_mut().zip(offsets) {
            for lane in 0..L {
                let pair = first[lane].wrapping_add(offset);
                (x[lane], y[lane]) = pair_numbers(index_rev[lane], pair_seed(seed[lane], pair));
            }
        }
        values
    }

    /// Moves past the next `pairs` pairs of dimensions, as that many draws would.
    #[inline(always)]
    pub fn skip(&mut self, pairs: u32) {
        self.pair += pairs;
    }

    /// The next pair of dimensions if it was computed ahead, moving on past it.
    #[inline(always)]
    fn next_pair_ahead(&mut self) -> Option<Vec2> {
        let ahead = &self.ahead;
        let k = self.pair.wrapping_sub(ahead.first);
        if k >= ahead.len {
            return None;
        }
        let value = ahead.values[k as usize];
        self.pair += 1;
        Some(value)
    }

    /// The seed of the next pair of dimensions of this sample.
    #[inline]
    fn next_pair_seed(&mut self) -> u32 {
        let seed = pair_seed(self.seed, self.pair);
        self.pair += 1;
        seed
    }
}

/// Fills the samplers of `group` (at most [`LANES`]) with their next pairs, lane by lane in
/// loops the compiler vectorizes.
fn prefetch_lanes(group: &mut [Option<&mut SobolSampler>]) {
    let (mut seed, mut index_rev, mut first) = ([0u32; LANES], [0u32; LANES], [0u32; LANES]);
    let mut len = 1;
    for (lane, sampler) in group.iter().enumerate() {
        if let Some(sampler) = sampler {
            (seed[lane], index_rev[lane], first[lane]) =
                (sampler.seed, sampler.index_rev, sampler.pair);
            len = len.max(sampler.step_end.saturating_sub(sampler.pair) as usize);
        }
    }
    let len = len.min(PREFETCH_PAIRS);
    let values: [[[f32; LANES]; 2]; PREFETCH_PAIRS] = pairs_in_lanes(seed, index_rev, first, len);
    for (lane, slot) in group.iter_mut().enumerate() {
        if let Some(sampler) = slot.take() {
            sampler.ahead = PairsAhead {
                first: first[lane],
                len: len as u32,
                values: std::array::from_fn(|k| Vec2::new(values[k][0][lane], values[k][1][lane])),
            };
        }
    }
}

/// Pairs `first[lane] .. first[lane] + len` (`len` ≤ `N`; the rest left zero) of the samples
/// with seeds `seed` and reversed indices `index_rev`, as `[pair][dimension][lane]`, lane
/// by lane in loops the compiler vectorizes.
#[inline(always)]
fn pairs_in_lanes<const N: usize, const L: usize>(
    seed: [u32; L],
    index_rev: [u32; L],
    first: [u32; L],
    len: usize,
) -> [[[f32; L]; 2]; N] {
    let mut values = [[[0.0f32; L]; 2]; N];
    for (k, [x, y]) in values.iter_mut().enumerate().take(len) {
        for lane in 0..L {
            let pair = first[lane].wrapping_add(k as u32);
            (x[lane], y[lane]) = pair_numbers(index_rev[lane], pair_seed(seed[lane], pair));
        }
    }
    values
}

impl Sampler for SobolSampler {
    /// The first dimension of a fresh pair (stratified in one dimension).
    #[inline]
    fn uniform(&mut self) -> f32 {
        if let Some(pair) = self.next_pair_ahead() {
            return pair.x;
        }
        let seed = self.next_pair_seed();
        let (bits, seed) = shuffle(self.index_rev, seed);
        owen_to_unit(bits, hash(seed ^ SCRAMBLE_X))
    }

    #[inline]
    fn uniform2(&mut self) -> Vec2 {
        if let Some(pair) = self.next_pair_ahead() {
            return pair;
        }
        let seed = self.next_pair_seed();
        let (x, y) = pair_numbers(self.index_rev, seed);
        Vec2::new(x, y)
    }
}

/// How the samples of one key (a pixel's, or an iteration's light paths) relate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SampleSequence {
    /// Stratified against each other: the points of one Owen-scrambled Sobol sequence.
    #[default]
    Sobol,
    /// Independent of each other: each sample is the first point of a sequence of its own.
    /// Frames are then independent too, so the spread between frames estimates the error
    /// of their mean (the statistical tests rely on it).
    Independent,
}

impl SampleSequence {
    /// The numbers of sample `index` of the samples keyed by `key`.
    #[inline]
    pub fn sampler(self, key: &[u64], index: u64) -> SobolSampler {
        match self {
            SampleSequence::Sobol => SobolSampler::new(key, index),
            SampleSequence::Independent => SobolSampler::new(&[hash_key(key), index], 0),
        }
    }
}

/// Scramble constants of dimensions 0 and 1 (those of `sobol_burley`).
const SCRAMBLE_X: u32 = 0x912F_69BA;
const SCRAMBLE_Y: u32 = 0x174F_18AB;

/// The seed of pair `pair` of the sample whose seed is `seed`.
#[inline(always)]
fn pair_seed(seed: u32, pair: u32) -> u32 {
    seed ^ pair.wrapping_mul(0x9E37_79B9)
}

/// Both numbers of the pair of dimensions with seed `seed` of the sample whose reversed index
/// is `index_rev`.
#[inline(always)]
fn pair_numbers(index_rev: u32, seed: u32) -> (f32, f32) {
    let (bits, seed) = shuffle(index_rev, seed);
    // Reversed-bit Sobol values: dimension 0 (van der Corput) is the index itself,
    // dimension 1 (the Pascal matrix mod 2) XORs into bit j every index bit k ⊇ j.
    let mut pascal = bits;
    for (shift, mask) in [(1, 0xAAAA), (2, 0xCCCC), (4, 0xF0F0), (8, 0xFF00)] {
        pascal ^= (pascal & mask) >> shift;
    }
    (
        owen_to_unit(bits, hash(seed ^ SCRAMBLE_X)),
        owen_to_unit(pascal, hash(seed ^ SCRAMBLE_Y)),
    )
}

/// The nested uniform shuffle by `seed` of the index whose reversed bits are `index_rev` (an
/// Owen scramble of them), and the seed the dimensions' scrambles derive from.
#[inline]
fn shuffle(index_rev: u32, seed: u32) -> (u32, u32) {
    let shuffled = owen_scramble_rev(index_rev, hash(seed ^ 0x79C6_8E4A));
    (
        shuffled.reverse_bits() & 0xFFFF,
        seed.wrapping_mul(0x9C8F_2D3B),
    )
}

/// The reversed-bit Sobol value `sobol` Owen-scrambled by `scramble`, as a float in [0, 1)
/// (its top 23 bits).
#[inline]
fn owen_to_unit(sobol: u32, scramble: u32) -> f32 {
    let n = owen_scramble_rev(sobol, scramble).reverse_bits();
    f32::from_bits((n >> 9) | 0x3F80_0000) - 1.0
}

/// Owen scramble of a bit-reversed value (the hash of Vegdahl's "Building a Better LK Hash",
/// 2021, which the `sobol_burley` crate uses).
#[inline]
fn owen_scramble_rev(mut n: u32, scramble: u32) -> u32 {
    n ^= n.wrapping_mul(0x3D20_ADEA);
    n = n.wrapping_add(scramble);
    n = n.wrapping_mul((scramble >> 16) | 1);
    n ^= n.wrapping_mul(0x0552_6C56);
    n ^= n.wrapping_mul(0x53A2_2864);
    n
}

/// 32-bit integer hash (Wellons' hash-prospector mixer, with zero not mapped to zero).
#[inline]
fn hash(mut n: u32) -> u32 {
    n ^= 0xE6FE_3BEB;
    n ^= n >> 16;
    n = n.wrapping_mul(0x7FEB_352D);
    n ^= n >> 15;
    n = n.wrapping_mul(0x846C_A68B);
    n ^= n >> 16;
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `next_stream` is the stream the next `stream` call returns, and draws nothing.
    #[test]
    fn next_stream_is_the_next_stream() {
        let mut sampler = SobolSampler::new(&[3, 4], 5);
        sampler.uniform2();
        let mut ahead = sampler.next_stream();
        let mut again = sampler.next_stream();
        let mut drawn = sampler.stream();
        for _ in 0..4 {
            let x = drawn.next_u32();
            assert_eq!((ahead.next_u32(), again.next_u32()), (x, x));
        }
        let mut after = sampler.stream();
        assert_ne!(after.next_u32(), sampler.next_stream().next_u32());
    }

    /// The same values as the `sobol_burley` crate's reference implementation, bit for bit.
    #[test]
    fn matches_sobol_burley() {
        for seed in [0u32, 1, 0xDEAD_BEEF, 12345] {
            for index in (0..1u32 << 16).step_by(7) {
                let expected = Vec2::new(
                    sobol_burley::sample(index, 0, seed),
                    sobol_burley::sample(index, 1, seed),
                );
                let mut sampler = SobolSampler {
                    seed,
                    index_rev: index.reverse_bits(),
                    pair: 0,
                    step_end: 0,
                    ahead: PairsAhead::default(),
                };
                assert_eq!(sampler.uniform2(), expected, "index {index} seed {seed}");
                sampler.pair = 0;
                assert_eq!(sampler.uniform(), expected.x, "index {index} seed {seed}");
            }
        }
    }

    /// Every power-of-two prefix of a pixel's samples is a (0, m, 2)-net in each pair: each of
    /// the 2^m elementary intervals of every shape holds exactly one point.
    #[test]
    fn pairs_are_stratified() {
        for m in [4u32, 6, 8] {
            let n = 1u32 << m;
            for pair in 0..3 {
                let points: Vec<Vec2> = (0..n)
                    .map(|i| {
                        let mut s = SobolSampler::new(&[3, 77], u64::from(i));
                        s.start_step(pair, 1);
                        s.uniform2()
                    })
                    .collect();
                for x_bits in 0..=m {
                    let (nx, ny) = (1u32 << x_bits, 1u32 << (m - x_bits));
                    let mut count = vec![0u32; n as usize];
                    for p in &points {
                        let cx = ((p.x * nx as f32) as u32).min(nx - 1);
                        let cy = ((p.y * ny as f32) as u32).min(ny - 1);
                        count[(cy * nx + cx) as usize] += 1;
                    }
                    assert!(
                        count.iter().all(|&c| c == 1),
                        "m = {m}, pair {pair}, {nx}×{ny} intervals: {count:?}"
                    );
                }
            }
        }
    }

    /// Different keys and different pairs are unrelated randomizations: the mean over many
    /// pixels of x·y across two pairs is 1/4 within its standard error.
    #[test]
    fn pairs_and_keys_are_independent() {
        let n = 20_000;
        let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
        for pixel in 0..n {
            let mut s = SobolSampler::new(&[1, pixel], 5);
            let (a, b) = (s.uniform(), s.uniform());
            let p = f64::from(a * b);
            sum += p;
            sum_sq += p * p;
        }
        let mean = sum / n as f64;
        let std_err = ((sum_sq / n as f64 - mean * mean) / n as f64).sqrt();
        assert!(
            (mean - 0.25).abs() < 4.0 * std_err,
            "mean {mean} ± {std_err}"
        );
    }

    /// Independent samples of one key are not stratified: their first pair is uniform, and
    /// 2^8 of them leave elementary intervals empty where Sobol points fill each once.
    #[test]
    fn independent_samples_are_uniform_and_unstratified() {
        let n = 1u32 << 8;
        let points: Vec<Vec2> = (0..n)
            .map(|i| {
                SampleSequence::Independent
                    .sampler(&[3, 77], u64::from(i))
                    .uniform2()
            })
            .collect();
        let mut count = [0u32; 256];
        for p in &points {
            count[((p.y * 16.0) as usize) * 16 + (p.x * 16.0) as usize] += 1;
        }
        assert!(count.contains(&0), "{count:?}");
        let mean = points.iter().map(|p| f64::from(p.x + p.y)).sum::<f64>() / f64::from(2 * n);
        // Each coordinate has variance 1/12: the mean of 512 of them has a standard error of
        // 0.0128.
        assert!((mean - 0.5).abs() < 4.0 * 0.0128, "mean {mean}");
    }

    /// Samples beyond the crate's 2^16 limit start fresh randomized blocks rather than
    /// repeating the first one.
    #[test]
    fn blocks_do_not_repeat() {
        let first = SobolSampler::new(&[9], 3).uniform2();
        let next_block = SobolSampler::new(&[9], 3 + (1 << 16)).uniform2();
        assert_ne!(first, next_block);
        assert!(next_block.cmpge(Vec2::ZERO).all() && next_block.cmplt(Vec2::ONE).all());
    }

    /// Prefetched pairs are the pairs the samplers compute on their own, for groups of any
    /// size and whatever mix of single and paired draws takes them; draws past the
    /// prefetched window compute as before.
    #[test]
    fn prefetched_pairs_match_computed_ones() {
        for count in [1usize, 7, 8, 9, 21] {
            let fresh: Vec<SobolSampler> = (0..count)
                .map(|i| {
                    let mut s = SobolSampler::new(&[5, i as u64], i as u64 * 37);
                    s.start_step(i as u32 % 4, 3);
                    s
                })
                .collect();
            let mut prefetched = fresh.clone();
            SobolSampler::prefetch(prefetched.iter_mut());
            for (i, (mut plain, mut ahead)) in fresh.into_iter().zip(prefetched).enumerate() {
                // The step's three pairs, where sampler 0 draws from its first step.
                assert_eq!(ahead.ahead.len, 3, "sampler {i} of {count}");
                for draw in 0..PREFETCH_PAIRS + 3 {
                    if (draw + i) % 2 == 0 {
                        assert_eq!(plain.uniform().to_bits(), ahead.uniform().to_bits());
                    } else {
                        assert_eq!(plain.uniform2(), ahead.uniform2(), "draw {draw}");
                    }
                }
                plain.start_step(40, 3);
                ahead.start_step(40, 3);
                assert_eq!(plain.uniform2(), ahead.uniform2());
            }
        }
    }

    /// A sampler whose next pair lies outside its prefetched window computes it.
    #[test]
    fn pairs_outside_the_window_are_computed() {
        let mut plain = SobolSampler::new(&[2], 11);
        let mut ahead = plain.clone();
        SobolSampler::prefetch([&mut ahead]);
        plain.start_step(2, PREFETCH_PAIRS as u32);
        ahead.start_step(2, PREFETCH_PAIRS as u32);
        for _ in 0..3 {
            assert_eq!(plain.uniform2(), ahead.uniform2());
        }
    }

    /// `peek_lanes` returns what each sampler's draws would at the offsets asked for, whether
    /// or not they were prefetched, and `skip` moves on as the draws do.
    #[test]
    fn peeking_in_lanes_sees_the_draws_and_skipping_makes_them() {
        let mut samplers: [SobolSampler; 3] =
            std::array::from_fn(|i| SobolSampler::new(&[9, i as u64], 21 + i as u64));
        for (i, sampler) in samplers.iter_mut().enumerate() {
            sampler.start_step(1 + i as u32, 4);
        }
        SobolSampler::prefetch(samplers[1..].iter_mut());
        let all: [[[f32; 3]; 2]; 7] =
            SobolSampler::peek_lanes(samplers.each_ref(), [0, 1, 2, 3, 4, 5, 6]);
        let some: [[[f32; 3]; 2]; 2] = SobolSampler::peek_lanes(samplers.each_ref(), [5, 2]);
        assert_eq!(some, [all[5], all[2]]);
        for (lane, sampler) in samplers.iter_mut().enumerate() {
            let mut drawn = sampler.clone();
            assert_eq!(all[0][0][lane], drawn.uniform(), "lane {lane}");
            for pair in &all[1..] {
                assert_eq!(Vec2::new(pair[0][lane], pair[1][lane]), drawn.uniform2());
            }
            sampler.skip(7);
            assert_eq!(sampler.uniform2(), drawn.uniform2(), "lane {lane}");
        }
    }
}
