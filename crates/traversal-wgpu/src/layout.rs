//! GPU layouts of the hierarchy: the node array, triangles in leaf order and the map from
//! leaf order back to the caller's triangle ids.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use obvhs::bvh2::Bvh2;

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
    /// Nodes, root first.
    pub nodes: Vec<Bvh2Node>,
    /// Triangle vertices in leaf order, three `[x, y, z, 0]` entries per triangle.
    pub vertices: Vec<[f32; 4]>,
    /// The caller's id of each leaf-order triangle.
    pub ids: Vec<u32>,
    /// The most entries a traversal stack can hold (the number of inner-node levels).
    pub stack_size: u32,
}

impl SceneLayout {
    /// Lays out `bvh` (built over `triangles`) depth first, each node's left subtree right
    /// after it. A root that is itself a leaf becomes a node whose two children are that leaf.
    pub fn from_bvh2(bvh: &Bvh2, triangles: &[[Vec3; 3]]) -> Self {
        let ids = bvh.primitive_indices.clone();
        let vertices = ids
            .iter()
            .flat_map(|&id| triangles[id as usize].map(|p| [p.x, p.y, p.z, 0.0]))
            .collect();
        let mut layout = Self {
            nodes: Vec::with_capacity(bvh.nodes.len() / 2),
            vertices,
            ids,
            stack_size: 1,
        };
        let Some(root) = bvh.nodes.first() else {
            return layout;
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
            return layout;
        }
        layout.nodes.push(Bvh2Node::default());
        // (obvhs inner node, its slot in `nodes`, its level)
        let mut pending = vec![(0usize, 0usize, 1u32)];
        while let Some((source, slot, level)) = pending.pop() {
            layout.stack_size = layout.stack_size.max(level);
            let first = bvh.nodes[source].first_index as usize;
            let mut child_ref = |child: usize, layout: &mut Self| {
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
        layout
    }

    /// Bytes of node, triangle and id data.
    pub fn memory_bytes(&self) -> usize {
        size_of_val(self.nodes.as_slice())
            + size_of_val(self.vertices.as_slice())
            + size_of_val(self.ids.as_slice())
    }
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
            let layout = SceneLayout::from_bvh2(&bvh, &triangles);
            let mut seen = vec![0u32; n];
            let mut pending = vec![(0u32, 1u32)];
            while let Some((node, level)) = pending.pop() {
                assert!(level <= layout.stack_size);
                let node = layout.nodes[node as usize];
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
    fn empty_scene_has_no_nodes() {
        let layout = SceneLayout::from_bvh2(&Bvh2::default(), &[]);
        assert!(layout.nodes.is_empty() && layout.vertices.is_empty());
    }
}
