//! Exact sums of `f32` values: addition that is associative, so a pixel's sum does not depend
//! on the order its samples arrive in, nor on how a render was split into frames, resumes or
//! shards.
//!
//! Every finite `f32` is an integer multiple of 2⁻¹⁴⁹ (the smallest subnormal) below 2¹²⁸, so
//! a fixed-point integer whose last bit weighs 2⁻¹⁴⁹ holds it exactly: 277 bits for the
//! largest value. [`ExactSum`] keeps 320 bits in two's complement (five 64-bit words), which
//! leaves 42 bits of headroom: 2⁴² values of the largest magnitude sum without overflow, and
//! any number of the values a render produces. Integer addition is exact, so the rounding
//! happens once, when the sum is read ([`ExactSum::to_f64`]).

/// Words of an [`ExactSum`].
pub const WORDS: usize = 5;

/// The weight of an [`ExactSum`]'s least significant bit is 2^`-LSB_EXPONENT`: the smallest
/// positive `f32` (subnormal).
pub const LSB_EXPONENT: i32 = 149;

/// An exact sum of `f32` values: a 320-bit two's complement fixed-point integer in units of
/// 2⁻¹⁴⁹, least significant word first.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ExactSum {
    words: [u64; WORDS],
}

impl ExactSum {
    /// The sum of nothing.
    pub const ZERO: ExactSum = ExactSum { words: [0; WORDS] };

    /// The sum held by `words` (least significant first), as [`ExactSum::words`] gives them.
    pub fn from_words(words: [u64; WORDS]) -> ExactSum {
        ExactSum { words }
    }

    /// The 320-bit two's complement integer, in units of 2⁻¹⁴⁹, least significant word first.
    pub fn words(&self) -> [u64; WORDS] {
        self.words
    }

    /// Adds a finite `value` exactly (a non-finite one must not be passed: it has no exact
    /// value; [`crate::Film`] drops and counts those before they get here).
    #[inline]
    pub fn add_f32(&mut self, value: f32) {
        debug_assert!(value.is_finite());
        let bits = value.to_bits();
        let exponent = (bits >> 23) & 0xff;
        let fraction = u128::from(bits & 0x7f_ffff);
        if exponent == 0 && fraction == 0 {
            return;
        }
        // A normal value is 1.f · 2^(e − 127) = (2²³ + f) · 2^((e − 1) − 149); a subnormal
        // is f · 2⁻¹⁴⁹: the integer mantissa shifted left by max(e, 1) − 1 bits.
        let (mantissa, shift) = if exponent == 0 {
            (fraction, 0)
        } else {
            (fraction | 1 << 23, exponent - 1)
        };
        let word = (shift / 64) as usize;
        let addend = mantissa << (shift % 64);
        let (low, high) = (addend as u64, (addend >> 64) as u64);
        if bits >> 31 == 0 {
            self.add_at(word, low, high);
        } else {
            self.subtract_at(word, low, high);
        }
    }

    /// Adds `other` (exact, modulo 2³²⁰).
    pub fn add(&mut self, other: &ExactSum) {
        let mut carry = false;
        for (word, &o) in self.words.iter_mut().zip(&other.words) {
            let (sum, c1) = word.overflowing_add(o);
            let (sum, c2) = sum.overflowing_add(u64::from(carry));
            *word = sum;
            carry = c1 || c2;
        }
    }

    /// Adds `low + high · 2⁶⁴` times 2^(64 · `word`), carrying upwards.
    #[inline]
    fn add_at(&mut self, word: usize, low: u64, high: u64) {
        let (sum, carry) = self.words[word].overflowing_add(low);
        self.words[word] = sum;
        let (sum, c1) = self.words[word + 1].overflowing_add(high);
        let (sum, c2) = sum.overflowing_add(u64::from(carry));
        self.words[word + 1] = sum;
        let mut carry = c1 || c2;
        for w in &mut self.words[word + 2..] {
            if !carry {
                break;
            }
            (*w, carry) = w.overflowing_add(1);
        }
    }

    /// Subtracts `low + high · 2⁶⁴` times 2^(64 · `word`), borrowing upwards.
    #[inline]
    fn subtract_at(&mut self, word: usize, low: u64, high: u64) {
        let (difference, borrow) = self.words[word].overflowing_sub(low);
        self.words[word] = difference;
        let (difference, b1) = self.words[word + 1].overflowing_sub(high);
        let (difference, b2) = difference.overflowing_sub(u64::from(borrow));
        self.words[word + 1] = difference;
        let mut borrow = b1 || b2;
        for w in &mut self.words[word + 2..] {
            if !borrow {
                break;
            }
            (*w, borrow) = w.overflowing_sub(1);
        }
    }

    /// Whether the sum is below zero (the top bit of the two's complement integer).
    fn is_negative(&self) -> bool {
        self.words[WORDS - 1] >> 63 == 1
    }

    /// The sum rounded to the nearest `f64` (ties to even): the only rounding of the sum.
    pub fn to_f64(&self) -> f64 {
        if self.is_negative() {
            let mut magnitude = ExactSum::ZERO;
            // −x = ¬x + 1 in two's complement.
            let mut carry = true;
            for (m, &w) in magnitude.words.iter_mut().zip(&self.words) {
                (*m, carry) = (!w).overflowing_add(u64::from(carry));
            }
            -magnitude.magnitude_to_f64()
        } else {
            self.magnitude_to_f64()
        }
    }

