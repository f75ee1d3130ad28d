// The light vertex cache and the iterations' hash grids as the bidirectional kernels and the
// builds of the index and the grids share them (vcm's light_vertex_cache.rs, hash_grid.rs):
// the layouts, the bucket of a grid cell, and the workgroup's prefix sum the builds use.

// A cached light vertex (`LightVertex`): where it is, toward the previous vertex, the path's
// throughput and MIS quantities there, the hit it was (to shade it again), and the segments
// from the light.
struct LightVertex {
    position: vec3<f32>,
    path_length: u32,
    wo: vec3<f32>,
    triangle: u32,
    throughput: vec3<f32>,
    u: f32,
    mis: vec3<f32>,
    v: f32,
}

// The MIS factors of an iteration (`MisFactors`): merge (η_VCM where merging), connect (1/η
// where connecting and merging), hit (1/η where merging), connections (1 where connecting).
struct MisFactors {
    merge: f32,
    connect: f32,
    hit: f32,
    connections: f32,
}

// An iteration of the frame (one sample per pixel): its light vertices in the cache, its
// MIS factors and merge radius, and its hash grid (`HashGrid::layout`: where its bucket
// starts and entries begin in bindings 9 and 10, the points' bounds, the inverse cell size,
// the bucket mask, the entries).
struct Iteration {
    cache_start: u32,
    cache_count: u32,
    grid_starts: u32,
    grid_entries: u32,
    factors: MisFactors,
    grid_min: vec3<f32>,
    inv_cell_size: f32,
    grid_max: vec3<f32>,
    bucket_mask: u32,
    radius: f32,
    radius_sq: f32,
    entry_count: u32,
    unused: u32,
}

// A hash grid's entry: a light vertex's position and its index in its iteration's cache.
struct GridEntry {
    position: vec3<f32>,
    index: u32,
}

// The bucket of a grid cell (`HashGrid::bucket`, Teschner et al. 2003): the low bits of the
// 64-bit hash, which 32-bit arithmetic gives alike.
fn grid_bucket(it: Iteration, cell: vec3<i32>) -> u32 {
    let c = bitcast<vec3<u32>>(cell);
    let h = (c.x * 73856093u) ^ (c.y * 19349663u) ^ (c.z * 83492791u);
    return h & it.bucket_mask;
}

const SCAN_WORKGROUP: u32 = 256u;

var<workgroup> chunk_totals: array<u32, SCAN_WORKGROUP>;
var<workgroup> chunks_sum: u32;

// The exclusive prefix sum over a workgroup's lanes of each lane's `total` (the sum of its
// chunk): this lane's offset; `chunks_sum` holds the sum of all afterwards. Called by every
// lane of the workgroup.
fn scan_chunks(lane: u32, total: u32) -> u32 {
    chunk_totals[lane] = total;
    workgroupBarrier();
    if lane == 0u {
        var sum = 0u;
        for (var k = 0u; k < SCAN_WORKGROUP; k++) {
            let t = chunk_totals[k];
            chunk_totals[k] = sum;
            sum += t;
        }
        chunks_sum = sum;
    }
    workgroupBarrier();
    return chunk_totals[lane];
}
