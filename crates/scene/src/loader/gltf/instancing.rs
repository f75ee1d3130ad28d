//! What a glTF node hierarchy expands to, worked out from the counts the file declares before
//! any geometry is read. glTF requires a tree, but a node listed twice among its parent's
//! children, or under several parents, instances its subtree again: 30 levels of nodes that
//! each list the next one twice describe 2³⁰ copies of a mesh in a few kilobytes. Counting
//! instances per node over the hierarchy (a directed graph, each node once) takes time linear
//! in the file, whatever it expands to; the count is then checked against the
//! [`LoadOptions`] before the expansion starts.

use gltf::Semantic;
use gltf::mesh::Mode;

use crate::loader::options::LoadOptions;

/// How many times each node is instanced from `roots` (listed with repetition, as a scene's
/// `nodes` may be): the number of paths from a root to it. Saturates rather than overflows.
/// `Err` where the hierarchy has a cycle, which would expand without end.
pub(super) fn instance_counts(
    document: &gltf::Document,
    roots: &[usize],
) -> Result<Vec<u64>, String> {
    let children: Vec<Vec<usize>> = document
        .nodes()
        .map(|node| node.children().map(|child| child.index()).collect())
        .collect();
    // The nodes reachable from the roots, depth first with an explicit stack (a hierarchy
    // may be deeper than the call stack allows).
    let mut reachable = vec![false; children.len()];
    let mut stack: Vec<usize> = roots.to_vec();
    while let Some(node) = stack.pop() {
        if !std::mem::replace(&mut reachable[node], true) {
            stack.extend(&children[node]);
        }
    }
    // Kahn's topological order over the reachable nodes: a node's count is final once every
    // edge into it (each listing as a child) has been counted.
    let mut parents = vec![0usize; children.len()];
    for (node, children) in children.iter().enumerate() {
        if reachable[node] {
            children.iter().for_each(|&child| parents[child] += 1);
        }
    }
    let mut counts = vec![0u64; children.len()];
    for &root in roots {
        counts[root] = counts[root].saturating_add(1);
    }
    let mut ready: Vec<usize> = (0..children.len())
        .filter(|&node| reachable[node] && parents[node] == 0)
        .collect();
    let mut ordered = 0;
    while let Some(node) = ready.pop() {
        ordered += 1;
        for &child in &children[node] {
            counts[child] = counts[child].saturating_add(counts[node]);
            parents[child] -= 1;
            if parents[child] == 0 {
                ready.push(child);
            }
        }
    }
    if ordered < reachable.iter().filter(|&&r| r).count() {
        return Err("the node hierarchy has a cycle".into());
    }
    Ok(counts)
}

/// The triangles and vertices that reading `mesh` once adds, from its accessors' declared
/// counts (what [`super::geometry::read_primitive`] will produce; non-triangle primitives add
/// nothing).
fn mesh_size(mesh: &gltf::Mesh) -> (u64, u64) {
    let mut triangles = 0u64;
    let mut vertices = 0u64;
    for primitive in mesh.primitives() {
        let Some(positions) = primitive.get(&Semantic::Positions) else {
            continue;
        };
        let corners = primitive
            .indices()
            .map_or(positions.count(), |indices| indices.count()) as u64;
        let added = match primitive.mode() {
            Mode::Triangles => corners / 3,
            Mode::TriangleStrip | Mode::TriangleFan => corners.saturating_sub(2),
            _ => continue,
        };
        triangles = triangles.saturating_add(added);
        vertices = vertices.saturating_add(positions.count() as u64);
    }
    (triangles, vertices)
}

/// Checks what expanding every node instance (`counts`, from [`instance_counts`]) would
/// create against `options`: `Err` says what it would need and what is allowed.
pub(super) fn check_expansion(
    document: &gltf::Document,
    counts: &[u64],
    options: &LoadOptions,
) -> Result<(), String> {
    let sizes: Vec<(u64, u64)> = document.meshes().map(|mesh| mesh_size(&mesh)).collect();
    let (mut instances, mut triangles, mut vertices) = (0u64, 0u64, 0u64);
    for node in document.nodes() {
        let count = counts[node.index()];
        instances = instances.saturating_add(count);
        if let Some(mesh) = node.mesh() {
            let (t, v) = sizes[mesh.index()];
            triangles = triangles.saturating_add(count.saturating_mul(t));
            vertices = vertices.saturating_add(count.saturating_mul(v));
        }
    }
    let limit = options.max_triangles;
    let refuse = |what: &str, count: u64, most: u64| {
        let count = if count == u64::MAX {
            "more than 2^64".to_string()
        } else {
            count.to_string()
        };
        Err(format!(
            "the node hierarchy expands to {count} {what} (every instance counted), more \
             than the {most} the load options allow (max_triangles {limit})"
        ))
    };
    if triangles > limit {
        return refuse("triangles", triangles, limit);
    }
    if vertices > options.max_vertices() {
        return refuse("vertices", vertices, options.max_vertices());
    }
    if instances > limit {
        return refuse("node instances", instances, limit);
    }
    Ok(())
}
