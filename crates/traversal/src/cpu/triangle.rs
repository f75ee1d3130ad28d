//! Triangles in leaf order and the watertight ray/triangle test (Woop, Benthin, Wald 2013).
//!
//! Möller–Trumbore evaluates the edge shared by two triangles with different expressions in
//! each, so a ray through the edge can miss both. Here every vertex is transformed into a
//! ray-aligned frame independently of the triangle it belongs to and the edge functions are
//! 2D cross products of transformed vertices, so the two triangles sharing an edge compute
//! the same value with opposite signs and no ray slips between them.
//!
//! The triangles of one node's leaves are consecutive in leaf order and stored together
//! ([`LeafTriangles`]), so a node's hit leaves are tested together ([`TriangleTest`]): with
//! AVX2, eight triangles per instruction, with exactly the operations of the one-triangle
//! test (no fused multiply-adds), so both give bit-identical hits.

use glam::{DVec3, Vec3, Vec3A, Vec3Swizzles};

use super::node::Portable;
use super::ray::PreparedRay;

/// Padding after the last group of [`LeafTriangles`], so that eight-wide loads starting at
/// any of its triangles stay inside the buffer.
const PADDING: usize = 8;

/// Coordinates per triangle: three of each of its three vertices.
const COORDS: usize = 9;

/// The leaf triangles of one node: leaf-order triangles `first..first + count`, of which a
/// search tests triangle `first + k` for the set bits `k` of `mask`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LeafGroup {
    /// The group's first leaf-order triangle.
    pub first: usize,
    /// The group's triangle count.
    pub count: usize,
    /// A bit per triangle to test.
    pub mask: u32,
}

/// All leaf triangles, each node's group in a block of its own: the block of the group
/// `first..first + count` starts at coordinate `9·first` and holds nine coordinate planes of
/// `count` floats, plane `3·v + a` holding coordinate `a` of vertex `v` of the group's
/// triangles (36 bytes per triangle). A node's triangles thus lie in a few adjacent cache
/// lines, which one leaf visit reads whole, and eight-wide loads take one coordinate of
/// eight of them.
#[derive(Clone, Debug, Default)]
pub(crate) struct LeafTriangles {
    /// The number of triangles.
    len: usize,
    coords: Vec<f32>,
}

