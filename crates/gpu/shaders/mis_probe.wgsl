// For tests only (`mis_probe.rs`): the MIS partition of unity of the GPU's weights. For a
// path x₀ (the camera) … x_k (a point on an area light) with a material at every inner
// vertex, bidir.wgsl's subpath updates and weights give the weight of every technique that
// samples it, in the order of `vcm::mis_paths::MisTestPath::weights`: the camera path
// hitting the light; where the algorithm connects, the light sample at x_{k−1}, the
// connections of x_t to x_{t+1} for t = 1 … k − 2 and the splat of x₁; where it merges,
// the merges at x_j for j = 1 … k − 1. Composed after the host constants, sampler.wgsl,
// bsdf.wgsl, cache.wgsl, bidir.wgsl and the constants LIGHT_AREA, PIXEL_AREA and
// LIGHT_PATHS of `vcm::mis_paths`.

// The most vertices of a path, and the most weights of one.
const MAX_VERTICES: u32 = 7u;
const MAX_WEIGHTS: u32 = 15u;

// One path: its vertices (w unused), their geometric normals (= shading normals), the
// camera's viewing direction, the number of segments k, the algorithm's MIS factors and
// where the materials of x₁ … x_{k−1} start in `materials`.
struct ProbePath {
    points: array<vec4<f32>, MAX_VERTICES>,
    normals: array<vec4<f32>, MAX_VERTICES>,
    camera_forward: vec3<f32>,
    k: u32,
    factors: MisFactors,
    first_material: u32,
}

// Its weights and how many there are.
struct ProbeWeights {
    weights: array<f32, MAX_WEIGHTS>,
    count: u32,
}

// What bidir.wgsl reads of the kernels' parameters.
struct ProbeParams {
    light_paths: f32,
    plan: u32,
}

var<private> params: ProbeParams;

@group(0) @binding(0) var<storage, read> materials: array<Material>;
@group(0) @binding(1) var<storage, read> tables: array<f32>;
@group(0) @binding(2) var<storage, read> probe_paths: array<ProbePath>;
@group(0) @binding(3) var<storage, read_write> probe_weights: array<ProbeWeights>;

// The invocation's path.
var<private> current: u32;

fn vertex(j: u32) -> vec3<f32> {
    return probe_paths[current].points[j].xyz;
}

fn direction(start: u32, end: u32) -> vec3<f32> {
    return normalize(vertex(end) - vertex(start));
}

fn distance_sq(a: u32, b: u32) -> f32 {
    let d = vertex(a) - vertex(b);
    return dot(d, d);
}

// |cos| at vertex `at` toward vertex `to`.
fn cos_toward(at: u32, to: u32) -> f32 {
    return abs(dot(probe_paths[current].normals[at].xyz, direction(at, to)));
}

// pdf at inner vertex `at` of sampling the direction to `next` given the direction to
// `previous`.
fn pdf(at: u32, previous: u32, next: u32) -> f32 {
    let p = probe_paths[current];
    let n = p.normals[at].xyz;
    let b = bsdf_new(materials[p.first_material + at - 1u], n, n);
    return bsdf_eval(b, outgoing(b, direction(at, previous)), direction(at, next), false, false).pdf_fwd;
}

// The solid-angle pdf of the camera ray x₀ → x₁: 1 / (A_pixel cos³).
fn camera_pdf_w() -> f32 {
    let c = dot(probe_paths[current].camera_forward, direction(0u, 1u));
    return 1.0 / (PIXEL_AREA * (c * c * c));
}

// The pdfs of x_k emitting toward x_{k−1}: direct 1 / A, emission cos / (π A).
fn direct_pdf() -> f32 {
    return 1.0 / LIGHT_AREA;
}

fn emission_pdf() -> f32 {
    let k = probe_paths[current].k;
    return cos_toward(k, k - 1u) * (1.0 / PI) / LIGHT_AREA;
}

// The camera subpath's quantities on arriving at x_j (1 ≤ j ≤ k).
fn camera_mis(j: u32) -> SubpathMis {
    var mis = mis_camera(camera_pdf_w());
    for (var i = 1u; i <= j; i++) {
        if i > 1u {
            let beside_light = i == probe_paths[current].k;
            mis_scatter(&mis, cos_toward(i - 1u, i), pdf(i - 1u, i - 2u, i), pdf(i - 1u, i, i - 2u), false, beside_light);
        }
        mis_arrive(&mis, distance_sq(i - 1u, i), cos_toward(i, i - 1u));
    }
    return mis;
}

// The light subpath's quantities on arriving at x_j (1 ≤ j < k).
fn light_mis(j: u32) -> SubpathMis {
    let k = probe_paths[current].k;
    var mis = mis_light(direct_pdf(), emission_pdf(), cos_toward(k, k - 1u), false, true);
    for (var i = k - 1u; i >= j; i--) {
        if i + 1u < k {
            mis_scatter(&mis, cos_toward(i + 1u, i), pdf(i + 1u, i + 2u, i), pdf(i + 1u, i, i + 2u), false, i + 2u == k);
        }
        mis_arrive(&mis, distance_sq(i + 1u, i), cos_toward(i, i + 1u));
    }
    return mis;
}

@compute @workgroup_size(64)
fn probe_mis(@builtin(global_invocation_id) id: vec3<u32>) {
    current = id.x;
    if current >= arrayLength(&probe_paths) {
        return;
    }
    let k = probe_paths[current].k;
    factors = probe_paths[current].factors;
    params = ProbeParams(LIGHT_PATHS, 0u);
    var out = ProbeWeights(array<f32, MAX_WEIGHTS>(), 0u);
    out.weights[out.count] = emission_hit_weight(camera_mis(k), direct_pdf(), emission_pdf());
    out.count++;
    if factors.connections > 0.0 {
        out.weights[out.count] = light_sample_weight(
            camera_mis(k - 1u),
            direct_pdf() * distance_sq(k - 1u, k) / cos_toward(k, k - 1u),
            emission_pdf(),
            cos_toward(k, k - 1u),
            cos_toward(k - 1u, k),
            pdf(k - 1u, k - 2u, k),
            pdf(k - 1u, k, k - 2u),
        );
        out.count++;
        for (var t = 1u; t + 1u < k; t++) {
            let d2 = distance_sq(t, t + 1u);
            out.weights[out.count] = connection_weight(
                camera_mis(t),
                light_mis(t + 1u),
                pdf(t, t - 1u, t + 1u) * cos_toward(t + 1u, t) / d2,
                pdf(t, t + 1u, t - 1u),
                pdf(t + 1u, t + 2u, t) * cos_toward(t, t + 1u) / d2,
                pdf(t + 1u, t, t + 2u),
                t + 2u == k,
            );
            out.count++;
        }
        let camera_pdf_a = camera_pdf_w() * cos_toward(1u, 0u) / distance_sq(0u, 1u);
        out.weights[out.count] = camera_connection_weight(light_mis(1u), camera_pdf_a, pdf(1u, 0u, 2u), k == 2u);
        out.count++;
    }
    if factors.merge > 0.0 {
        // Where connections run, nothing merges beside the light.
        let last = select(k, k - 1u, factors.connections > 0.0);
        for (var j = 1u; j < last; j++) {
            out.weights[out.count] = merge_weight(
                camera_mis(j),
                light_mis(j),
                pdf(j, j - 1u, j + 1u),
                pdf(j, j + 1u, j - 1u),
            );
            out.count++;
        }
    }
    probe_weights[current] = out;
}
