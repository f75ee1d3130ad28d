// The light vertex cache and the iterations' hash grids as the bidirectional kernels and the
// grid's build share them (vcm's light_vertex_cache.rs, hash_grid.rs): the layouts, and the
// bucket of a grid cell.

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
