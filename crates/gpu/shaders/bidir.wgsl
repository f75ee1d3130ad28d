// What the bidirectional kernels share (vcm's bidir/): the MIS quantities a subpath carries
// and the weights made from them (mis.rs, Georgiev et al. 2012, SmallVCM's recursive form),
// the light vertex cache and its index, each iteration's MIS factors and hash grid
// (hash_grid.rs), and the PCG32 stream that picks cached vertices (vcm-scene's
// sampling/rng.rs).
//
// Bindings (group 0): 6 per light path of the frame its stored vertices (counted by the
// light pass's first run) or where they start in its iteration (for its second, index.wgsl);
// 7 the vertices, iteration by iteration, each iteration's in the order of its light paths;
// 8 the frame's iterations; for the camera pass 9 and 10 the iterations' hash grids; and for
// the light pass 14 the first vertices of each light path, `params.kept_vertices` a path.

// What the light pass does (`Params::light_pass`): trace light paths for light tracing
// alone (weight 1, with the camera's first hits); or, for the bidirectional algorithms, in a
// first run trace them, splat with the bidirectional weights, count each path's cacheable
// vertices and keep the first `params.kept_vertices` of them in `scratch`, and, once the
// index says where each path's vertices go, in a second run copy those into the cache and
// trace again only the paths that have more, to store the rest.
const LIGHT_TRACING: u32 = 0u;
const FIRST_VERTICES: u32 = 1u;
const LATER_VERTICES: u32 = 2u;

// The parts that run (`Params::plan`, vcm's `BidirPlan`): light vertices connect to the
// camera; camera vertices take light samples and connect to cached vertices; they merge
// with cached vertices; photon mapping proper (merging at the first diffuse or glossy vertex
// and stopping there, unweighted).
const SPLATS: u32 = 1u;
const CONNECTS: u32 = 2u;
const MERGES: u32 = 4u;
const PPM: u32 = 8u;

fn plan_has(part: u32) -> bool {
    return (params.plan & part) != 0u;
}

// A subpath's MIS quantities (`SubpathMis`): dVCM, dVC, dVM.
struct SubpathMis {
    d_vcm: f32,
    d_vc: f32,
    d_vm: f32,
}

@group(0) @binding(6) var<storage, read_write> vertex_index: array<u32>;
@group(0) @binding(7) var<storage, read_write> cache: array<LightVertex>;
@group(0) @binding(8) var<storage, read> iterations: array<Iteration>;
@group(0) @binding(14) var<storage, read_write> scratch: array<LightVertex>;

// The MIS factors of the invocation's iteration, set where it starts.
var<private> factors: MisFactors;

// A camera subpath's quantities at its start (`SubpathMis::camera`).
fn mis_camera(camera_pdf_w: f32) -> SubpathMis {
    return SubpathMis(params.light_paths / camera_pdf_w, 0.0, 0.0);
}

// A light subpath's quantities at its start (`SubpathMis::light`).
fn mis_light(
    direct_pdf: f32,
    emission_pdf_w: f32,
    cos_at_light: f32,
    is_delta: bool,
    is_finite: bool,
) -> SubpathMis {
    var d_vc = 0.0;
    if !is_delta {
        d_vc = select(1.0 / emission_pdf_w, cos_at_light / emission_pdf_w, is_finite);
    }
    return SubpathMis(direct_pdf / emission_pdf_w, d_vc, d_vc * factors.hit);
}

// Arrival at a vertex over a segment of squared length `distance_sq` (negative: from a
// light at infinity, whose pdfs are per solid angle) at cosine `cos_in`
// (`SubpathMis::arrive`).
fn mis_arrive(mis: ptr<function, SubpathMis>, distance_sq: f32, cos_in: f32) {
    if distance_sq >= 0.0 {
        (*mis).d_vcm = (*mis).d_vcm * distance_sq;
    }
    let inv_cos = 1.0 / abs(cos_in);
    (*mis).d_vcm = (*mis).d_vcm * inv_cos;
    (*mis).d_vc = (*mis).d_vc * inv_cos;
    (*mis).d_vm = (*mis).d_vm * inv_cos;
}

// 1 where merging is a technique at a vertex, 0 beside a light where connections run
// (`MisFactors::beside_light`).
fn merges_at(beside_light: bool) -> f32 {
    return select(1.0, 1.0 - factors.connections, beside_light);
}

// Whether light tracing splats the first vertex of a delta light's path: not where
// connections run (`MisFactors::splats_first_of_delta`).
fn splats_first_of_delta() -> bool {
    return factors.connections == 0.0;
}

// Whether a delta light's sample at a camera vertex `segments` segments from the camera is
// its path's only technique (`MisFactors::only_delta_light_sample`).
fn only_delta_light_sample(segments: u32) -> bool {
    return segments == 1u && !splats_first_of_delta();
}

