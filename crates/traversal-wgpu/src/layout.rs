//! GPU layouts of the hierarchy: the node array, triangles in leaf order and the map from
//! leaf order back to the caller's triangle ids.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use vcm_traversal::build::cwbvh_levels;

/// 32-bit words of one node of the wide layout.
const WIDE_NODE_WORDS: usize = 20;

/// The node formats the kernels can traverse.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum NodeLayout {
    /// Binary nodes of 64 bytes holding both children's boxes ([`Bvh2Node`],
    /// `traverse_bvh2.wgsl`).
    Binary,
    /// obvhs's compressed 8-wide nodes of 80 bytes (`traverse_cwbvh.wgsl`), the layout of
    /// the CPU backend and of Ylitie et al. 2017. The default: on lavapipe it traces 1.8–2.1×
    /// more rays/s than the binary layout (README, traversal benchmark) in half the memory.
    #[default]
    Wide,
}
/// A binary BVH node that holds the boxes of both children, so one 64-byte fetch decides
/// which children a ray enters (Aila and Laine 2009).
///
/// A child with `count == 0` is the inner node `nodes[index]`; one with `count > 0` is a leaf
/// of the `count` triangles starting at leaf-order position `index`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct Bvh2Node {
    /// Left child box minimum.
    pub left_min: [f32; 3],
    /// Left child node or first triangle.
    pub left_index: u32,
    /// Left child box maximum.
    pub left_max: [f32; 3],
    /// Right child node or first triangle.
    pub right_index: u32,
    /// Right child box minimum.
    pub right_min: [f32; 3],
    /// Left child triangle count (0 for an inner node).
    pub left_count: u32,
    /// Right child box maximum.
    pub right_max: [f32; 3],
    /// Right child triangle count (0 for an inner node).
    pub right_count: u32,
}

/// Everything the traversal kernels read, ready to upload.
#[derive(Clone, Debug, Default)]
pub struct SceneLayout {
    /// The node format.
    pub layout: NodeLayout,
    /// Nodes, root first, as 32-bit words.
    pub nodes: Vec<u32>,
    /// Triangle vertices in leaf order, three `[x, y, z, 0]` entries per triangle.
    pub vertices: Vec<[f32; 4]>,
    /// The caller's id of each leaf-order triangle.
    pub ids: Vec<u32>,
    /// The most entries a traversal stack can hold (the number of inner-node levels).
    pub stack_size: u32,
}

impl SceneLayout {
    /// Lays out `bvh` (built over `triangles`) in `layout`; `leaf_size` bounds the
    /// triangles per wide leaf (1 to 3).
    pub fn new(bvh: &Bvh2, triangles: &[[Vec3; 3]], layout: NodeLayout, leaf_size: u32) -> Self {
        match layout {
            NodeLayout::Binary => {
                let (nodes, stack_size) = binary_nodes(bvh);
                Self::with_leaf_order(
                    layout,
                    bytemuck::cast_slice(&nodes).to_vec(),
                    &bvh.primitive_indices,
                    triangles,
                    stack_size,
                )
            }
            NodeLayout::Wide if bvh.nodes.is_empty() => Self::default(),
            NodeLayout::Wide => {
                let wide = bvh2_to_cwbvh(bvh, leaf_size.clamp(1, 3), true, false);
                let stack_size = cwbvh_levels(&wide) as u32 + 1;
                Self::with_leaf_order(
                    layout,
                    bytemuck::cast_slice(&wide.nodes).to_vec(),
                    &wide.primitive_indices,
                    triangles,
                    stack_size,
                )
            }
        }
    }

    fn with_leaf_order(
        layout: NodeLayout,
        nodes: Vec<u32>,
        ids: &[u32],
        triangles: &[[Vec3; 3]],
        stack_size: u32,
    ) -> Self {
        let vertices = ids
            .iter()
            .flat_map(|&id| triangles[id as usize].map(|p| [p.x, p.y, p.z, 0.0]))
            .collect();
        Self {
            layout,
            nodes,
            vertices,
            ids: ids.to_vec(),
            stack_size,
        }
    }

    /// Whether every index the kernels derive from the nodes stays inside its buffer and
    /// every path from the root fits the traversal stack: inner children within the node
    /// array, leaf triangles within the triangle and id arrays, and no path deeper than
    /// [`stack_size`](Self::stack_size). The host checks this before it drops the kernels'
    /// run-time bounds checks.
    pub fn indices_in_bounds(&self) -> bool {
        match self.layout {
            NodeLayout::Binary => self.binary_in_bounds(),
            NodeLayout::Wide => self.wide_in_bounds(),
        }
    }

