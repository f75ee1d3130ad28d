//! Several paths' numbers side by side: arrays of [`LANES`] values whose element-wise loops
//! the compiler turns into SIMD instructions (eight `f32` fill an AVX2 register), for shading
//! several paths with each instruction.
//!
//! Every operation is the `f32` operation of the same name applied lane by lane, so code
//! written with these types computes, in each lane, bit for bit what the same steps compute
//! on one path with `f32` and glam's `Vec3` (Rust never fuses a multiply and an add).

use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};

use glam::Vec3;

/// Paths shaded together.
pub(crate) const LANES: usize = 8;

/// One `f32` per lane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(align(32))]
pub(crate) struct F32s(pub [f32; LANES]);

/// One truth value per lane, all bits set for true (as SIMD comparisons give them, so that
/// selecting by a mask is a bitwise operation): the result of a comparison, or which lanes
/// take part.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(align(32))]
pub(crate) struct Mask([u32; LANES]);

/// One `Vec3` per lane, as three [`F32s`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Vec3s {
    pub x: F32s,
    pub y: F32s,
    pub z: F32s,
}

pub(crate) use vcm_scene::Real;

impl Real for F32s {
    #[inline(always)]
    fn splat(x: f32) -> F32s {
        F32s::splat(x)
    }

    #[inline(always)]
    fn abs(self) -> F32s {
        F32s::abs(self)
    }
}

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

impl F32s {
    /// `x` in every lane.
    #[inline(always)]
    pub fn splat(x: f32) -> F32s {
        F32s([x; LANES])
    }

    /// Lane `i` is `f(i)`.
    #[inline(always)]
    pub fn from_fn(f: impl FnMut(usize) -> f32) -> F32s {
        F32s(std::array::from_fn(f))
    }

    /// [`f32::sqrt`] in each lane.
    #[inline(always)]
    pub fn sqrt(self) -> F32s {
        F32s(map(self.0, f32::sqrt))
    }

    /// [`f32::abs`] in each lane.
    #[inline(always)]
    pub fn abs(self) -> F32s {
        F32s(map(self.0, f32::abs))
    }

    /// `self` where it is greater than `other`, else `other` (glam's `max` and
    /// `max_element`: NaN in `self` gives `other`).
    #[inline(always)]
    pub fn max(self, other: F32s) -> F32s {
        F32s(zip(self.0, other.0, |a, b| if a > b { a } else { b }))
    }

    /// `1.0.copysign(self)` in each lane.
    #[inline(always)]
    pub fn sign_of(self) -> F32s {
        F32s(map(self.0, |x| 1.0f32.copysign(x)))
    }

    /// Lanes where `self < other`.
    #[inline(always)]
    pub fn lt(self, other: F32s) -> Mask {
        Mask::from_bools(zip(self.0, other.0, |a, b| a < b))
    }

    /// Lanes where `self <= other`.
    #[inline(always)]
    pub fn le(self, other: F32s) -> Mask {
        Mask::from_bools(zip(self.0, other.0, |a, b| a <= b))
    }

    /// Lanes where `self > other`.
    #[inline(always)]
    pub fn gt(self, other: F32s) -> Mask {
        Mask::from_bools(zip(self.0, other.0, |a, b| a > b))
    }

    /// Lanes where `self >= other`.
    #[inline(always)]
    pub fn ge(self, other: F32s) -> Mask {
        Mask::from_bools(zip(self.0, other.0, |a, b| a >= b))
    }

    /// Lanes where `self == other`.
    #[inline(always)]
    pub fn eq(self, other: F32s) -> Mask {
        Mask::from_bools(zip(self.0, other.0, |a, b| a == b))
    }

    /// Lanes holding a finite number ([`f32::is_finite`]).
    #[inline(always)]
    pub fn is_finite(self) -> Mask {
        Mask::from_bools(map(self.0, f32::is_finite))
    }

    /// Lanes holding NaN.
    #[inline(always)]
    pub fn is_nan(self) -> Mask {
        Mask::from_bools(map(self.0, f32::is_nan))
    }
}

macro_rules! lane_ops {
    ($($trait:ident $method:ident $op:tt),*) => {$(
        impl $trait for F32s {
            type Output = F32s;
            #[inline(always)]
            fn $method(self, rhs: F32s) -> F32s {
                F32s(zip(self.0, rhs.0, |a, b| a $op b))
            }
        }
    )*};
}
lane_ops!(Add add +, Sub sub -, Mul mul *, Div div /);

