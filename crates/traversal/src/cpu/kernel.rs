//! Single-ray CWBVH traversal for closest-hit and any-hit queries, driven by obvhs's
//! `traverse!` macro.

use glam::UVec2;
use obvhs::faststack::{FastStack, HeapStack};

use super::filter::HitFilter;
use super::geometry::LeafGeometry;
use super::node::NodeTest;
use super::ray::PreparedRay;
use super::triangle::{Candidate, TriangleTest};

/// A node group holding just the root: one hit bit in the top byte, which resolves to
/// relative index 0 (node 0) whatever the ray's octant.
const ROOT_GROUP: UVec2 = UVec2::new(0, 0x8000_0000);

/// Traversal state with the fields `traverse!` uses, and a stack as deep as the hierarchy
/// (obvhs's own state has a fixed 32-entry stack that degenerate inputs can overflow).
/// Reused across the rays of a chunk.
pub(crate) struct TraversalState {
    pub stack: HeapStack<UVec2>,
    pub current_group: UVec2,
    pub primitive_group: UVec2,
    pub oct_inv4: u32,
    pub primitive_id: u32,
    pub hitmask: u32,
}

impl TraversalState {
    /// State able to traverse `geometry`.
    pub fn new(geometry: &LeafGeometry) -> Self {
        Self {
            stack: HeapStack::new_with_capacity(geometry.levels.max(1)),
            current_group: UVec2::ZERO,
            primitive_group: UVec2::ZERO,
            oct_inv4: 0,
            primitive_id: 0,
            hitmask: 0,
        }
    }

    #[inline(always)]
    fn start(&mut self, geometry: &LeafGeometry, ray: &PreparedRay) {
        self.stack.clear();
        self.current_group = if geometry.bvh.nodes.is_empty() {
            UVec2::ZERO
        } else {
            ROOT_GROUP
        };
        self.primitive_group = UVec2::ZERO;
        self.oct_inv4 = ray.oct_inv4;
    }
}

/// Finds the closest accepted intersection in `[ray.tmin, ray.tmax)`, returning the leaf
/// index of its triangle.
#[inline(always)]
pub(crate) fn closest_hit<N: NodeTest + TriangleTest, F: HitFilter>(
    geometry: &LeafGeometry,
    node_test: N,
    filter: &F,
    state: &mut TraversalState,
    ray: &PreparedRay,
) -> Option<(usize, Candidate)> {
    let bvh = &geometry.bvh;
    state.start(geometry, ray);
    let mut node;
    let mut tmax = ray.tmax;
    let mut closest = None;
    obvhs::traverse!(
        bvh,
        node,
        state,
        node_test.intersect(node, ray, state.oct_inv4, tmax),
        {
            let (first, mask) = take_primitive_group(state);
            // Once something is hit, a candidate at exactly the same t wins only with a
            // smaller id, so ties resolve the same way whatever the traversal order.
            let limit = |closest: &Option<(usize, Candidate)>, tmax: f32| match closest {
                Some(_) => tmax.next_up(),
                None => tmax,
            };
            let group_limit = limit(&closest, tmax);
            node_test.candidates(
                &geometry.triangles,
                ray,
                first,
                mask,
                group_limit,
                |leaf, candidate| {
                    // The limit only shrinks while the group's candidates are taken in turn.
                    if candidate.t < limit(&closest, tmax)
                        && closest.is_none_or(|(best, _)| {
                            candidate.t < tmax || geometry.ids[leaf] < geometry.ids[best]
                        })
                        && filter.accepts(leaf, &candidate)
                    {
                        tmax = candidate.t;
                        closest = Some((leaf, candidate));
                    }
                    false
                },
            );
        }
    );
    closest
}

/// Whether any accepted intersection lies in `[ray.tmin, ray.tmax)`; stops at the first.
#[inline(always)]
pub(crate) fn any_hit<N: NodeTest + TriangleTest, F: HitFilter>(
    geometry: &LeafGeometry,
    node_test: N,
    filter: &F,
    state: &mut TraversalState,
    ray: &PreparedRay,
) -> bool {
    let bvh = &geometry.bvh;
    state.start(geometry, ray);
    let mut node;
    'search: {
        obvhs::traverse!(
            bvh,
            node,
            state,
            node_test.intersect(node, ray, state.oct_inv4, ray.tmax),
            {
                let (first, mask) = take_primitive_group(state);
                let accept = |leaf, candidate| filter.accepts(leaf, &candidate);
                if node_test.candidates(&geometry.triangles, ray, first, mask, ray.tmax, accept) {
                    break 'search true;
                }
            }
        );
        false
    }
}

/// The primitives left in the node's group, including the one `traverse!` just took: the
/// first leaf index and a bit per leaf after it. Empties the group, so that `traverse!` goes
/// on to the next node once they are all tested together.
#[inline(always)]
fn take_primitive_group(state: &mut TraversalState) -> (usize, u32) {
    let first = state.primitive_group.x;
    let mask = state.primitive_group.y | (1 << (state.primitive_id - first));
    state.primitive_group.y = 0;
    (first as usize, mask)
}