    fn binary_in_bounds(&self) -> bool {
        let nodes: &[Bvh2Node] = bytemuck::cast_slice(&self.nodes);
        let triangles = self.ids.len() as u64;
        let mut pending = vec![(0usize, 1u32)];
        while let Some((index, level)) = pending.pop() {
            let Some(node) = nodes.get(index) else {
                return nodes.is_empty() && index == 0;
            };
            if level > self.stack_size {
                return false;
            }
            for (child, count) in [
                (node.left_index, node.left_count),
                (node.right_index, node.right_count),
            ] {
                if count == 0 {
                    pending.push((child as usize, level + 1));
                } else if u64::from(child) + u64::from(count) > triangles {
                    return false;
                }
            }
        }
        true
    }

    fn wide_in_bounds(&self) -> bool {
        let node_count = self.nodes.len() / WIDE_NODE_WORDS;
        let triangles = self.ids.len() as u64;
        let mut pending = vec![(0usize, 1u32)];
        while let Some((index, level)) = pending.pop() {
            if index >= node_count {
                return node_count == 0 && index == 0;
            }
            if level > self.stack_size {
                return false;
            }
            // The words `traverse_cwbvh.wgsl` reads: imask in the top byte of word 3, the
            // child and triangle bases in words 4 and 5, the child meta bytes in words 6-7.
            let words = &self.nodes[index * WIDE_NODE_WORDS..][..8];
            let imask = words[3] >> 24;
            let (child_base, triangle_base) = (words[4] as usize, u64::from(words[5]));
            let inner = imask.count_ones() as usize;
            if child_base + inner > node_count {
                return false;
            }
            pending.extend((child_base..child_base + inner).map(|child| (child, level + 1)));
            for byte in 0..8 {
                let meta = (words[6 + byte / 4] >> (8 * (byte % 4))) & 0xff;
                let is_inner = meta & 0x18 == 0x18;
                let count = u64::from((meta >> 5).count_ones());
                let first = triangle_base + u64::from(meta & 0x1f);
                if !is_inner && meta != 0 && first + count > triangles {
                    return false;
                }
            }
        }
        true
    }

    /// Bytes of node, triangle and id data.
    pub fn memory_bytes(&self) -> usize {
        size_of_val(self.nodes.as_slice())
            + size_of_val(self.vertices.as_slice())
            + size_of_val(self.ids.as_slice())
    }
}

/// Lays out `bvh`'s inner nodes depth first, each node's left subtree right after it, and
/// returns them with the deepest level. A root that is itself a leaf becomes a node whose
/// two children are that leaf.
fn binary_nodes(bvh: &Bvh2) -> (Vec<Bvh2Node>, u32) {
    let mut layout = BinaryNodes {
        nodes: Vec::with_capacity(bvh.nodes.len() / 2),
        stack_size: 1,
    };
    let Some(root) = bvh.nodes.first() else {
        return (layout.nodes, layout.stack_size);
    };
    if root.is_leaf() {
        let (index, count) = (root.first_index, root.prim_count);
        let (min, max) = (root.aabb.min.into(), root.aabb.max.into());
        layout.nodes.push(Bvh2Node {
            left_min: min,
            left_index: index,
            left_max: max,
            right_index: index,
            right_min: min,
            left_count: count,
            right_max: max,
            right_count: count,
        });
        return (layout.nodes, layout.stack_size);
    }
    layout.nodes.push(Bvh2Node::default());
    // (obvhs inner node, its slot in `nodes`, its level)
    let mut pending = vec![(0usize, 0usize, 1u32)];
    while let Some((source, slot, level)) = pending.pop() {
        layout.stack_size = layout.stack_size.max(level);
        let first = bvh.nodes[source].first_index as usize;
        let mut child_ref = |child: usize, layout: &mut BinaryNodes| {
            let node = &bvh.nodes[child];
            if node.is_leaf() {
                (node.first_index, node.prim_count)
            } else {
                let index = layout.nodes.len();
                layout.nodes.push(Bvh2Node::default());
                // Push the right subtree first so the left one is laid out next.
                pending.push((child, index, level + 1));
                (index as u32, 0)
            }
        };
        let (right_index, right_count) = child_ref(first + 1, &mut layout);
        let (left_index, left_count) = child_ref(first, &mut layout);
        let (left, right) = (&bvh.nodes[first].aabb, &bvh.nodes[first + 1].aabb);
        layout.nodes[slot] = Bvh2Node {
            left_min: left.min.into(),
            left_index,
            left_max: left.max.into(),
            right_index,
            right_min: right.min.into(),
            left_count,
            right_max: right.max.into(),
            right_count,
        };
    }
    (layout.nodes, layout.stack_size)
}

