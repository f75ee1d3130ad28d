//! The hierarchy every backend starts from: validated triangles, obvhs's PLOC build and
//! reinsertion, giving a binary BVH that each backend lays out its own way.

use glam::{Vec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    aabb::Aabb,
    bvh2::{Bvh2, reinsertion::ReinsertionOptimizer},
    cwbvh::CwBvh,
    ploc::PlocBuilder,
    splits::split_aabbs_preset,
    triangle::Triangle,
};

use crate::error::BuildError;

/// obvhs build quality presets, from fastest build to best hierarchy, and `Auto`.
///
/// `Slow` and `VerySlow` split large triangles' boxes before building (a triangle may then be
/// stored in several leaves).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BuildPreset {
    /// The best hierarchy (`VerySlow`) for scenes of up to [`BEST_BUILD_UP_TO`] triangles,
    /// where its build stays short, and `Fast` above. The default.
    #[default]
    Auto,
    /// No reinsertion, one primitive per leaf.
    Fastest,
    /// Minimal search radius, light reinsertion.
    VeryFast,
    /// Small search radius, light reinsertion. On a 1M-triangle scene its hierarchy costs the
    /// same node and triangle tests per ray as `Medium`'s (within 0.5%) and builds 10–15%
    /// faster.
    Fast,
    /// Medium search radius, more reinsertion.
    Medium,
    /// Spatial pre-splits, large search radius.
    Slow,
    /// Spatial pre-splits, full reinsertion.
    VerySlow,
}

/// Triangles up to which [`BuildPreset::Auto`] builds with `VerySlow`. Its pre-splits and
/// full reinsertion pass take 2–3.5 times as long as `Fast`'s build (2.1× at 10k triangles,
/// 3.4× at 100k; ~2.6 µs per triangle on 2 cores here: ~0.17 s at this size, against a
/// render of seconds), and it gives hierarchies that cost fewer triangle tests per ray: on
/// the Cornell box 2.55 instead of 3.66 (0.86 leaf visits instead of 1.21), the same hits.
pub const BEST_BUILD_UP_TO: usize = 1 << 16;

impl BuildPreset {
    /// The obvhs parameters of this preset for a scene of `triangles` triangles (only `Auto`
    /// depends on the count).
    pub fn params(self, triangles: usize) -> BvhBuildParams {
        match self {
            Self::Auto if triangles <= BEST_BUILD_UP_TO => BvhBuildParams::very_slow_build(),
            Self::Auto => BvhBuildParams::fast_build(),
            Self::Fastest => BvhBuildParams::fastest_build(),
            Self::VeryFast => BvhBuildParams::very_fast_build(),
            Self::Fast => BvhBuildParams::fast_build(),
            Self::Medium => BvhBuildParams::medium_build(),
            Self::Slow => BvhBuildParams::slow_build(),
            Self::VerySlow => BvhBuildParams::very_slow_build(),
        }
    }
}

/// Validates `triangles` and builds their binary BVH with `preset`.
///
/// Leaves index `bvh.primitive_indices`, whose entries are indices into `triangles`. Fails if
/// a vertex is not finite or there are `u32::MAX` triangles or more; an empty slice gives an
/// empty hierarchy (no nodes).
pub fn build_bvh2(triangles: &[[Vec3; 3]], preset: BuildPreset) -> Result<Bvh2, BuildError> {
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
    if triangles.is_empty() {
        return Ok(Bvh2::default());
    }
    Ok(optimized_bvh2(triangles, preset.params(triangles.len())))
}

/// PLOC (optionally over pre-split boxes), then reinsertion.
fn optimized_bvh2(triangles: &[[Vec3; 3]], params: BvhBuildParams) -> Bvh2 {
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
    bvh2
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

/// The number of node levels of a compressed wide BVH, root included (0 when empty): a
/// traversal that pushes at most one node group per level needs no deeper stack.
pub fn cwbvh_levels(bvh: &CwBvh) -> usize {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut deepest = 0;
    let mut pending = vec![(0u32, 1usize)];
    while let Some((index, level)) = pending.pop() {
        deepest = deepest.max(level);
        let node = &bvh.nodes[index as usize];
        for child in (0..8).filter(|&c| !node.is_leaf(c)) {
            pending.push((node.child_node_index(child), level + 1));
        }
    }
    deepest
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parameters that tell the presets apart.
    fn key(params: BvhBuildParams) -> (bool, f32) {
        (params.pre_split, params.reinsertion_batch_ratio)
    }

    #[test]
    fn auto_builds_the_best_hierarchy_up_to_its_limit_only() {
        let (best, fast) = (BuildPreset::VerySlow.params(0), BuildPreset::Fast.params(0));
        assert_ne!(key(best), key(fast));
        for triangles in [1, BEST_BUILD_UP_TO] {
            assert_eq!(key(BuildPreset::Auto.params(triangles)), key(best));
        }
        assert_eq!(
            key(BuildPreset::Auto.params(BEST_BUILD_UP_TO + 1)),
            key(fast)
        );
    }
}
