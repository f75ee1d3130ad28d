//! The lane operations as element-wise loops over the arrays, for targets without AVX: the
//! compiler vectorizes what it can.

use super::{F32s, LANES, Mask};

#[inline(always)]
fn map<T: Copy, U: Copy + Default>(a: [T; LANES], f: impl Fn(T) -> U) -> [U; LANES] {
    let mut out = [U::default(); LANES];
    for lane in 0..LANES {
        out[lane] = f(a[lane]);
    }
    out
}

#[inline(always)]
fn zip<T: Copy, U: Copy + Default>(
    a: [T; LANES],
    b: [T; LANES],
    f: impl Fn(T, T) -> U,
) -> [U; LANES] {
    let mut out = [U::default(); LANES];
    for lane in 0..LANES {
        out[lane] = f(a[lane], b[lane]);
    }
    out
}

#[inline(always)]
pub fn add(a: F32s, b: F32s) -> F32s {
    F32s(zip(a.0, b.0, |a, b| a + b))
}

#[inline(always)]
pub fn sub(a: F32s, b: F32s) -> F32s {
    F32s(zip(a.0, b.0, |a, b| a - b))
}

#[inline(always)]
pub fn mul(a: F32s, b: F32s) -> F32s {
    F32s(zip(a.0, b.0, |a, b| a * b))
}

#[inline(always)]
pub fn div(a: F32s, b: F32s) -> F32s {
    F32s(zip(a.0, b.0, |a, b| a / b))
}

#[inline(always)]
pub fn neg(a: F32s) -> F32s {
    F32s(map(a.0, |x| -x))
}

#[inline(always)]
pub fn abs(a: F32s) -> F32s {
    F32s(map(a.0, f32::abs))
}

#[inline(always)]
pub fn sqrt(a: F32s) -> F32s {
    F32s(map(a.0, f32::sqrt))
}

#[inline(always)]
pub fn sign_of(a: F32s) -> F32s {
    F32s(map(a.0, |x| 1.0f32.copysign(x)))
}

#[inline(always)]
pub fn max(a: F32s, b: F32s) -> F32s {
    F32s(zip(a.0, b.0, |a, b| if a > b { a } else { b }))
}

#[inline(always)]
pub fn lt(a: F32s, b: F32s) -> Mask {
    Mask::from_bools(zip(a.0, b.0, |a, b| a < b))
}

#[inline(always)]
pub fn le(a: F32s, b: F32s) -> Mask {
    Mask::from_bools(zip(a.0, b.0, |a, b| a <= b))
}

#[inline(always)]
pub fn gt(a: F32s, b: F32s) -> Mask {
    Mask::from_bools(zip(a.0, b.0, |a, b| a > b))
}

#[inline(always)]
pub fn ge(a: F32s, b: F32s) -> Mask {
    Mask::from_bools(zip(a.0, b.0, |a, b| a >= b))
}

#[inline(always)]
pub fn eq(a: F32s, b: F32s) -> Mask {
    Mask::from_bools(zip(a.0, b.0, |a, b| a == b))
}

#[inline(always)]
pub fn is_finite(a: F32s) -> Mask {
    Mask::from_bools(map(a.0, f32::is_finite))
}

#[inline(always)]
pub fn is_nan(a: F32s) -> Mask {
    Mask::from_bools(map(a.0, f32::is_nan))
}

#[inline(always)]
pub fn and(a: Mask, b: Mask) -> Mask {
    Mask(zip(a.0, b.0, |a, b| a & b))
}

#[inline(always)]
pub fn or(a: Mask, b: Mask) -> Mask {
    Mask(zip(a.0, b.0, |a, b| a | b))
}

#[inline(always)]
pub fn xor(a: Mask, b: Mask) -> Mask {
    Mask(zip(a.0, b.0, |a, b| a ^ b))
}

#[inline(always)]
pub fn not(a: Mask) -> Mask {
    Mask(map(a.0, |a| !a))
}

#[inline(always)]
pub fn select(mask: Mask, yes: F32s, no: F32s) -> F32s {
    F32s(std::array::from_fn(|lane| {
        let m = mask.0[lane];
        f32::from_bits((yes.0[lane].to_bits() & m) | (no.0[lane].to_bits() & !m))
    }))
}
