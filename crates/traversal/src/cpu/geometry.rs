//! Building the hierarchy and laying the triangles out in leaf order.

use glam::Vec3;
use obvhs::cwbvh::{CwBvh, bvh2_to_cwbvh::bvh2_to_cwbvh};

use super::triangle::LeafTriangles;
use super::wide_node::{WideNode, wide_nodes};
use crate::build::{BuildPreset, build_bvh2, cwbvh_levels};
use crate::error::BuildError;

/// An 8-wide hierarchy whose leaves index `triangles` directly.
pub(crate) struct LeafGeometry {
    /// The nodes, root first (none without triangles).
    pub nodes: Vec<WideNode>,
    /// Node levels, root included: bounds the traversal stack.
    pub levels: usize,
    /// Triangles in leaf order (a triangle split by the builder appears once per leaf).
    pub triangles: LeafTriangles,
    /// The caller's id of each leaf-order triangle.
    pub ids: Vec<u32>,
}

impl LeafGeometry {
    /// Validates the input and builds the hierarchy with `preset`.
    pub fn build(triangles: &[[Vec3; 3]], preset: BuildPreset) -> Result<Self, BuildError> {
        let bvh2 = build_bvh2(triangles, preset)?;
        let mut bvh = if triangles.is_empty() {
            CwBvh::default()
        } else {
            let leaf_size = preset
                .params(triangles.len())
                .max_prims_per_leaf
                .clamp(1, 3);
            bvh2_to_cwbvh(&bvh2, leaf_size, true, false)
        };
        let ids = std::mem::take(&mut bvh.primitive_indices);
        let leaf_order: Vec<[Vec3; 3]> = ids.iter().map(|&id| triangles[id as usize]).collect();
        let nodes = wide_nodes(&bvh, &leaf_order);
        let groups = nodes
            .iter()
            .map(|node| (node.first_triangle as usize, node.triangle_count as usize));
        Ok(Self {
            levels: cwbvh_levels(&bvh),
            triangles: LeafTriangles::new(&leaf_order, groups),
            nodes,
            ids,
        })
    }

    /// Asks for the cache lines of node `index` (256 bytes: four lines).
    #[inline(always)]
    pub fn prefetch_node(&self, index: usize) {
        let node = self.nodes.as_ptr().wrapping_add(index).cast::<u8>();
        for line in 0..size_of::<WideNode>() / 64 {
            prefetch(node.wrapping_add(64 * line));
        }
    }

    /// Bytes used by nodes, leaf triangles and the id map.
    pub fn memory_bytes(&self) -> usize {
        size_of_val(self.nodes.as_slice())
            + self.triangles.memory_bytes()
            + size_of_val(self.ids.as_slice())
    }
}

/// Asks the CPU to bring the cache line holding `address` closer (a hint: never faults,
/// whatever the address; nothing on targets without a prefetch instruction here).
#[inline(always)]
pub(crate) fn prefetch<T>(address: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch reads nothing and cannot fault.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(address.cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = address;
}

/// A reproducible soup of `count` small triangles in the unit cube, for tests of the layout.
#[cfg(test)]
pub(crate) fn small_triangle_soup(count: usize, seed: u32) -> Vec<[Vec3; 3]> {
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (state >> 8) as f32 / (1 << 24) as f32
    };
    (0..count)
        .map(|_| {
            let corner = Vec3::new(next(), next(), next());
            [0, 1, 2].map(|_| corner + 0.05 * Vec3::new(next(), next(), next()))
        })
        .collect()
}
