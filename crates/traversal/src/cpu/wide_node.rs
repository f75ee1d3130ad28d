//! The node layout the CPU traverses: obvhs's CWBVH topology with its quantised child
//! boxes replaced by exact ones in single precision, eight children per node.
//!
//! A CWBVH node (80 bytes) stores its child boxes as 8-bit offsets on a per-node grid, which
//! a ray must first be transformed into, and its children in an octant-dependent order that
//! takes bit tricks to resolve. A [`WideNode`] (256 bytes) holds the planes of its eight
//! child boxes as floats, ready for one 8-wide slab test, and each child's node index or leaf
//! triangles directly.

use glam::{Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;

/// Marks a [`WideNode::children`] entry as leaf triangles rather than a node index.
pub(crate) const LEAF: u32 = 1 << 31;

/// Eight child boxes and what each one holds.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct WideNode {
    /// Child box planes, per slot: `planes[2·axis]` the minimum along `axis`,
    /// `planes[2·axis + 1]` the maximum. An empty slot holds an inverted box (minimum +∞,
    /// maximum −∞), which no ray overlaps.
    pub planes: [[f32; 8]; 6],
    /// Per slot: an internal child's node index, or [`LEAF`] with a bit per leaf triangle
    /// `first_triangle + k` in the low 24 bits. Zero for an empty slot.
    pub children: [u32; 8],
    /// The first leaf triangle of the node's leaf children.
    pub first_triangle: u32,
    /// How many leaf triangles its leaf children hold, from `first_triangle` on: the size of
    /// its block of [`LeafTriangles`](super::triangle::LeafTriangles).
    pub triangle_count: u32,
}

impl WideNode {
    /// A node with eight empty slots.
    const EMPTY: Self = Self {
        planes: [
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
        ],
        children: [0; 8],
        first_triangle: 0,
        triangle_count: 0,
    };

    /// Fills `slot` with `bounds` holding `child`.
    fn set(&mut self, slot: usize, bounds: &Aabb, child: u32) {
        for axis in 0..3 {
            self.planes[2 * axis][slot] = bounds.min[axis];
            self.planes[2 * axis + 1][slot] = bounds.max[axis];
        }
        self.children[slot] = child;
    }
}

/// The nodes of `bvh` (whose leaves index `triangles`, in leaf order) with exact child
/// boxes: a leaf child's box bounds its triangles, an internal child's box bounds its own
/// children.
///
/// # Panics
/// If a node's children are stored before it (obvhs lays nodes out top-down).
pub(crate) fn wide_nodes(bvh: &CwBvh, triangles: &[[Vec3; 3]]) -> Vec<WideNode> {
    let mut nodes = vec![WideNode::EMPTY; bvh.nodes.len()];
    let mut bounds = vec![Aabb::empty(); bvh.nodes.len()];
    // Children come after their parent, so bottom-up is back to front.
    for index in (0..bvh.nodes.len()).rev() {
        let compressed = &bvh.nodes[index];
        let node = &mut nodes[index];
        node.first_triangle = compressed.primitive_base_idx;
        let mut node_bounds = Aabb::empty();
        for slot in (0..8).filter(|&slot| !compressed.is_child_empty(slot)) {
            let (child, child_bounds) = if compressed.is_leaf(slot) {
                let (first, count) = compressed.child_primitives(slot);
                let offset = first - compressed.primitive_base_idx;
                let leaves =
                    (first..first + count).map(|leaf| triangle_bounds(&triangles[leaf as usize]));
                let bits = ((1 << count) - 1) << offset;
                node.triangle_count = node.triangle_count.max(offset + count);
                (LEAF | bits, leaves.fold(Aabb::empty(), |a, b| a.union(&b)))
            } else {
                let child = compressed.child_node_index(slot);
                assert!(
                    child as usize > index,
                    "CWBVH node {child} precedes its parent"
                );
                (child, bounds[child as usize])
            };
            node.set(slot, &child_bounds, child);
            node_bounds = node_bounds.union(&child_bounds);
        }
        bounds[index] = node_bounds;
    }
    nodes
}

/// The bounding box of `triangle`.
fn triangle_bounds(triangle: &[Vec3; 3]) -> Aabb {
    let [a, b, c] = triangle.map(Vec3A::from);
    Aabb::new(a.min(b).min(c), a.max(b).max(c))
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use obvhs::aabb::Aabb;

    use super::{LEAF, WideNode};
    use crate::build::BuildPreset;
    use crate::cpu::geometry::{LeafGeometry, small_triangle_soup};

    /// The leaf triangles below `child`, an entry of `node.children`.
    fn leaves_below(nodes: &[WideNode], node: &WideNode, child: u32, out: &mut Vec<usize>) {
        if child & LEAF != 0 {
            let bits = child & !LEAF;
            let first = node.first_triangle as usize;
            out.extend((0..24).filter(|k| bits & (1 << k) != 0).map(|k| first + k));
        } else {
            let node = &nodes[child as usize];
            for &grandchild in node.children.iter().filter(|&&c| c != 0) {
                leaves_below(nodes, node, grandchild, out);
            }
        }
    }

    fn slot_bounds(node: &WideNode, slot: usize) -> Aabb {
        let plane = |index: usize| node.planes[index][slot];
        Aabb::new(
            Vec3::new(plane(0), plane(2), plane(4)).into(),
            Vec3::new(plane(1), plane(3), plane(5)).into(),
        )
    }

    #[test]
    fn every_child_box_is_the_exact_bound_of_the_triangles_below_it() {
        let triangles = small_triangle_soup(2000, 7);
        for preset in [BuildPreset::Fastest, BuildPreset::Fast] {
            let geometry = LeafGeometry::build(&triangles, preset).unwrap();
            let nodes = &geometry.nodes;
            assert!(nodes.len() > 1);
            for node in nodes {
                for slot in 0..8 {
                    let bounds = slot_bounds(node, slot);
                    if node.children[slot] == 0 {
                        assert!(bounds.min.cmpgt(bounds.max).all(), "empty slot {bounds:?}");
                        continue;
                    }
                    let mut below = Vec::new();
                    leaves_below(nodes, node, node.children[slot], &mut below);
                    let exact = below
                        .iter()
                        .map(|&leaf| {
                            super::triangle_bounds(&triangles[geometry.ids[leaf] as usize])
                        })
                        .fold(Aabb::empty(), |a, b| a.union(&b));
                    assert_eq!(bounds, exact);
                }
            }
            // Every leaf triangle hangs below the root exactly once.
            let mut all = Vec::new();
            for &child in nodes[0].children.iter().filter(|&&c| c != 0) {
                leaves_below(nodes, &nodes[0], child, &mut all);
            }
            all.sort_unstable();
            assert!(all.iter().copied().eq(0..geometry.triangles.len()));
        }
    }
}