// Scattering from a vertex at cosine `cos_out` with the sample's pdfs (`SubpathMis::scatter`);
// `beside_light` where the vertex lies next to the light (`MisFactors::beside_light`).
// Returns the new d_VC as it is without the merge at the vertex.
fn mis_scatter(
    mis: ptr<function, SubpathMis>,
    cos_out: f32,
    pdf_fwd: f32,
    pdf_rev: f32,
    specular: bool,
    beside_light: bool,
) -> f32 {
    let ratio = abs(cos_out) / pdf_fwd;
    let m = *mis;
    if specular {
        (*mis).d_vcm = 0.0;
        (*mis).d_vc = m.d_vc * (ratio * pdf_rev);
        (*mis).d_vm = m.d_vm * (ratio * pdf_rev);
        return (*mis).d_vc;
    }
    let merges = merges_at(beside_light);
    // d_VC's terms but the merge's: the connections' along the subpath and this vertex's.
    let connected = m.d_vc * pdf_rev + m.d_vcm * factors.connections;
    let d_vc = ratio * (connected + factors.merge * merges);
    let d_vm = ratio * (m.d_vm * pdf_rev + m.d_vcm * factors.connect + merges);
    *mis = SubpathMis(1.0 / pdf_fwd, d_vc, d_vm);
    return ratio * (connected + factors.merge * merges_at(true));
}

// Weight of emission a camera path found by itself (`emission_hit_weight`).
fn emission_hit_weight(camera: SubpathMis, direct_pdf_a: f32, emission_pdf_w: f32) -> f32 {
    let w_camera = factors.connections * direct_pdf_a * camera.d_vcm + emission_pdf_w * camera.d_vc;
    return 1.0 / (1.0 + w_camera);
}

// Weight of a light sample from a camera vertex (`light_sample_weight`).
fn light_sample_weight(
    camera: SubpathMis,
    direct_pdf_w: f32,
    emission_pdf_w: f32,
    cos_at_light: f32,
    cos_at_receiver: f32,
    bsdf_fwd_pdf_w: f32,
    bsdf_rev_pdf_w: f32,
) -> f32 {
    let w_light = bsdf_fwd_pdf_w / direct_pdf_w;
    let merge = factors.merge * merges_at(true);
    let w_camera = (emission_pdf_w * cos_at_receiver / (direct_pdf_w * cos_at_light))
        * (merge + camera.d_vcm + camera.d_vc * bsdf_rev_pdf_w);
    return 1.0 / (w_light + 1.0 + w_camera);
}

// Weight of a light vertex's connection to the camera (`camera_connection_weight`);
// `beside_light` where the vertex is its path's first.
fn camera_connection_weight(
    light: SubpathMis,
    camera_pdf_a: f32,
    bsdf_rev_pdf_w: f32,
    beside_light: bool,
) -> f32 {
    let merge = factors.merge * merges_at(beside_light);
    let w_light = (camera_pdf_a / params.light_paths)
        * (merge + light.d_vcm + light.d_vc * bsdf_rev_pdf_w);
    return 1.0 / (w_light + 1.0);
}

// Weight of a connection between a camera vertex and a light vertex (`connection_weight`);
// `light_beside_light` where the light vertex is its path's first.
fn connection_weight(
    camera: SubpathMis,
    light: SubpathMis,
    camera_fwd_pdf_a: f32,
    camera_rev_pdf_w: f32,
    light_fwd_pdf_a: f32,
    light_rev_pdf_w: f32,
    light_beside_light: bool,
) -> f32 {
    let light_merge = factors.merge * merges_at(light_beside_light);
    let w_light = camera_fwd_pdf_a * (light_merge + light.d_vcm + light.d_vc * light_rev_pdf_w);
    let w_camera = light_fwd_pdf_a
        * (factors.merge + camera.d_vcm + camera.d_vc * camera_rev_pdf_w);
    return 1.0 / (w_light + 1.0 + w_camera);
}

// Weight of a merge of a camera vertex with a light vertex (`merge_weight`).
fn merge_weight(
    camera: SubpathMis,
    light: SubpathMis,
    camera_fwd_pdf_w: f32,
    camera_rev_pdf_w: f32,
) -> f32 {
    let w_light = light.d_vcm * factors.connect + light.d_vm * camera_fwd_pdf_w;
    let w_camera = camera.d_vcm * factors.connect + camera.d_vm * camera_rev_pdf_w;
    return 1.0 / (w_light + 1.0 + w_camera);
}

// PCG32 (`Rng`): a 64-bit state and increment, as vec2<u32> (low, high).
struct Pcg {
    state: vec2<u32>,
    inc: vec2<u32>,
}

// The multiplier of PCG32's linear congruential step.
const PCG_MULT: vec2<u32> = vec2(0x4C957F2Du, 0x5851F42Du);

// The next 32 bits (`Rng::next_u32`).
fn pcg_next(r: ptr<function, Pcg>) -> u32 {
    let old = (*r).state;
    (*r).state = add64(mul64(old, PCG_MULT), (*r).inc);
    let xorshifted = shr64(shr64(old, 18u) ^ old, 27u).x;
    let rot = old.y >> 27u;
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

// `Rng::new(seed, stream)`.
fn pcg_new(seed: vec2<u32>, stream: vec2<u32>) -> Pcg {
    let inc = vec2((stream.x << 1u) | 1u, (stream.y << 1u) | (stream.x >> 31u));
    var r = Pcg(vec2(0u), inc);
    pcg_next(&r);
    r.state = add64(r.state, seed);
    pcg_next(&r);
    return r;
}

// The stream a sampler gives in place of its next pair of dimensions
// (`SobolSampler::next_stream`: `Rng::from_key([seed, index_rev, pair])`).
fn next_stream(s: Sampler) -> Pcg {
    let h = hash_key3(vec2(s.seed, 0u), vec2(s.index_rev, 0u), vec2(s.pair, 0u));
    return pcg_new(splitmix64(h), splitmix64(h ^ vec2(0x2468ACE0u, 0x13579BDFu)));
}
