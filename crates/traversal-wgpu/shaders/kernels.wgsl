// The traversal kernels' entry points over batches of rays: one invocation traces one ray of
// `rays` and writes its hit or occlusion flag. `trace(ray, any_hit)` comes from the layout's
// traversal file.

struct Params {
    // Rays in this batch.
    ray_count: u32,
    // Threads per row of the 2D dispatch (workgroups in x times the workgroup size).
    row_threads: u32,
}

const WORKGROUP_SIZE: u32 = 64u;

@group(0) @binding(0) var<storage, read> rays: array<Ray>;
@group(0) @binding(1) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(2) var<uniform> params: Params;
@group(0) @binding(3) var<storage, read_write> occluded: array<u32>;

// The ray index of this invocation in the 2D dispatch, or ray_count if it has none.
fn ray_index(id: vec3<u32>) -> u32 {
    let index = id.x + id.y * params.row_threads;
    return select(params.ray_count, index, index < params.ray_count);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn closest_hit(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = ray_index(id);
    if index < params.ray_count {
        hits[index] = trace(rays[index], false);
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn any_hit(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = ray_index(id);
    if index < params.ray_count {
        occluded[index] = u32(trace(rays[index], true).prim != NO_HIT);
    }
}