impl LeafTriangles {
    /// Lays out `triangles` (in leaf order) in the blocks of `groups`, `(first, count)` per
    /// node with leaves (no triangles: no memory).
    ///
    /// # Panics
    /// If the groups do not cover the triangles exactly once, in order (obvhs's CWBVH gives
    /// each node's leaves a range of its own, one after the other).
    pub fn new(triangles: &[[Vec3; 3]], groups: impl Iterator<Item = (usize, usize)>) -> Self {
        let len = triangles.len();
        let mut coords = vec![0.0; COORDS * len + if len == 0 { 0 } else { PADDING }];
        let mut groups: Vec<(usize, usize)> = groups.filter(|&(_, count)| count > 0).collect();
        groups.sort_unstable();
        let mut covered = 0;
        for (first, count) in groups {
            assert_eq!(
                first, covered,
                "leaf triangle groups overlap or leave a gap"
            );
            covered += count;
            let block = &mut coords[COORDS * first..COORDS * (first + count)];
            for (k, triangle) in triangles[first..first + count].iter().enumerate() {
                for (v, vertex) in triangle.iter().enumerate() {
                    for a in 0..3 {
                        block[(3 * v + a) * count + k] = vertex[a];
                    }
                }
            }
        }
        assert_eq!(covered, len, "leaf triangle groups leave triangles out");
        Self { len, coords }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Bytes of the blocks.
    pub fn memory_bytes(&self) -> usize {
        size_of_val(self.coords.as_slice())
    }

    /// Asks for the cache lines of the block of `group`.
    #[inline(always)]
    pub fn prefetch(&self, group: &LeafGroup) {
        let block = self.coords.as_ptr().wrapping_add(COORDS * group.first);
        // Sixteen floats per 64-byte line.
        for line in (0..COORDS * group.count).step_by(16) {
            super::geometry::prefetch(block.wrapping_add(line));
        }
        super::geometry::prefetch(block.wrapping_add(COORDS * group.count - 1));
    }

    /// Where coordinate `a` of vertex `v` of triangle `k` of `group` is in `coords`.
    #[inline(always)]
    fn index(group: &LeafGroup, v: usize, a: usize, k: usize) -> usize {
        COORDS * group.first + (3 * v + a) * group.count + k
    }

    /// Triangle `k` of `group`, transposed for the one-triangle test.
    #[inline(always)]
    pub fn get(&self, group: &LeafGroup, k: usize) -> LeafTriangle {
        let c = |v, a| self.coords[Self::index(group, v, a, k)];
        LeafTriangle {
            axes: [0, 1, 2].map(|a| Vec3A::new(c(0, a), c(1, a), c(2, a))),
        }
    }
}

/// Tests a ray against several leaf triangles at once.
pub(crate) trait TriangleTest: Copy {
    /// Tests the ray against the triangles of `group` its mask selects, and calls
    /// `found(leaf, candidate)` for each one it hits with t in `[ray.tmin, limit)`, in
    /// increasing leaf order, until `found` returns true. Returns whether it did.
    fn candidates(
        self,
        triangles: &LeafTriangles,
        ray: &PreparedRay,
        group: LeafGroup,
        limit: f32,
        found: impl FnMut(usize, Candidate) -> bool,
    ) -> bool;
}

impl TriangleTest for Portable {
    #[inline(always)]
    fn candidates(
        self,
        triangles: &LeafTriangles,
        ray: &PreparedRay,
        group: LeafGroup,
        limit: f32,
        mut found: impl FnMut(usize, Candidate) -> bool,
    ) -> bool {
        let mut mask = group.mask;
        while mask != 0 {
            let k = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            if let Some(candidate) = triangles.get(&group, k).intersect(ray, limit)
                && found(group.first + k, candidate)
            {
                return true;
            }
        }
        false
    }
}

/// A triangle stored transposed: `axes[a]` holds coordinate `a` of the three vertices
/// (lanes 0, 1, 2), so the test can fetch the permuted axes with one load each.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LeafTriangle {
    axes: [Vec3A; 3],
}

/// An accepted ray/triangle intersection before barycentrics are normalised.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Candidate {
    /// Ray parameter of the intersection.
    pub t: f32,
    /// Scaled barycentric weights of the second and third vertices.
    weights: [f32; 2],
    /// Normalisation: the sum of the three scaled weights.
    det: f32,
}

impl Candidate {
    /// Barycentrics `(u, v)`: hit point = `(1 − u − v)·p0 + u·p1 + v·p2`.
    #[inline(always)]
    pub fn barycentrics(&self) -> (f32, f32) {
        let inv_det = 1.0 / self.det;
        (self.weights[0] * inv_det, self.weights[1] * inv_det)
    }
}

impl LeafTriangle {
    /// Intersects the ray with the triangle, accepting `t` in `[ray.tmin, tmax)`.
    #[inline(always)]
    pub fn intersect(&self, ray: &PreparedRay, tmax: f32) -> Option<Candidate> {
        let [kx, ky, kz] = ray.axes;
        let [sx, sy, sz] = ray.shear;
        let [ox, oy, oz] = ray.origin_permuted;
        // Vertices relative to the origin in the permuted frame, then sheared onto +z.
        let z = self.axes[kz] - Vec3A::splat(oz);
        let x = self.axes[kx] - Vec3A::splat(ox) - Vec3A::splat(sx) * z;
        let y = self.axes[ky] - Vec3A::splat(oy) - Vec3A::splat(sy) * z;
        // Edge functions: lane 0 is the edge opposite p0, lane 1 opposite p1, lane 2 opposite p2.
        let mut edges = x.zxy() * y.yzx() - y.zxy() * x.yzx();
        if edges.cmpeq(Vec3A::ZERO).any() {
            edges = edges_f64(x, y);
        }
        let negative = edges.cmplt(Vec3A::ZERO).any();
        let positive = edges.cmpgt(Vec3A::ZERO).any();
        if negative && positive {
            return None;
        }
        let det = edges.x + edges.y + edges.z;
        if det == 0.0 {
            return None;
        }
        let t = edges.dot(z * sz) / det;
        (t >= ray.tmin && t < tmax).then_some(Candidate {
            t,
            weights: [edges.y, edges.z],
            det,
        })
    }
}