    /// The (non-negative) sum rounded to the nearest `f64`, ties to even.
    fn magnitude_to_f64(&self) -> f64 {
        let Some(top_word) = self.words.iter().rposition(|&w| w != 0) else {
            return 0.0;
        };
        // Bit index of the most significant set bit.
        let top = top_word as u32 * 64 + 63 - self.words[top_word].leading_zeros();
        if top < 53 {
            // Below 2⁵³ the integer converts exactly, and so does the power of two.
            return self.words[0] as f64 * power_of_two(-LSB_EXPONENT);
        }
        // The 53 bits from `top` down, then round to nearest, ties to even, on what is below.
        let shift = top - 52;
        let mut mantissa = self.bits(shift, 53);
        let half = self.bit(shift - 1);
        let below_half = self.any_below(shift - 1);
        if half && (below_half || mantissa & 1 == 1) {
            mantissa += 1; // 2⁵³ after a carry is still exact as an f64
        }
        mantissa as f64 * power_of_two(shift as i32 - LSB_EXPONENT)
    }

    /// Bit `index` of the integer.
    fn bit(&self, index: u32) -> bool {
        self.words[(index / 64) as usize] >> (index % 64) & 1 == 1
    }

    /// Whether any bit below bit `index` is set (whole words at a time).
    fn any_below(&self, index: u32) -> bool {
        let (word, offset) = ((index / 64) as usize, index % 64);
        let partial = self.words[word] & ((1 << offset) - 1);
        partial != 0 || self.words[..word].iter().any(|&w| w != 0)
    }

    /// `count` (≤ 64) bits from bit `first` upwards.
    fn bits(&self, first: u32, count: u32) -> u64 {
        let (word, offset) = ((first / 64) as usize, first % 64);
        let mut value = self.words[word] >> offset;
        if offset > 0 && word + 1 < WORDS {
            value |= self.words[word + 1] << (64 - offset);
        }
        if count < 64 {
            value &= (1 << count) - 1;
        }
        value
    }
}

/// 2^`exponent` for an exponent in the normal range of `f64` (−1022 to 1023).
fn power_of_two(exponent: i32) -> f64 {
    f64::from_bits(((exponent + 1023) as u64) << 52)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sum(values: &[f32]) -> ExactSum {
        let mut sum = ExactSum::ZERO;
        for &v in values {
            sum.add_f32(v);
        }
        sum
    }

    #[test]
    fn single_values_read_back_exactly() {
        let values = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            3.5e-7,
            f32::MIN_POSITIVE,
            f32::from_bits(1), // the smallest subnormal
            f32::from_bits(0x007f_ffff),
            f32::MAX,
            -f32::MAX,
            12345.678,
        ];
        for v in values {
            assert_eq!(sum(&[v]).to_f64(), f64::from(v), "{v:e}");
        }
    }

    #[test]
    fn sums_do_not_depend_on_the_order_or_the_grouping() {
        // Values over 80 binary orders of magnitude, where f64 sums depend on the order.
        let values: Vec<f32> = (0..1000u32)
            .map(|i| {
                let scale = 2f32.powi((i % 80) as i32 - 40);
                let sign = if i % 7 == 0 { -1.0 } else { 1.0 };
                sign * scale * (1.0 + i as f32 / 997.0)
            })
            .collect();
        let forward = sum(&values);
        let mut reversed = values.clone();
        reversed.reverse();
        assert_eq!(sum(&reversed), forward);
        // Four parts summed apart, then merged in another order.
        let mut merged = ExactSum::ZERO;
        for part in values.chunks(250).rev() {
            merged.add(&sum(part));
        }
        assert_eq!(merged, forward);
        // And the f64 sums really did depend on the order.
        let f64_forward: f64 = values.iter().map(|&v| f64::from(v)).sum();
        let f64_reversed: f64 = reversed.iter().map(|&v| f64::from(v)).sum();
        assert_ne!(
            f64_forward, f64_reversed,
            "the test needs values that round"
        );
        // The exact sum, rounded once, is at least as close as either.
        let exact = forward.to_f64();
        assert!((exact - f64_forward).abs() <= 1e-9 * exact.abs());
    }

    #[test]
    fn rounding_is_to_nearest_with_ties_to_even() {
        // 2⁵³ + 1 is a tie between 2⁵³ and 2⁵³ + 2: to even, 2⁵³.
        let two_53 = 2f32.powi(53);
        assert_eq!(sum(&[two_53, 1.0]).to_f64(), 2f64.powi(53));
        // 2⁵³ + 3 is a tie between 2⁵³ + 2 and 2⁵³ + 4: to even, 2⁵³ + 4.
        assert_eq!(sum(&[two_53, 1.0, 2.0]).to_f64(), 2f64.powi(53) + 4.0);
        // Just above a tie rounds up: 2⁵³ + 1 + 2⁻¹⁰⁰.
        let above = sum(&[two_53, 1.0, 2f32.powi(-100)]);
        assert_eq!(above.to_f64(), 2f64.powi(53) + 2.0);
        // The same with the sticky bit in the word of the rounding bit, and in the lowest.
        let above = sum(&[two_53, 1.0, 2f32.powi(-10)]);
        assert_eq!(above.to_f64(), 2f64.powi(53) + 2.0);
        let above = sum(&[two_53, 1.0, 2f32.powi(-149)]);
        assert_eq!(above.to_f64(), 2f64.powi(53) + 2.0);
    }

    #[test]
    fn large_and_negative_sums() {
        let big = sum(&vec![f32::MAX; 1 << 12]);
        assert_eq!(big.to_f64(), f64::from(f32::MAX) * 4096.0);
        let cancelled = sum(&[f32::MAX, 1e-30, -f32::MAX]);
        assert_eq!(cancelled.to_f64(), f64::from(1e-30f32));
        assert_eq!(sum(&[1.0, -3.0]).to_f64(), -2.0);
        assert_eq!(sum(&[2.5, -2.5]), ExactSum::ZERO);
        let words = big.words();
        assert_eq!(ExactSum::from_words(words), big);
    }
}
