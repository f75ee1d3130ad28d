//! Ray tests against the eight quantised child boxes of a CWBVH node.
//!
//! Child boxes are stored as 8-bit offsets on a per-node grid (origin `p`, cell size `e`
//! per axis). The slab distance of plane `q` is `q · (e / d) + (p − o) / d`. Both terms are
//! rounded, and obvhs rounds the grid coordinates of a child once before flooring them, so
//! each distance is widened by a bound on those errors: a few ulps of the largest term. That
//! keeps geometry lying exactly on a box face (axis-aligned walls, cube corners) from being
//! culled by a one-ulp miss.

use glam::{Vec3A, Vec4};
use obvhs::cwbvh::node::CwBvhNode;

use super::ray::PreparedRay;

/// Relative error bound on a slab distance, in units of its largest term.
const SLAB_SLACK: f32 = 8.0 * f32::EPSILON;

/// Intersects a ray with the children of a node.
pub(crate) trait NodeTest: Copy {
    /// Returns obvhs's hit mask for the children whose boxes the ray overlaps within
    /// `[ray.tmin, tmax]`: internal children in the top byte (in traversal order for
    /// octant `oct_inv4`), leaf primitives in the low 24 bits.
    fn intersect(self, node: &CwBvhNode, ray: &PreparedRay, oct_inv4: u32, tmax: f32) -> u32;
}

/// The ray transformed into a node's grid: slab distance of grid plane `q` along an axis is
/// `q · scale + near` for the entry plane and `q · scale + far` for the exit plane.
struct NodeFrame {
    scale: Vec3A,
    near: Vec3A,
    far: Vec3A,
}

impl NodeFrame {
    #[inline(always)]
    fn new(node: &CwBvhNode, ray: &PreparedRay) -> Self {
        let extent = node.compute_extent();
        let offset = Vec3A::from(node.p) - ray.origin;
        let base = offset * ray.inv_dir;
        let slack = (offset.abs() + extent * 255.0) * ray.inv_dir.abs() * SLAB_SLACK;
        Self {
            scale: extent * ray.inv_dir,
            near: base - slack,
            far: base + slack,
        }
    }
}

/// The grid planes a ray enters and exits each child through along one axis.
#[inline(always)]
fn entry_exit_planes<'n>(
    node: &'n CwBvhNode,
    ray: &PreparedRay,
    axis: usize,
) -> (&'n [u8; 8], &'n [u8; 8]) {
    let (min, max) = match axis {
        0 => (&node.child_min_x, &node.child_max_x),
        1 => (&node.child_min_y, &node.child_max_y),
        _ => (&node.child_min_z, &node.child_max_z),
    };
    if ray.negative[axis] {
        (max, min)
    } else {
        (min, max)
    }
}

/// Turns a mask of overlapped child slots into obvhs's traversal hit mask.
#[inline(always)]
fn hit_mask(node: &CwBvhNode, oct_inv4: u32, mut slots: u32) -> u32 {
    let (child_bits, bit_index) = node.get_child_and_index_bits(oct_inv4);
    let mut mask = 0;
    while slots != 0 {
        let shift = slots.trailing_zeros() * 8;
        slots &= slots - 1;
        mask |= ((child_bits >> shift) as u32 & 0xff) << ((bit_index >> shift) as u32 & 0xff);
    }
    mask
}

/// Four children at a time with 4-wide vectors; works on every target.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable;

impl NodeTest for Portable {
    #[inline(always)]
    fn intersect(self, node: &CwBvhNode, ray: &PreparedRay, oct_inv4: u32, tmax: f32) -> u32 {
        let frame = NodeFrame::new(node, ray);
        let planes = [0, 1, 2].map(|axis| entry_exit_planes(node, ray, axis));
        let mut slots = 0;
        for half in 0..2 {
            let mut entry = Vec4::splat(ray.tmin);
            let mut exit = Vec4::splat(tmax);
            for (axis, (near, far)) in planes.iter().enumerate() {
                let scale = Vec4::splat(frame.scale[axis]);
                entry = entry.max(quads(near, half) * scale + Vec4::splat(frame.near[axis]));
                exit = exit.min(quads(far, half) * scale + Vec4::splat(frame.far[axis]));
            }
            slots |= entry.cmple(exit).bitmask() << (half * 4);
        }
        hit_mask(node, oct_inv4, slots)
    }
}