impl Neg for F32s {
    type Output = F32s;
    #[inline(always)]
    fn neg(self) -> F32s {
        F32s(map(self.0, |x| -x))
    }
}

impl Mask {
    /// The mask of `bools`.
    #[inline(always)]
    pub fn from_bools(bools: [bool; LANES]) -> Mask {
        Mask(map(bools, |b| 0u32.wrapping_sub(u32::from(b))))
    }

    /// The first `count` lanes set.
    #[inline(always)]
    pub fn first(count: usize) -> Mask {
        Mask::from_bools(std::array::from_fn(|lane| lane < count))
    }

    /// Each lane's truth value.
    #[inline(always)]
    pub fn bools(self) -> [bool; LANES] {
        map(self.0, |m| m != 0)
    }

    /// Whether lane `lane` is set.
    #[inline(always)]
    pub fn get(self, lane: usize) -> bool {
        self.0[lane] != 0
    }

    /// `yes` in the set lanes, `no` in the others.
    #[inline(always)]
    pub fn select(self, yes: F32s, no: F32s) -> F32s {
        F32s(std::array::from_fn(|lane| {
            let m = self.0[lane];
            f32::from_bits((yes.0[lane].to_bits() & m) | (no.0[lane].to_bits() & !m))
        }))
    }

    /// [`Mask::select`] for each coordinate.
    #[inline(always)]
    pub fn select3(self, yes: Vec3s, no: Vec3s) -> Vec3s {
        Vec3s {
            x: self.select(yes.x, no.x),
            y: self.select(yes.y, no.y),
            z: self.select(yes.z, no.z),
        }
    }
}

impl BitAnd for Mask {
    type Output = Mask;
    #[inline(always)]
    fn bitand(self, rhs: Mask) -> Mask {
        Mask(zip(self.0, rhs.0, |a, b| a & b))
    }
}

impl BitOr for Mask {
    type Output = Mask;
    #[inline(always)]
    fn bitor(self, rhs: Mask) -> Mask {
        Mask(zip(self.0, rhs.0, |a, b| a | b))
    }
}

impl BitXor for Mask {
    type Output = Mask;
    #[inline(always)]
    fn bitxor(self, rhs: Mask) -> Mask {
        Mask(zip(self.0, rhs.0, |a, b| a ^ b))
    }
}

impl Not for Mask {
    type Output = Mask;
    #[inline(always)]
    fn not(self) -> Mask {
        Mask(map(self.0, |a| !a))
    }
}

