//! Ray tests against the eight child boxes of a [`WideNode`].
//!
//! Each slab distance `(plane − o) · (1/d)` takes three roundings (the subtraction, the
//! reciprocal and the product), so it is within a relative `γ₃ = 3u/(1 − 3u)` of the exact
//! distance. The test widens the entry distance down and the exit distance up by
//! [`SLAB_SLACK`] of their magnitude before comparing them, so a box is never culled that
//! the exact test would keep: geometry lying exactly on a box face (axis-aligned walls,
//! cube corners) is never missed by one ulp. An empty slot's inverted box gives an infinite
//! entry and exit, whose widening is NaN, and NaN compares false: it is never entered.

use glam::Vec4;

use super::ray::PreparedRay;
use super::wide_node::{LEAF, WideNode};

/// Relative widening of slab distances: `2γ₃` and the rounding of the widening itself,
/// with room to spare.
const SLAB_SLACK: f32 = 4.0 * f32::EPSILON;

/// What a ray overlaps among a node's children.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NodeHits {
    /// A bit per overlapped internal child slot.
    pub inner: u32,
    /// A bit per leaf triangle `node.first_triangle + k` of the overlapped leaf children.
    pub leaves: u32,
    /// Per slot, a lower bound of the ray parameter at which the ray enters the child box.
    pub entry: [f32; 8],
}

/// Intersects a ray with the children of a node.
pub(crate) trait NodeTest: Copy {
    /// The children whose boxes the ray overlaps within `[ray.tmin, tmax]`.
    fn intersect(self, node: &WideNode, ray: &PreparedRay, tmax: f32) -> NodeHits;
}

/// `exit` widened up by [`SLAB_SLACK`] of its magnitude.
#[inline(always)]
pub(crate) fn widen_up(exit: f32) -> f32 {
    exit + exit.abs() * SLAB_SLACK
}

/// Four children at a time with 4-wide vectors; works on every target.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable;

impl NodeTest for Portable {
    #[inline(always)]
    fn intersect(self, node: &WideNode, ray: &PreparedRay, tmax: f32) -> NodeHits {
        let mut overlapped = 0;
        let mut entry = [0.0; 8];
        for half in 0..2 {
            let quad = |plane: usize| Vec4::from_slice(&node.planes[plane][half * 4..]);
            let mut near = Vec4::splat(ray.tmin);
            let mut far = Vec4::splat(tmax);
            for axis in 0..3 {
                let (origin, inv_dir) = (Vec4::splat(ray.origin[axis]), ray.inv_dir[axis]);
                let plane = ray.near_planes[axis];
                near = near.max((quad(plane) - origin) * inv_dir);
                far = far.min((quad(plane ^ 1) - origin) * inv_dir);
            }
            let near = near - near.abs() * SLAB_SLACK;
            let far = far + far.abs() * SLAB_SLACK;
            overlapped |= near.cmple(far).bitmask() << (half * 4);
            near.write_to_slice(&mut entry[half * 4..]);
        }
        let mut hits = NodeHits {
            inner: 0,
            leaves: 0,
            entry,
        };
        while overlapped != 0 {
            let slot = overlapped.trailing_zeros() as usize;
            overlapped &= overlapped - 1;
            match node.children[slot] {
                child if child & LEAF != 0 => hits.leaves |= child & !LEAF,
                _ => hits.inner |= 1 << slot,
            }
        }
        hits
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx2::Avx2;

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    use super::{NodeHits, NodeTest, SLAB_SLACK};
    use crate::cpu::ray::PreparedRay;
    use crate::cpu::wide_node::{LEAF, WideNode};

    /// All eight children at once with AVX2 and FMA. Only constructible where the CPU
    /// supports both.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Avx2 {
        _supported: (),
    }

    impl Avx2 {
        /// Returns the AVX2 node test if this CPU supports AVX2 and FMA.
        pub fn detect() -> Option<Self> {
            (is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"))
                .then_some(Self { _supported: () })
        }
    }

    impl NodeTest for Avx2 {
        // Not a `#[target_feature]` function, so that it can be `inline(always)` into the
        // AVX2 chunk loops, where the intrinsics then inline too.
        #[inline(always)]
        fn intersect(self, node: &WideNode, ray: &PreparedRay, tmax: f32) -> NodeHits {
            // SAFETY: `Avx2` values only exist when the CPU supports AVX2 and FMA; the
            // loads read whole `[f32; 8]` and `[u32; 8]` arrays.
            unsafe {
                let plane = |index: usize| _mm256_loadu_ps(node.planes[index].as_ptr());
                let mut near = _mm256_set1_ps(ray.tmin);
                let mut far = _mm256_set1_ps(tmax);
                for axis in 0..3 {
                    let origin = _mm256_set1_ps(ray.origin[axis]);
                    let inv_dir = _mm256_set1_ps(ray.inv_dir[axis]);
                    let entry_plane = ray.near_planes[axis];
                    let distance =
                        |index| _mm256_mul_ps(_mm256_sub_ps(plane(index), origin), inv_dir);
                    near = _mm256_max_ps(near, distance(entry_plane));
                    far = _mm256_min_ps(far, distance(entry_plane ^ 1));
                }
                let (sign, slack) = (_mm256_set1_ps(-0.0), _mm256_set1_ps(SLAB_SLACK));
                let widen = |t| _mm256_mul_ps(_mm256_andnot_ps(sign, t), slack);
                let near = _mm256_sub_ps(near, widen(near));
                let far = _mm256_add_ps(far, widen(far));
                let overlapped = _mm256_cmp_ps::<_CMP_LE_OQ>(near, far);
                let children = _mm256_loadu_si256(node.children.as_ptr().cast());
                // Leaf children have their sign bit set.
                let leaf_slots = _mm256_castsi256_ps(children);
                let hit_children = _mm256_and_si256(_mm256_castps_si256(overlapped), children);
                let hit_leaves = _mm256_srai_epi32::<31>(hit_children);
                let mut entry = [0.0; 8];
                _mm256_storeu_ps(entry.as_mut_ptr(), near);
                NodeHits {
                    inner: _mm256_movemask_ps(_mm256_andnot_ps(leaf_slots, overlapped)) as u32,
                    leaves: or_lanes(hit_leaves, hit_children) & !LEAF,
                    entry,
                }
            }
        }
    }

    /// The OR of the lanes of `values` selected by the all-ones lanes of `selected`.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[inline(always)]
    unsafe fn or_lanes(selected: __m256i, values: __m256i) -> u32 {
        // SAFETY: the caller guarantees AVX2.
        unsafe {
            let lanes = _mm256_and_si256(selected, values);
            let halves = _mm_or_si128(
                _mm256_castsi256_si128(lanes),
                _mm256_extracti128_si256::<1>(lanes),
            );
            let pairs = _mm_or_si128(halves, _mm_shuffle_epi32::<0b01_00_11_10>(halves));
            let all = _mm_or_si128(pairs, _mm_shuffle_epi32::<0b10_11_00_01>(pairs));
            _mm_cvtsi128_si32(all) as u32
        }
    }
}
