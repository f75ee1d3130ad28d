// The iterations' hash grids built on the device (vcm's `HashGrid::build`), after cache.wgsl:
// the same grid the CPU builds over each iteration's light vertices — bounds, cells as wide
// as the CPU's (`HashGrid::CELL_RADII` radii), as many buckets as vertices (a power of two),
// a counting sort by bucket, each bucket's entries in index order — so that merging finds
// the CPU's vertices. As on the CPU, a grid holds only the vertices that merge
// (`MisFactors::shortest_merged`), and the device counts them: the host sizes each grid for
// its whole cache.
// Kernels, in order: grid_bounds (per vertex), grid_layout (per iteration), grid_count (per
// vertex), grid_scan (a workgroup per iteration), [the host copies the starts to the
// cursors], grid_scatter (per vertex), grid_sort (per bucket).

struct GridParams {
    // Light vertices of the frame, its iterations, and the bucket starts of all its grids.
    vertices: u32,
    iterations: u32,
    starts: u32,
    // The fewest segments a vertex that merges lies from its light.
    shortest: u32,
}

@group(0) @binding(0) var<storage, read> cache: array<LightVertex>;
@group(0) @binding(1) var<storage, read_write> iterations: array<Iteration>;
// Per iteration from its `grid_starts`: each bucket's count, then its first entry, then the
// total after its last bucket.
@group(0) @binding(2) var<storage, read_write> starts: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> entries: array<GridEntry>;
// Each vertex's bucket.
@group(0) @binding(4) var<storage, read_write> bucket_of: array<u32>;
// Each bucket's next free entry.
@group(0) @binding(5) var<storage, read_write> cursors: array<atomic<u32>>;
// Per iteration the bounds of its merging vertices' positions, as order-preserving bits: the
// smallest x, y, z, then the largest; then how many they are.
@group(0) @binding(6) var<storage, read_write> bounds: array<atomic<u32>>;
@group(0) @binding(7) var<uniform> grid: GridParams;

const GRID_WORKGROUP: u32 = 64u;

// Slots of `bounds` per iteration.
const BOUNDS_SLOTS: u32 = 7u;

// Whether invocation `v` names a vertex of the cache that merges.
fn merging_vertex(v: u32) -> bool {
    return v < grid.vertices && cache[v].path_length >= grid.shortest;
}

// The invocation's index over a dispatch of rows of `num_workgroups.x` workgroups.
fn invocation(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * GRID_WORKGROUP;
}

// The last iteration whose part starts at or before `x`: of the cache (`in_cache`; the
// iteration vertex `x` of the frame belongs to), or of the bucket starts.
fn iteration_at(x: u32, in_cache: bool) -> u32 {
    var s = 0u;
    while s + 1u < grid.iterations {
        let next = iterations[s + 1u];
        if x < select(next.grid_starts, next.cache_start, in_cache) {
            break;
        }
        s += 1u;
    }
    return s;
}

// A float's bits ordered as the floats are, and back.
fn ordered(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b >> 31u) != 0u);
}

fn unordered(o: u32) -> f32 {
    return bitcast<f32>(select(~o, o & 0x7fffffffu, (o >> 31u) != 0u));
}

@compute @workgroup_size(GRID_WORKGROUP)
fn grid_bounds(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let v = invocation(id, groups);
    if !merging_vertex(v) {
        return;
    }
    let p = cache[v].position;
    let at = BOUNDS_SLOTS * iteration_at(v, true);
    for (var k = 0u; k < 3u; k++) {
        atomicMin(&bounds[at + k], ordered(p[k]));
        atomicMax(&bounds[at + 3u + k], ordered(p[k]));
    }
    atomicAdd(&bounds[at + 6u], 1u);
}

@compute @workgroup_size(GRID_WORKGROUP)
fn grid_layout(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let s = invocation(id, groups);
    if s >= grid.iterations {
        return;
    }
    let at = BOUNDS_SLOTS * s;
    // As many buckets as vertices, a power of two.
    let count = atomicLoad(&bounds[at + 6u]);
    iterations[s].entry_count = count;
    iterations[s].bucket_mask = select((1u << (32u - countLeadingZeros(count - 1u))) - 1u, 0u, count <= 1u);
    if count == 0u {
        return;
    }
    for (var k = 0u; k < 3u; k++) {
        iterations[s].grid_min[k] = unordered(atomicLoad(&bounds[at + k]));
        iterations[s].grid_max[k] = unordered(atomicLoad(&bounds[at + 3u + k]));
    }
}

// A vertex's cell (`HashGrid::cell_of`).
fn cell_of(it: Iteration, p: vec3<f32>) -> vec3<i32> {
    return vec3<i32>(floor((p - it.grid_min) * it.inv_cell_size));
}

@compute @workgroup_size(GRID_WORKGROUP)
fn grid_count(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let v = invocation(id, groups);
    if !merging_vertex(v) {
        return;
    }
    let it = iterations[iteration_at(v, true)];
    let bucket = grid_bucket(it, cell_of(it, cache[v].position));
    bucket_of[v] = bucket;
    atomicAdd(&starts[it.grid_starts + bucket], 1u);
}

// An exclusive prefix sum of iteration `wg.x`'s bucket counts, each invocation over a chunk
// of them, then the total after the last bucket.
@compute @workgroup_size(SCAN_WORKGROUP)
fn grid_scan(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let s = wg.x;
    let it = iterations[s];
    let buckets = it.bucket_mask + 1u;
    let chunk = (buckets + SCAN_WORKGROUP - 1u) / SCAN_WORKGROUP;
    let first = min(lane * chunk, buckets);
    let end = min(first + chunk, buckets);
    var total = 0u;
    for (var b = first; b < end; b++) {
        total += atomicLoad(&starts[it.grid_starts + b]);
    }
    var running = scan_chunks(lane, total);
    if lane == 0u {
        atomicStore(&starts[it.grid_starts + buckets], chunks_sum);
    }
    for (var b = first; b < end; b++) {
        let count = atomicLoad(&starts[it.grid_starts + b]);
        atomicStore(&starts[it.grid_starts + b], running);
        running += count;
    }
}

@compute @workgroup_size(GRID_WORKGROUP)
fn grid_scatter(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let v = invocation(id, groups);
    if !merging_vertex(v) {
        return;
    }
    let it = iterations[iteration_at(v, true)];
    let slot = atomicAdd(&cursors[it.grid_starts + bucket_of[v]], 1u);
    entries[it.grid_entries + slot] = GridEntry(cache[v].position, v - it.cache_start);
}

// Sorts bucket `g` of all the frame's grids by index (insertion sort: buckets hold about one
// vertex), as the CPU sorts its buckets.
@compute @workgroup_size(GRID_WORKGROUP)
fn grid_sort(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let g = invocation(id, groups);
    if g >= grid.starts {
        return;
    }
    let it = iterations[iteration_at(g, false)];
    // The slot after the last bucket holds the total, not a bucket.
    if g - it.grid_starts > it.bucket_mask {
        return;
    }
    let first = it.grid_entries + atomicLoad(&starts[g]);
    let end = it.grid_entries + atomicLoad(&starts[g + 1u]);
    for (var i = first + 1u; i < end; i++) {
        let entry = entries[i];
        var j = i;
        while j > first && entries[j - 1u].index > entry.index {
            entries[j] = entries[j - 1u];
            j -= 1u;
        }
        entries[j] = entry;
    }
}
