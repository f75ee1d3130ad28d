//! Building the CWBVH and laying the triangles out in leaf order.

use glam::{Vec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    aabb::Aabb,
    bvh2::reinsertion::ReinsertionOptimizer,
    cwbvh::{CwBvh, bvh2_to_cwbvh::bvh2_to_cwbvh},
    ploc::PlocBuilder,
    splits::split_aabbs_preset,
    triangle::Triangle,
};

use super::BuildPreset;
use super::triangle::LeafTriangle;
use crate::error::BuildError;

/// A CWBVH whose leaves index `triangles` directly.
pub(crate) struct LeafGeometry {
    /// The hierarchy; its `primitive_indices` are moved into `ids`.
    pub bvh: CwBvh,
    /// Number of internal-node levels below the root: bounds the traversal stack.
    pub depth: usize,
    /// Triangles in leaf order (a triangle split by the builder appears once per leaf).
    pub triangles: Vec<LeafTriangle>,
    /// The caller's id of each leaf-order triangle.
    pub ids: Vec<u32>,
}

impl LeafGeometry {
    /// Validates the input and builds the hierarchy with `preset`.
    pub fn build(triangles: &[[Vec3; 3]], preset: BuildPreset) -> Result<Self, BuildError> {
        if triangles.len() >= u32::MAX as usize {
            return Err(BuildError::TooManyTriangles {
                count: triangles.len(),
            });
        }
        if let Some(triangle) = triangles
            .iter()
            .position(|t| !t.iter().all(|p| p.is_finite()))
        {
            return Err(BuildError::NonFiniteVertex { triangle });
        }
        let mut bvh = if triangles.is_empty() {
            CwBvh::default()
        } else {
            build_cwbvh(triangles, preset.params())
        };
        let ids = std::mem::take(&mut bvh.primitive_indices);
        let triangles = ids
            .iter()
            .map(|&id| LeafTriangle::new(triangles[id as usize]))
            .collect();
        Ok(Self {
            depth: depth(&bvh),
            bvh,
            triangles,
            ids,
        })
    }

    /// Bytes used by nodes, leaf triangles and the id map.
    pub fn memory_bytes(&self) -> usize {
        size_of_val(self.bvh.nodes.as_slice())
            + size_of_val(self.triangles.as_slice())
            + size_of_val(self.ids.as_slice())
    }
}

/// PLOC (optionally over pre-split boxes), reinsertion, then collapse to CWBVH.
fn build_cwbvh(triangles: &[[Vec3; 3]], params: BvhBuildParams) -> CwBvh {
    let mut boxes: Vec<Aabb> = triangles
        .iter()
        .map(|tri| Aabb::from_points(&tri.map(Vec3A::from)))
        .collect();
    let mut indices: Vec<u32> = (0..triangles.len() as u32).collect();
    if params.pre_split {
        let half_areas = boxes.iter().map(Aabb::half_area);
        let (largest, total) =
            half_areas.fold((0.0f32, 0.0f32), |(max, sum), a| (max.max(a), sum + a));
        let obvhs_triangles: Vec<Triangle> = triangles
            .iter()
            .map(|tri| {
                let [v0, v1, v2] = tri.map(Vec3A::from);
                Triangle { v0, v1, v2 }
            })
            .collect();
        let average = total / triangles.len() as f32;
        split_aabbs_preset(&mut boxes, &mut indices, &obvhs_triangles, average, largest);
    }
    break_ties(&mut boxes);
    let mut bvh2 = PlocBuilder::with_capacity(boxes.len()).build(
        params.ploc_search_distance,
        &boxes,
        indices,
        params.sort_precision,
        params.search_depth_threshold,
    );
    bvh2.uses_spatial_splits = params.pre_split;
    ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false)
}

/// Widens each of the six faces of every box by an independent pseudo-random fraction of up
/// to 2^-10 of the box's largest extent (2^-18 of its coordinates' magnitude if larger).
///
/// obvhs's PLOC pairs each cluster with the *last* of equally good neighbours, so many
/// identical boxes (duplicated geometry) never pair up mutually: the build degenerates into
/// a chain, quadratic in time and deep enough to overflow the stack. With independent
/// growth on all six faces, the union of two boxes rarely costs the same as another union,
/// so pairing works normally. Boxes only grow, so they still bound their triangles.
fn break_ties(boxes: &mut [Aabb]) {
    for (i, aabb) in boxes.iter_mut().enumerate() {
        let extent = (aabb.max - aabb.min).max_element() * 2f32.powi(-10);
        let magnitude = aabb.min.abs().max(aabb.max.abs()).max_element() * 2f32.powi(-18);
        let scale = extent.max(magnitude) * 2f32.powi(-24);
        let seed = (i as u32).wrapping_mul(6);
        let pad = |face: u32| (hash(seed.wrapping_add(face)) >> 8) as f32 * scale;
        aabb.min -= Vec3A::new(pad(0), pad(1), pad(2));
        aabb.max += Vec3A::new(pad(3), pad(4), pad(5));
    }
}

/// A 32-bit integer hash (lowbias32 by Chris Wellons).
fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// The number of internal-node levels below the root (0 for an empty or one-node tree).
fn depth(bvh: &CwBvh) -> usize {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut deepest = 0;
    let mut pending = vec![(0u32, 0usize)];
    while let Some((index, level)) = pending.pop() {
        deepest = deepest.max(level);
        let node = &bvh.nodes[index as usize];
        for child in (0..8).filter(|&c| !node.is_leaf(c)) {
            pending.push((node.child_node_index(child), level + 1));
        }
    }
    deepest
}