impl Vec3s {
    /// `v` in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> Vec3s {
        Vec3s {
            x: F32s::splat(v.x),
            y: F32s::splat(v.y),
            z: F32s::splat(v.z),
        }
    }

    /// Sets lane `lane` to `v`.
    #[inline(always)]
    pub fn set(&mut self, lane: usize, v: Vec3) {
        (self.x.0[lane], self.y.0[lane], self.z.0[lane]) = (v.x, v.y, v.z);
    }

    /// Lane `lane`.
    #[inline(always)]
    pub fn lane(&self, lane: usize) -> Vec3 {
        Vec3::new(self.x.0[lane], self.y.0[lane], self.z.0[lane])
    }

    /// [`Vec3::dot`]: `(x·x') + (y·y') + (z·z')`.
    #[inline(always)]
    pub fn dot(self, rhs: Vec3s) -> F32s {
        self.x * rhs.x + self.y * rhs.y + self.z * rhs.z
    }

    /// [`Vec3::cross`].
    #[inline(always)]
    pub fn cross(self, rhs: Vec3s) -> Vec3s {
        Vec3s {
            x: self.y * rhs.z - rhs.y * self.z,
            y: self.z * rhs.x - rhs.z * self.x,
            z: self.x * rhs.y - rhs.x * self.y,
        }
    }

    /// Each coordinate times `s` ([`Vec3`] `* f32`).
    #[inline(always)]
    pub fn scale(self, s: F32s) -> Vec3s {
        Vec3s {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }

    /// Each coordinate divided by `s` ([`Vec3`] `/ f32`).
    #[inline(always)]
    pub fn div(self, s: F32s) -> Vec3s {
        Vec3s {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }

    /// Coordinate-wise product ([`Vec3`] `* Vec3`).
    #[inline(always)]
    pub fn mul(self, rhs: Vec3s) -> Vec3s {
        Vec3s {
            x: self.x * rhs.x,
            y: self.y * rhs.y,
            z: self.z * rhs.z,
        }
    }

    /// [`Vec3::abs`].
    #[inline(always)]
    pub fn abs(self) -> Vec3s {
        Vec3s {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }

    /// [`Vec3::max_element`]: `max(x, max(y, z))`.
    #[inline(always)]
    pub fn max_element(self) -> F32s {
        self.x.max(self.y.max(self.z))
    }

    /// [`Vec3::length_squared`].
    #[inline(always)]
    pub fn length_squared(self) -> F32s {
        self.dot(self)
    }

    /// `1 / length`, glam's `length_recip`.
    #[inline(always)]
    pub fn length_recip(self) -> F32s {
        F32s::splat(1.0) / self.length_squared().sqrt()
    }

    /// [`Vec3::normalize`]: `self · length_recip`.
    #[inline(always)]
    pub fn normalize(self) -> Vec3s {
        self.scale(self.length_recip())
    }

    /// [`Vec3::normalize_or`]: `fallback` in the lanes whose `length_recip` is not finite
    /// and positive.
    #[inline(always)]
    pub fn normalize_or(self, fallback: Vec3s) -> Vec3s {
        let rcp = self.length_recip();
        let ok = rcp.is_finite() & rcp.gt(F32s::splat(0.0));
        ok.select3(self.scale(rcp), fallback)
    }

    /// Lanes where every coordinate is finite ([`Vec3::is_finite`]).
    #[inline(always)]
    pub fn is_finite(self) -> Mask {
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite()
    }

    /// Lanes where some coordinate is not zero (`!= Vec3::ZERO`).
    #[inline(always)]
    pub fn is_nonzero(self) -> Mask {
        let zero = F32s::splat(0.0);
        !(self.x.eq(zero) & self.y.eq(zero) & self.z.eq(zero))
    }
}

macro_rules! vec_ops {
    ($($trait:ident $method:ident $op:tt),*) => {$(
        impl $trait for Vec3s {
            type Output = Vec3s;
            #[inline(always)]
            fn $method(self, rhs: Vec3s) -> Vec3s {
                Vec3s {
                    x: self.x $op rhs.x,
                    y: self.y $op rhs.y,
                    z: self.z $op rhs.z,
                }
            }
        }
    )*};
}
vec_ops!(Add add +, Sub sub -);

impl Neg for Vec3s {
    type Output = Vec3s;
    #[inline(always)]
    fn neg(self) -> Vec3s {
        Vec3s {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vectors() -> [Vec3; LANES] {
        [
            Vec3::new(0.3, -1.2, 2.5),
            Vec3::new(1e-20, 3.0, -0.0),
            Vec3::ZERO,
            Vec3::new(f32::NAN, 1.0, 2.0),
            Vec3::new(-7.0, 0.125, 1e30),
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(-0.5, -0.25, 4.0),
            Vec3::new(f32::INFINITY, 0.0, 1.0),
        ]
    }

    /// Bit patterns, so that zeros' signs count, with every NaN alike (its sign and payload
    /// depend on the instruction that made it).
    fn bits(v: Vec3) -> [u32; 3] {
        v.to_array()
            .map(|x| if x.is_nan() { f32::NAN } else { x }.to_bits())
    }

    #[test]
    fn vector_operations_match_glam_lane_by_lane() {
        let a = vectors();
        let b = a.map(|v| Vec3::new(v.z, -v.x, v.y * 0.5));
        let (mut la, mut lb) = (Vec3s::default(), Vec3s::default());
        for i in 0..LANES {
            la.set(i, a[i]);
            lb.set(i, b[i]);
        }
        let fallback = Vec3s::splat(Vec3::X);
        for i in 0..LANES {
            let (x, y) = (a[i], b[i]);
            assert_eq!(bits(la.cross(lb).lane(i)), bits(x.cross(y)), "cross {i}");
            let dot = Vec3::splat(la.dot(lb).0[i]);
            assert_eq!(bits(dot), bits(Vec3::splat(x.dot(y))), "dot {i}");
            assert_eq!(bits(la.normalize().lane(i)), bits(x * x.length_recip()));
            assert_eq!(
                bits(la.normalize_or(fallback).lane(i)),
                bits(x.normalize_or(Vec3::X)),
                "normalize_or {i}"
            );
            let max = Vec3::splat(la.max_element().0[i]);
            assert_eq!(
                bits(max),
                bits(Vec3::splat(x.max_element())),
                "max_element {i}"
            );
            assert_eq!(la.is_finite().get(i), x.is_finite());
            assert_eq!(la.is_nonzero().get(i), x != Vec3::ZERO);
        }
    }
}
