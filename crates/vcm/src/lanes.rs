//! Several paths' numbers side by side: arrays of [`LANES`] values, for shading several
//! paths with each instruction. Where the build targets AVX, each operation is one AVX
//! instruction on all eight lanes (`lanes/avx.rs`); elsewhere an element-wise loop that the
//! compiler vectorizes (`lanes/portable.rs`).
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

#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
#[path = "lanes/avx.rs"]
mod ops;
// Built into AVX test builds too, which check both versions against each other.
#[cfg(any(test, not(all(target_arch = "x86_64", target_feature = "avx"))))]
#[path = "lanes/portable.rs"]
mod portable;
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
use portable as ops;

impl Real for F32s {
    #[inline(always)]
    fn splat(x: f32) -> F32s {
        F32s::splat(x)
    }

    #[inline(always)]
    fn abs(self) -> F32s {
        F32s::abs(self)
    }

    type Mask = Mask;

    #[inline(always)]
    fn gt(self, other: F32s) -> Mask {
        F32s::gt(self, other)
    }

    #[inline(always)]
    fn is_infinite(self) -> Mask {
        self.abs().eq(F32s::splat(f32::INFINITY))
    }

    #[inline(always)]
    fn select(mask: Mask, yes: F32s, no: F32s) -> F32s {
        mask.select(yes, no)
    }
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
        ops::sqrt(self)
    }

    /// [`f32::abs`] in each lane.
    #[inline(always)]
    pub fn abs(self) -> F32s {
        ops::abs(self)
    }

    /// `self` where it is greater than `other`, else `other` (glam's `max` and
    /// `max_element`: NaN in `self` gives `other`).
    #[inline(always)]
    pub fn max(self, other: F32s) -> F32s {
        ops::max(self, other)
    }

    /// `1.0.copysign(self)` in each lane.
    #[inline(always)]
    pub fn sign_of(self) -> F32s {
        ops::sign_of(self)
    }

    /// Lanes where `self < other`.
    #[inline(always)]
    pub fn lt(self, other: F32s) -> Mask {
        ops::lt(self, other)
    }

    /// Lanes where `self <= other`.
    #[inline(always)]
    pub fn le(self, other: F32s) -> Mask {
        ops::le(self, other)
    }

    /// Lanes where `self > other`.
    #[inline(always)]
    pub fn gt(self, other: F32s) -> Mask {
        ops::gt(self, other)
    }

    /// Lanes where `self >= other`.
    #[inline(always)]
    pub fn ge(self, other: F32s) -> Mask {
        ops::ge(self, other)
    }

    /// Lanes where `self == other`.
    #[inline(always)]
    pub fn eq(self, other: F32s) -> Mask {
        ops::eq(self, other)
    }

    /// Lanes holding a finite number ([`f32::is_finite`]).
    #[inline(always)]
    pub fn is_finite(self) -> Mask {
        ops::is_finite(self)
    }

    /// Lanes holding NaN.
    #[inline(always)]
    pub fn is_nan(self) -> Mask {
        ops::is_nan(self)
    }
}

macro_rules! lane_ops {
    ($($trait:ident $method:ident),*) => {$(
        impl $trait for F32s {
            type Output = F32s;
            #[inline(always)]
            fn $method(self, rhs: F32s) -> F32s {
                ops::$method(self, rhs)
            }
        }
    )*};
}
lane_ops!(Add add, Sub sub, Mul mul, Div div);

impl Neg for F32s {
    type Output = F32s;
    #[inline(always)]
    fn neg(self) -> F32s {
        ops::neg(self)
    }
}

impl Mask {
    /// The mask of `bools`.
    #[inline(always)]
    pub fn from_bools(bools: [bool; LANES]) -> Mask {
        Mask(bools.map(|b| 0u32.wrapping_sub(u32::from(b))))
    }

    /// No lane set.
    #[inline(always)]
    pub fn none() -> Mask {
        Mask([0; LANES])
    }

    /// The first `count` lanes set.
    #[inline(always)]
    pub fn first(count: usize) -> Mask {
        Mask::from_bools(std::array::from_fn(|lane| lane < count))
    }

    /// Each lane's truth value.
    #[inline(always)]
    pub fn bools(self) -> [bool; LANES] {
        self.0.map(|m| m != 0)
    }