#[inline(always)]
fn quads(bytes: &[u8; 8], half: usize) -> Vec4 {
    let b = &bytes[half * 4..half * 4 + 4];
    Vec4::new(b[0] as f32, b[1] as f32, b[2] as f32, b[3] as f32)
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx2::Avx2;

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    use obvhs::cwbvh::node::CwBvhNode;

    use super::{NodeFrame, NodeTest, entry_exit_planes};
    use crate::cpu::ray::PreparedRay;

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
        fn intersect(self, node: &CwBvhNode, ray: &PreparedRay, oct_inv4: u32, tmax: f32) -> u32 {
            let frame = NodeFrame::new(node, ray);
            // SAFETY: `Avx2` values only exist when the CPU supports AVX2 and FMA.
            unsafe {
                let mut entry = _mm256_set1_ps(ray.tmin);
                let mut exit = _mm256_set1_ps(tmax);
                for axis in 0..3 {
                    let (near, far) = entry_exit_planes(node, ray, axis);
                    let scale = _mm256_set1_ps(frame.scale[axis]);
                    let near_t =
                        _mm256_fmadd_ps(octs(near), scale, _mm256_set1_ps(frame.near[axis]));
                    let far_t = _mm256_fmadd_ps(octs(far), scale, _mm256_set1_ps(frame.far[axis]));
                    entry = _mm256_max_ps(entry, near_t);
                    exit = _mm256_min_ps(exit, far_t);
                }
                let overlapped = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LE_OQ>(entry, exit));
                traversal_mask(node, oct_inv4, overlapped)
            }
        }
    }

    /// Branch-free equivalent of [`hit_mask`](super::hit_mask) for a lane mask of
    /// overlapped slots: every lane shifts its child bits into place, then the lanes are
    /// OR-reduced.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[inline(always)]
    unsafe fn traversal_mask(node: &CwBvhNode, oct_inv4: u32, overlapped: __m256i) -> u32 {
        // SAFETY: the caller guarantees AVX2.
        unsafe {
            let meta = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(i64::from_le_bytes(node.child_meta)));
            // Internal children have offsets 24..32: both bits 3 and 4 set.
            let inner_bits = _mm256_set1_epi32(0b1_1000);
            let inner = _mm256_cmpeq_epi32(_mm256_and_si256(meta, inner_bits), inner_bits);
            let octant = _mm256_and_si256(_mm256_set1_epi32((oct_inv4 & 0xff) as i32), inner);
            let bit_index =
                _mm256_and_si256(_mm256_xor_si256(meta, octant), _mm256_set1_epi32(0b1_1111));
            let child_bits =
                _mm256_and_si256(_mm256_srli_epi32::<5>(meta), _mm256_set1_epi32(0b111));
            let lanes = _mm256_and_si256(_mm256_sllv_epi32(child_bits, bit_index), overlapped);
            let halves = _mm_or_si128(
                _mm256_castsi256_si128(lanes),
                _mm256_extracti128_si256::<1>(lanes),
            );
            let pairs = _mm_or_si128(halves, _mm_shuffle_epi32::<0b01_00_11_10>(halves));
            let all = _mm_or_si128(pairs, _mm_shuffle_epi32::<0b10_11_00_01>(pairs));
            _mm_cvtsi128_si32(all) as u32
        }
    }

    /// Converts eight grid coordinates to floats.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[inline(always)]
    unsafe fn octs(bytes: &[u8; 8]) -> __m256 {
        // SAFETY: the caller guarantees AVX2.
        unsafe {
            let packed = _mm_cvtsi64_si128(i64::from_le_bytes(*bytes));
            _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(packed))
        }
    }
}