/// Binary nodes under construction.
struct BinaryNodes {
    nodes: Vec<Bvh2Node>,
    stack_size: u32,
}

#[cfg(test)]
mod tests {
    use super::*;
    use vcm_traversal::{BuildPreset, build::build_bvh2};

    fn grid_triangles(n: usize) -> Vec<[Vec3; 3]> {
        (0..n)
            .map(|i| {
                let p = Vec3::new((i % 17) as f32, (i / 17) as f32, (i % 5) as f32);
                [p, p + Vec3::X, p + Vec3::Y]
            })
            .collect()
    }

    /// Every triangle is reachable from the root exactly as often as the BVH2 stores it,
    /// every child box contains its triangles, and the stack bound covers the deepest path.
    #[test]
    fn layout_keeps_every_triangle_inside_its_boxes() {
        for n in [1, 2, 3, 100, 1000] {
            let triangles = grid_triangles(n);
            let bvh = build_bvh2(&triangles, BuildPreset::Fast).unwrap();
            let (nodes, stack_size) = binary_nodes(&bvh);
            let layout = SceneLayout::new(&bvh, &triangles, NodeLayout::Binary, 1);
            assert_eq!(bytemuck::cast_slice::<_, u32>(&nodes), layout.nodes);
            let mut seen = vec![0u32; n];
            let mut pending = vec![(0u32, 1u32)];
            while let Some((node, level)) = pending.pop() {
                assert!(level <= stack_size);
                let node = nodes[node as usize];
                let children = [
                    (
                        node.left_index,
                        node.left_count,
                        node.left_min,
                        node.left_max,
                    ),
                    (
                        node.right_index,
                        node.right_count,
                        node.right_min,
                        node.right_max,
                    ),
                ];
                for (index, count, min, max) in children {
                    if count == 0 {
                        pending.push((index, level + 1));
                        continue;
                    }
                    for position in index..index + count {
                        let id = layout.ids[position as usize] as usize;
                        seen[id] += 1;
                        for p in triangles[id] {
                            assert!(
                                p.cmpge(Vec3::from(min)).all() && p.cmple(Vec3::from(max)).all()
                            );
                        }
                    }
                }
            }
            let expected = if n == 1 { 2 } else { 1 };
            assert!(seen.iter().all(|&s| s == expected), "n = {n}: {seen:?}");
        }
    }

    #[test]
    fn index_check_accepts_built_layouts_and_rejects_broken_ones() {
        let triangles = grid_triangles(1000);
        let bvh = build_bvh2(&triangles, BuildPreset::Fast).unwrap();
        for kind in [NodeLayout::Binary, NodeLayout::Wide] {
            let layout = SceneLayout::new(&bvh, &triangles, kind, 3);
            assert!(layout.indices_in_bounds(), "{kind:?}");
            let mut shallow = layout.clone();
            shallow.stack_size = 1;
            assert!(!shallow.indices_in_bounds(), "{kind:?}: stack too small");
            let mut fewer_ids = layout.clone();
            fewer_ids.ids.pop();
            assert!(
                !fewer_ids.indices_in_bounds(),
                "{kind:?}: triangle past the end"
            );
        }
        let wide = SceneLayout::new(&bvh, &triangles, NodeLayout::Wide, 3);
        let mut cut = wide.clone();
        cut.nodes.truncate(cut.nodes.len() - WIDE_NODE_WORDS);
        assert!(!cut.indices_in_bounds(), "child node past the end");
        for kind in [NodeLayout::Binary, NodeLayout::Wide] {
            assert!(SceneLayout::new(&Bvh2::default(), &[], kind, 3).indices_in_bounds());
        }
    }

    #[test]
    fn empty_scene_has_no_nodes() {
        for layout in [NodeLayout::Binary, NodeLayout::Wide] {
            let layout = SceneLayout::new(&Bvh2::default(), &[], layout, 3);
            assert!(layout.nodes.is_empty() && layout.vertices.is_empty());
        }
    }

    #[test]
    fn wide_nodes_are_twenty_words() {
        let triangles = grid_triangles(100);
        let bvh = build_bvh2(&triangles, BuildPreset::Fast).unwrap();
        let layout = SceneLayout::new(&bvh, &triangles, NodeLayout::Wide, 3);
        assert_eq!(layout.nodes.len() % 20, 0);
        assert_eq!(layout.vertices.len(), 3 * layout.ids.len());
        assert!(layout.stack_size >= 2);
    }
}