    /// Whether lane `lane` is set.
    #[inline(always)]
    pub fn get(self, lane: usize) -> bool {
        self.0[lane] != 0
    }

    /// `yes` in the set lanes, `no` in the others.
    #[inline(always)]
    pub fn select(self, yes: F32s, no: F32s) -> F32s {
        ops::select(self, yes, no)
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
        ops::and(self, rhs)
    }
}

impl BitOr for Mask {
    type Output = Mask;
    #[inline(always)]
    fn bitor(self, rhs: Mask) -> Mask {
        ops::or(self, rhs)
    }
}

impl BitXor for Mask {
    type Output = Mask;
    #[inline(always)]
    fn bitxor(self, rhs: Mask) -> Mask {
        ops::xor(self, rhs)
    }
}

impl Not for Mask {
    type Output = Mask;
    #[inline(always)]
    fn not(self) -> Mask {
        ops::not(self)
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

    /// The AVX instructions against the portable loops.
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    mod avx_against_portable {
        use super::super::{F32s, LANES, Mask, ops, portable};

        /// Values where instructions and scalar code could disagree: signed zeros, subnormals,
        /// infinities, NaNs of both signs, and ordinary numbers.
        const SPECIAL: [f32; 16] = [
            0.0,
            -0.0,
            1.0,
            -2.5,
            1e-42,
            -1e-42,
            f32::MIN_POSITIVE,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            3.0e-20,
            7.5,
            -0.1,
            1e30,
        ];

        /// Every pair of [`SPECIAL`] values, eight pairs at a time.
        fn special_pairs() -> Vec<(F32s, F32s)> {
            let pairs: Vec<_> = SPECIAL
                .iter()
                .flat_map(|&a| SPECIAL.iter().map(move |&b| (a, b)))
                .collect();
            pairs
                .chunks(LANES)
                .map(|chunk| {
                    (
                        F32s::from_fn(|lane| chunk[lane].0),
                        F32s::from_fn(|lane| chunk[lane].1),
                    )
                })
                .collect()
        }

        type Binary = fn(F32s, F32s) -> F32s;
        type Unary = fn(F32s) -> F32s;
        type Comparison = fn(F32s, F32s) -> Mask;

        #[test]
        fn avx_operations_match_the_portable_loops_bit_for_bit() {
            let same = |x: F32s, y: F32s| x.0.map(f32::to_bits) == y.0.map(f32::to_bits);
            for (a, b) in special_pairs() {
                let binary: [(Binary, Binary); 5] = [
                    (ops::add, portable::add),
                    (ops::sub, portable::sub),
                    (ops::mul, portable::mul),
                    (ops::div, portable::div),
                    (ops::max, portable::max),
                ];
                for (k, (avx, loops)) in binary.iter().enumerate() {
                    assert!(same(avx(a, b), loops(a, b)), "binary {k}: {a:?} {b:?}");
                }
                let unary: [(Unary, Unary); 4] = [
                    (ops::neg, portable::neg),
                    (ops::abs, portable::abs),
                    (ops::sqrt, portable::sqrt),
                    (ops::sign_of, portable::sign_of),
                ];
                for (k, (avx, loops)) in unary.iter().enumerate() {
                    assert!(same(avx(a), loops(a)), "unary {k}: {a:?}");
                }
                let compare: [(Comparison, Comparison); 5] = [
                    (ops::lt, portable::lt),
                    (ops::le, portable::le),
                    (ops::gt, portable::gt),
                    (ops::ge, portable::ge),
                    (ops::eq, portable::eq),
                ];
                for (k, (avx, loops)) in compare.iter().enumerate() {
                    assert_eq!(avx(a, b), loops(a, b), "comparison {k}: {a:?} {b:?}");
                }
                assert_eq!(ops::is_finite(a), portable::is_finite(a));
                assert_eq!(ops::is_nan(a), portable::is_nan(a));
                let (m, n) = (portable::lt(a, b), portable::is_nan(b));
                assert_eq!(ops::and(m, n), portable::and(m, n));
                assert_eq!(ops::or(m, n), portable::or(m, n));
                assert_eq!(ops::xor(m, n), portable::xor(m, n));
                assert_eq!(ops::not(m), portable::not(m));
                assert!(same(ops::select(m, a, b), portable::select(m, a, b)));
            }
        }
    }
}
