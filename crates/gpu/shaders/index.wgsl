// The light vertex index built on the device, after cache.wgsl: from the vertices each of the
// frame's light paths counted (light pass, first run) to where each path's vertices start in
// its iteration's part of the cache, and each iteration's part — iteration by iteration, each
// iteration's in the order of its light paths, the CPU cache's order. The light pass's second
// run stores path p's vertices from `vertex_index[p]` + its iteration's `cache_start` on.

struct IndexParams {
    // Light paths per iteration, and iterations in the frame.
    paths: u32,
    samples: u32,
    unused: vec2<u32>,
}

// Per light path (p = i · samples + sample for the iteration's light path i) its count, then
// its start in its iteration.
@group(0) @binding(0) var<storage, read_write> vertex_index: array<u32>;
@group(0) @binding(1) var<storage, read_write> iterations: array<Iteration>;
@group(0) @binding(2) var<uniform> index: IndexParams;

// An exclusive prefix sum of iteration `wg.x`'s light paths' counts in path order, each
// invocation over a chunk of them; the iteration's total becomes its `cache_count`.
@compute @workgroup_size(SCAN_WORKGROUP)
fn index_scan(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let s = wg.x;
    let chunk = (index.paths + SCAN_WORKGROUP - 1u) / SCAN_WORKGROUP;
    let first = min(lane * chunk, index.paths);
    let end = min(first + chunk, index.paths);
    var total = 0u;
    for (var i = first; i < end; i++) {
        total += vertex_index[i * index.samples + s];
    }
    var running = scan_chunks(lane, total);
    if lane == 0u {
        iterations[s].cache_count = chunks_sum;
    }
    for (var i = first; i < end; i++) {
        let path = i * index.samples + s;
        let count = vertex_index[path];
        vertex_index[path] = running;
        running += count;
    }
}

// Each iteration's first vertex: the iterations' parts one after the other.
@compute @workgroup_size(1)
fn index_starts() {
    var start = 0u;
    for (var s = 0u; s < index.samples; s++) {
        iterations[s].cache_start = start;
        start += iterations[s].cache_count;
    }
}
