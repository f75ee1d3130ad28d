//! [`Real`]: the arithmetic of formulas written once for one number and for several in SIMD
//! lanes (the `vcm` crate's lane types implement it).

use std::ops::{Add, Div, Mul, Sub};

/// Numbers whose operations are those of `f32`, applied to one value or lane by lane: a
/// formula written for `T: Real` computes, in every lane, bit for bit what it computes on
/// one `f32` (Rust never fuses a multiply and an add).
pub trait Real:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// `x` (in every lane).
    fn splat(x: f32) -> Self;

    /// [`f32::abs`] (in every lane).
    fn abs(self) -> Self;

    /// The truth of a comparison (in every lane).
    type Mask: Copy;

    /// Lanes where `self > other`.
    fn gt(self, other: Self) -> Self::Mask;

    /// Lanes holding +∞ or −∞ ([`f32::is_infinite`]).
    fn is_infinite(self) -> Self::Mask;

    /// `yes` in the lanes of `mask`, `no` elsewhere.
    fn select(mask: Self::Mask, yes: Self, no: Self) -> Self;
}

impl Real for f32 {
    #[inline(always)]
    fn splat(x: f32) -> f32 {
        x
    }

    #[inline(always)]
    fn abs(self) -> f32 {
        f32::abs(self)
    }

    type Mask = bool;

    #[inline(always)]
    fn gt(self, other: f32) -> bool {
        self > other
    }

    #[inline(always)]
    fn is_infinite(self) -> bool {
        f32::is_infinite(self)
    }

    #[inline(always)]
    fn select(mask: bool, yes: f32, no: f32) -> f32 {
        if mask { yes } else { no }
    }
}