/// Recomputes the edge functions in double precision, where the products are exact; only
/// needed when a single-precision edge function is exactly zero (ray through an edge or
/// vertex) and its sign is therefore unreliable.
#[cold]
fn edges_f64(x: Vec3A, y: Vec3A) -> Vec3A {
    let (x, y) = (DVec3::from(Vec3::from(x)), DVec3::from(Vec3::from(y)));
    let edges = x.zxy() * y.yzx() - y.zxy() * x.yzx();
    edges.as_vec3().into()
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    use super::{Candidate, LeafGroup, LeafTriangles, TriangleTest};
    use crate::cpu::node::Avx2;
    use crate::cpu::ray::PreparedRay;

    /// Edge functions, determinant and t of eight consecutive triangles.
    struct Block {
        edges: [__m256; 3],
        det: __m256,
        t: __m256,
    }

    impl TriangleTest for Avx2 {
        // Not a `#[target_feature]` function, so that it inlines into the AVX2 chunk loops.
        #[inline(always)]
        fn candidates(
            self,
            triangles: &LeafTriangles,
            ray: &PreparedRay,
            group: LeafGroup,
            limit: f32,
            mut found: impl FnMut(usize, Candidate) -> bool,
        ) -> bool {
            let mut mask = group.mask;
            while mask != 0 {
                let offset = mask.trailing_zeros();
                let start = offset as usize;
                let lanes = (mask >> offset) & 0xff;
                mask &= !(0xff << offset);
                // SAFETY: `Avx2` values only exist when the CPU supports AVX2 and FMA; the
                // block's loads stay inside the padded buffer (`start` < the group's count).
                let (block, accepted, degenerate) =
                    unsafe { test_block(triangles, ray, (&group, start), limit) };
                let mut hits = (accepted | degenerate) & lanes;
                if hits == 0 {
                    continue;
                }
                // SAFETY: as above, the CPU supports AVX2.
                let (t, e1, e2, det) = unsafe {
                    (
                        lanes_of(block.t),
                        lanes_of(block.edges[1]),
                        lanes_of(block.edges[2]),
                        lanes_of(block.det),
                    )
                };
                while hits != 0 {
                    let lane = hits.trailing_zeros() as usize;
                    hits &= hits - 1;
                    let leaf = group.first + start + lane;
                    // A zero edge function needs the double-precision sign of the scalar test.
                    let candidate = if degenerate & (1 << lane) != 0 {
                        triangles.get(&group, start + lane).intersect(ray, limit)
                    } else {
                        Some(Candidate {
                            t: t[lane],
                            weights: [e1[lane], e2[lane]],
                            det: det[lane],
                        })
                    };
                    if let Some(candidate) = candidate
                        && found(leaf, candidate)
                    {
                        return true;
                    }
                }
            }
            false
        }
    }

    /// The watertight test of triangles `start..start + 8` of `group`, operation for operation as
    /// [`LeafTriangle::intersect`](super::LeafTriangle::intersect): the block, the lanes
    /// that hit with t in `[ray.tmin, limit)`, and the lanes with a zero edge function
    /// (left to the scalar test).
    ///
    /// # Safety
    /// The CPU must support AVX2, and `start` must be below the group's count.
    #[inline(always)]
    unsafe fn test_block(
        triangles: &LeafTriangles,
        ray: &PreparedRay,
        (group, start): (&LeafGroup, usize),
        limit: f32,
    ) -> (Block, u32, u32) {
        // SAFETY: the caller guarantees AVX2; eight floats from any coordinate of the
        // group's triangles stay within the padded buffer.
        unsafe {
            let [sx, sy, sz] = ray.shear.map(|s| _mm256_set1_ps(s));
            let [ox, oy, oz] = ray.origin_permuted.map(|o| _mm256_set1_ps(o));
            let [kx, ky, kz] = ray.axes;
            // Unchecked loads: a checked slice per load put a bounds check on every load of
            // the hot loop.
            debug_assert!(LeafTriangles::index(group, 2, 2, start) + 8 <= triangles.coords.len());
            let coords = triangles.coords.as_ptr();
            let load = |vertex: usize, axis: usize| {
                _mm256_loadu_ps(coords.add(LeafTriangles::index(group, vertex, axis, start)))
            };
            let mut x = [_mm256_setzero_ps(); 3];
            let mut y = [_mm256_setzero_ps(); 3];
            let mut z = [_mm256_setzero_ps(); 3];
            for v in 0..3 {
                z[v] = _mm256_sub_ps(load(v, kz), oz);
                x[v] = _mm256_sub_ps(_mm256_sub_ps(load(v, kx), ox), _mm256_mul_ps(sx, z[v]));
                y[v] = _mm256_sub_ps(_mm256_sub_ps(load(v, ky), oy), _mm256_mul_ps(sy, z[v]));
            }
            let cross = |a: usize, b: usize| {
                _mm256_sub_ps(_mm256_mul_ps(x[a], y[b]), _mm256_mul_ps(y[a], x[b]))
            };
            // Edge opposite vertex 0, 1, 2, as the scalar test's lanes.
            let edges = [cross(2, 1), cross(0, 2), cross(1, 0)];
            let zero = _mm256_setzero_ps();
            let any = |f: &dyn Fn(__m256) -> __m256| {
                _mm256_or_ps(_mm256_or_ps(f(edges[0]), f(edges[1])), f(edges[2]))
            };
            let degenerate = any(&|e| _mm256_cmp_ps::<_CMP_EQ_OQ>(e, zero));
            let negative = any(&|e| _mm256_cmp_ps::<_CMP_LT_OQ>(e, zero));
            let positive = any(&|e| _mm256_cmp_ps::<_CMP_GT_OQ>(e, zero));
            let det = _mm256_add_ps(_mm256_add_ps(edges[0], edges[1]), edges[2]);
            let dot = _mm256_add_ps(
                _mm256_add_ps(
                    _mm256_mul_ps(edges[0], _mm256_mul_ps(z[0], sz)),
                    _mm256_mul_ps(edges[1], _mm256_mul_ps(z[1], sz)),
                ),
                _mm256_mul_ps(edges[2], _mm256_mul_ps(z[2], sz)),
            );
            let t = _mm256_div_ps(dot, det);
            let in_range = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GE_OQ>(t, _mm256_set1_ps(ray.tmin)),
                _mm256_cmp_ps::<_CMP_LT_OQ>(t, _mm256_set1_ps(limit)),
            );
            let rejected = _mm256_or_ps(
                _mm256_or_ps(_mm256_and_ps(negative, positive), degenerate),
                _mm256_cmp_ps::<_CMP_EQ_OQ>(det, zero),
            );
            let accepted = _mm256_andnot_ps(rejected, in_range);
            (
                Block { edges, det, t },
                _mm256_movemask_ps(accepted) as u32,
                _mm256_movemask_ps(degenerate) as u32,
            )
        }
    }

    /// The eight lanes of `v`.
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[inline(always)]
    unsafe fn lanes_of(v: __m256) -> [f32; 8] {
        let mut out = [0.0; 8];
        // SAFETY: the caller guarantees AVX; `out` holds eight floats.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), v) };
        out
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3A;

    use super::LeafGroup;
    use crate::build::BuildPreset;
    use crate::cpu::geometry::{LeafGeometry, small_triangle_soup};

    #[test]
    fn every_node_reads_back_its_own_leaf_triangles() {
        let triangles = small_triangle_soup(3000, 11);
        for preset in [
            BuildPreset::Fastest,
            BuildPreset::Fast,
            BuildPreset::VerySlow,
        ] {
            let geometry = LeafGeometry::build(&triangles, preset).unwrap();
            let mut read = 0;
            for node in geometry.nodes.iter().filter(|node| node.triangle_count > 0) {
                let group = LeafGroup {
                    first: node.first_triangle as usize,
                    count: node.triangle_count as usize,
                    mask: 0,
                };
                for k in 0..group.count {
                    let original = triangles[geometry.ids[group.first + k] as usize];
                    let axes = geometry.triangles.get(&group, k).axes;
                    for (a, axis) in axes.iter().enumerate() {
                        let expected = Vec3A::from(original.map(|vertex| vertex[a]));
                        assert_eq!(*axis, expected, "{preset:?}, leaf {}", group.first + k);
                    }
                }
                read += group.count;
            }
            assert_eq!(read, geometry.triangles.len());
        }
    }
}
