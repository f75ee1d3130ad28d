//! The lane operations in AVX instructions, one per operation on all eight lanes, for builds
//! that target AVX (`-C target-cpu=native` on such a CPU).
//!
//! The element-wise loops of the portable version vectorize well one at a time, but LLVM
//! turned some chains of them into scalar code: a lane-wise `is_finite() & gt(0)` became
//! eight integer tests of the bit patterns, each extracted from its register. Each
//! instruction here computes exactly the `f32` operation of the portable loop in every lane:
//! IEEE add, subtract, multiply, divide and square root; `max(a, b)` is `a > b ? a : b` (as
//! `vmaxps` defines it); the comparisons are ordered and quiet (false for NaN), as Rust's
//! are; the sign operations touch only the sign bit.

use std::arch::x86_64::*;

use super::{F32s, Mask};

/// Runs AVX intrinsics.
macro_rules! avx {
    ($($body:tt)*) => {
        // SAFETY: this module is only built for targets with AVX (`cfg(target_feature)`),
        // so the CPU that runs it has the instructions.
        unsafe { $($body)* }
    };
}

/// The lanes as a register.
#[inline(always)]
fn reg(a: F32s) -> __m256 {
    // SAFETY: eight `f32` and a `__m256` are the same 32 bytes, and every bit pattern is
    // valid for both.
    unsafe { std::mem::transmute::<[f32; 8], __m256>(a.0) }
}

/// A register as lanes.
#[inline(always)]
fn lanes(v: __m256) -> F32s {
    // SAFETY: as in `reg`.
    F32s(unsafe { std::mem::transmute::<__m256, [f32; 8]>(v) })
}

/// A mask's bits as a register.
#[inline(always)]
fn mask_reg(m: Mask) -> __m256 {
    // SAFETY: eight `u32` and a `__m256` are the same 32 bytes, and every bit pattern is
    // valid for both.
    unsafe { std::mem::transmute::<[u32; 8], __m256>(m.0) }
}

/// A register's bits as a mask.
#[inline(always)]
fn mask(v: __m256) -> Mask {
    // SAFETY: as in `mask_reg`.
    Mask(unsafe { std::mem::transmute::<__m256, [u32; 8]>(v) })
}

/// Only the sign bit set, in every lane.
#[inline(always)]
fn sign_bits() -> __m256 {
    avx! { _mm256_set1_ps(-0.0) }
}

#[inline(always)]
pub fn add(a: F32s, b: F32s) -> F32s {
    avx! { lanes(_mm256_add_ps(reg(a), reg(b))) }
}

#[inline(always)]
pub fn sub(a: F32s, b: F32s) -> F32s {
    avx! { lanes(_mm256_sub_ps(reg(a), reg(b))) }
}

#[inline(always)]
pub fn mul(a: F32s, b: F32s) -> F32s {
    avx! { lanes(_mm256_mul_ps(reg(a), reg(b))) }
}

#[inline(always)]
pub fn div(a: F32s, b: F32s) -> F32s {
    avx! { lanes(_mm256_div_ps(reg(a), reg(b))) }
}

#[inline(always)]
pub fn neg(a: F32s) -> F32s {
    avx! { lanes(_mm256_xor_ps(reg(a), sign_bits())) }
}

#[inline(always)]
pub fn abs(a: F32s) -> F32s {
    avx! { lanes(_mm256_andnot_ps(sign_bits(), reg(a))) }
}

#[inline(always)]
pub fn sqrt(a: F32s) -> F32s {
    avx! { lanes(_mm256_sqrt_ps(reg(a))) }
}

/// `1.0.copysign(a)`: the sign bit of `a` on the bits of 1.
#[inline(always)]
pub fn sign_of(a: F32s) -> F32s {
    avx! {
        let sign = _mm256_and_ps(reg(a), sign_bits());
        lanes(_mm256_or_ps(sign, _mm256_set1_ps(1.0)))
    }
}

#[inline(always)]
pub fn max(a: F32s, b: F32s) -> F32s {
    avx! { lanes(_mm256_max_ps(reg(a), reg(b))) }
}

#[inline(always)]
pub fn lt(a: F32s, b: F32s) -> Mask {
    avx! { mask(_mm256_cmp_ps::<_CMP_LT_OQ>(reg(a), reg(b))) }
}

#[inline(always)]
pub fn le(a: F32s, b: F32s) -> Mask {
    avx! { mask(_mm256_cmp_ps::<_CMP_LE_OQ>(reg(a), reg(b))) }
}

#[inline(always)]
pub fn gt(a: F32s, b: F32s) -> Mask {
    avx! { mask(_mm256_cmp_ps::<_CMP_GT_OQ>(reg(a), reg(b))) }
}

#[inline(always)]
pub fn ge(a: F32s, b: F32s) -> Mask {
    avx! { mask(_mm256_cmp_ps::<_CMP_GE_OQ>(reg(a), reg(b))) }
}

#[inline(always)]
pub fn eq(a: F32s, b: F32s) -> Mask {
    avx! { mask(_mm256_cmp_ps::<_CMP_EQ_OQ>(reg(a), reg(b))) }
}

/// `|a| < ∞`, as [`f32::is_finite`].
#[inline(always)]
pub fn is_finite(a: F32s) -> Mask {
    avx! {
        let infinity = _mm256_set1_ps(f32::INFINITY);
        mask(_mm256_cmp_ps::<_CMP_LT_OQ>(reg(abs(a)), infinity))
    }
}

#[inline(always)]
pub fn is_nan(a: F32s) -> Mask {
    avx! { mask(_mm256_cmp_ps::<_CMP_UNORD_Q>(reg(a), reg(a))) }
}

#[inline(always)]
pub fn and(a: Mask, b: Mask) -> Mask {
    avx! { mask(_mm256_and_ps(mask_reg(a), mask_reg(b))) }
}

#[inline(always)]
pub fn or(a: Mask, b: Mask) -> Mask {
    avx! { mask(_mm256_or_ps(mask_reg(a), mask_reg(b))) }
}

#[inline(always)]
pub fn xor(a: Mask, b: Mask) -> Mask {
    avx! { mask(_mm256_xor_ps(mask_reg(a), mask_reg(b))) }
}

#[inline(always)]
pub fn not(a: Mask) -> Mask {
    avx! {
        let all = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        mask(_mm256_xor_ps(mask_reg(a), all))
    }
}

/// `(yes & mask) | (no & !mask)`, bit for bit.
#[inline(always)]
pub fn select(m: Mask, yes: F32s, no: F32s) -> F32s {
    avx! {
        let m = mask_reg(m);
        lanes(_mm256_or_ps(
            _mm256_and_ps(m, reg(yes)),
            _mm256_andnot_ps(m, reg(no)),
        ))
    }
}
