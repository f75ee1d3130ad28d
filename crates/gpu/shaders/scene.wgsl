// What every kernel shares: the dispatch's parameters, the scene's shading data and the
// operations on it that vcm-scene and vcm do on the CPU — surface points, materials, lights
// seen from a point and emitting, media, ray offsets, MIS, Russian roulette — each in the
// CPU's order of operations.
//
// Bind groups: 0 this dispatch (binding 0 the parameters; the kernel's outputs from 1 on),
// 1 the hierarchy (traversal functions), 2 the scene's shading data (3 where the
// traversal's alpha masks take 2: the host renumbers them). The host defines the constants
// of `host_constants` (shader.rs): the CPU's rounding factors, the GGX width floor, the
// tables' layout.

struct Params {
    camera_position: vec3<f32>,
    width: u32,
    camera_forward: vec3<f32>,
    height: u32,
    camera_right: vec3<f32>,
    first_sample: u32,
    camera_up: vec3<f32>,
    // Samples per pixel in this frame.
    samples: u32,
    // tan(yfov / 2) · aspect, tan(yfov / 2).
    half_extent: vec2<f32>,
    // The image size as floats.
    size: vec2<f32>,
    // The render's 64-bit seed.
    seed: vec2<u32>,
    // The frame's path number of this dispatch's first invocation, and its paths.
    first_path: u32,
    path_count: u32,
    // Invocations per row of the 2D dispatch.
    row_threads: u32,
    // Longest path in segments.
    max_segments: u32,
    // 1: independent samples; 0: Sobol.
    independent: u32,
    // Lights the light sampler picks from (0: no light sampling).
    light_count: u32,
    // The environment light, or NO_LIGHT.
    environment: u32,
    // Where the environment map's rows, and its rows' texels, start in `picks`.
    environment_rows: u32,
    environment_columns: u32,
    // The area of a pixel on the image plane at unit distance (`Projection::pixel_area`).
    pixel_area: f32,
    // Light paths per iteration of a bidirectional algorithm (N_p), as the host rounds it to
    // a float, as the CPU's MIS weights and normalisations read it.
    light_paths: f32,
    // Light vertices each camera vertex connects to (N_c).
    connections: u32,
    // What the light pass does (bidir.wgsl).
    light_pass: u32,
    // The parts of a bidirectional algorithm that run (`BidirPlan`, bidir.wgsl).
    plan: u32,
    // Vertices of each light path the light pass's first run keeps in `scratch` (bidir.wgsl).
    kept_vertices: u32,
    // N_p exactly, for indexing the light paths (`light_paths` is rounded above 2²⁴).
    light_path_count: u32,
}

// A triangle as shading sees it: corners (w: the material, the area light or NO_LIGHT, as
// bits) and vertex normals (zero where the mesh has none).
struct ShadeTriangle {
    p0: vec4<f32>,
    p1: vec4<f32>,
    p2: vec4<f32>,
    n0: vec4<f32>,
    n1: vec4<f32>,
    n2: vec4<f32>,
}

// A light (`Light`), its kind in `normal.w` (as bits, with CUT_OUT) and its radiance,
// intensity or irradiance in `emission`:
// - AREA_LIGHT, an emitting triangle: corners c0..c2, c0.w its area; where an alpha mask
//   cuts it out (CUT_OUT), c1.w its alpha factor, c2.w its cutoff and uv2.w (as bits) the
//   mask's texture reference;
// - POINT_LIGHT at c0;
// - SPOT_LIGHT at c0 toward c1, c0.w and c1.w the cosines of its inner and outer cones;
// - DIRECTIONAL_LIGHT shining along c0;
// - ENVIRONMENT_LIGHT, radiance from every direction: constant, or that times its map's
//   texels, the map's width and height in c0.xy (as bits) and in c0.z 1 where it has a
//   map, in c0.w 1 where the map has a sampling distribution (some texel is not black);
// the lights at infinity have the scene's bounding sphere (centre, radius) in c1, where
// their light paths enter the scene.
struct Light {
    c0: vec4<f32>,
    c1: vec4<f32>,
    c2: vec4<f32>,
    normal: vec4<f32>,
    emission: vec4<f32>,
    // An area light's texture coordinates at its corners, and in `uv2.z` (as bits) the
    // texture reference of its emission or NO_TEXTURE.
    uv01: vec4<f32>,
    uv2: vec4<f32>,
}

// A triangle's texture coordinates, vertex colours (white without) and tangents (w: the
// bitangent's sign) at its corners, where the scene has any.
struct TriangleAttributes {
    uv01: vec4<f32>,
    uv2: vec4<f32>,
    color0: vec4<f32>,
    color1: vec4<f32>,
    color2: vec4<f32>,
    tangent0: vec4<f32>,
    tangent1: vec4<f32>,
    tangent2: vec4<f32>,
}

// What the scene needs, set per scene by the host (`KernelPlan`) so that the compiler drops
// the code of what it does not: texture coordinates (for textures or normal maps), normal
// maps, vertex colours, materials built per hit, absorbing volumes, and which kinds of light
// exist (bit k for kind k).
override TEXTURE_COORDINATES: bool = true;
override NORMAL_MAPS: bool = true;
override VERTEX_COLORS: bool = true;
override VARYING_MATERIALS: bool = true;
override ABSORBING_VOLUMES: bool = true;
override LIGHT_KINDS: u32 = 31u;
override ENVIRONMENT_MAP: bool = true;

fn has_light_kind(kind: u32) -> bool {
    return (LIGHT_KINDS & (1u << kind)) != 0u;
}

const AREA_LIGHT: u32 = 0u;
const POINT_LIGHT: u32 = 1u;
const SPOT_LIGHT: u32 = 2u;
const DIRECTIONAL_LIGHT: u32 = 3u;
const ENVIRONMENT_LIGHT: u32 = 4u;
const CUT_OUT: u32 = 0x100u;

const NO_LIGHT: u32 = 0xffffffffu;
const WORKGROUP: u32 = 64u;
// Russian roulette (vcm's roulette.rs).
const ROULETTE_AFTER_SEGMENTS: u32 = 3u;
const CAPPED_AFTER_SEGMENTS: u32 = 1024u;
const CAPPED_CONTINUATION: f32 = 0.95;

@group(0) @binding(0) var<uniform> params: Params;

@group(2) @binding(0) var<storage, read> triangles: array<ShadeTriangle>;
@group(2) @binding(1) var<storage, read> materials: array<Material>;
@group(2) @binding(2) var<storage, read> lights: array<Light>;
// Discrete distributions as the kernel samples them: per entry, the smallest number that
// picks it or a later entry (`first_numbers`), and its probability. The lights' come first
// (`light_count`), then the environment map's rows and each row's texels, at the offsets in
// `params`.
@group(2) @binding(3) var<storage, read> picks: array<vec2<f32>>;
// The albedo tables A and B (rows over the roughness), their averages, the sRGB table.
@group(2) @binding(4) var<storage, read> tables: array<f32>;
@group(2) @binding(5) var<storage, read> texture_infos: array<TextureInfo>;
// RGBA8 texels, red in the low byte.
@group(2) @binding(6) var<storage, read> material_texels: array<u32>;
@group(2) @binding(7) var<storage, read> texture_refs: array<TextureRef>;
@group(2) @binding(8) var<storage, read> material_inputs: array<MaterialInputs>;
@group(2) @binding(9) var<storage, read> attributes: array<TriangleAttributes>;
// The environment map's texels.
@group(2) @binding(10) var<storage, read> environment_texels: array<vec4<f32>>;

// glam's `cross`.
fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

// The unit direction through raster position `raster` (`Projection::direction`).
fn camera_direction(raster: vec2<f32>) -> vec3<f32> {
    let ndc_x = 2.0 * raster.x / params.size.x - 1.0;
    let ndc_y = 1.0 - 2.0 * raster.y / params.size.y;
    let a = ndc_x * params.half_extent.x;
    let b = ndc_y * params.half_extent.y;
    return normalized(params.camera_forward + params.camera_right * a + params.camera_up * b);
}

// The frame's path number of invocation `id` of the dispatch (a 2D grid of rows of
// `row_threads`), or NO_PATH beyond the dispatch's paths.
fn frame_path(id: vec3<u32>) -> u32 {
    let local = id.x + id.y * params.row_threads;
    return select(params.first_path + local, NO_PATH, local >= params.path_count);
}

const NO_PATH: u32 = 0xffffffffu;

// The direction of a camera ray through pixel `pixel`, jittered with the next pair of
// numbers (the camera paths' start).
fn pixel_direction(rng: ptr<function, Sampler>, pixel: u32) -> vec3<f32> {
    let jitter = uniform2(rng);
    let raster = vec2(f32(pixel % params.width) + jitter.x, f32(pixel / params.width) + jitter.y);
    return camera_direction(raster);
}

// A hit turned into a surface point (`SurfaceHit`).
struct Surface {
    position: vec3<f32>,
    n_g: vec3<f32>,
    n_s: vec3<f32>,
    // Per-axis bound of the position's rounding error.
    error: vec3<f32>,
    uv: vec2<f32>,
    color: vec3<f32>,
    material: u32,
    light: u32,
}

fn barycentric_error(c0: vec3<f32>, c1: vec3<f32>, c2: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    let sum = abs(c0 * b.x) + abs(c1 * b.y) + abs(c2 * b.z);
    return vec3(max_element(sum) * GAMMA_7);
}

// The unit geometric normal of triangle `index` (counter-clockwise winding faces it).
fn geometric_normal(index: u32) -> vec3<f32> {
    let t = triangles[index];
    return normalized_or(cross3(t.p1.xyz - t.p0.xyz, t.p2.xyz - t.p0.xyz), vec3(0.0));
}

fn surface_at(index: u32, u: f32, v: f32) -> Surface {
    let t = triangles[index];
    let c0 = t.p0.xyz;
    let c1 = t.p1.xyz;
    let c2 = t.p2.xyz;
    let w = 1.0 - u - v;
    let material = bitcast<u32>(t.p0.w);
    let n_g = geometric_normal(index);
    var n_s = normalized_or(t.n0.xyz * w + t.n1.xyz * u + t.n2.xyz * v, n_g);
    var uv = vec2(0.0);
    var color = vec3(1.0);
    if TEXTURE_COORDINATES || VERTEX_COLORS {
        let a = attributes[index];
        if TEXTURE_COORDINATES {
            uv = a.uv01.xy * w + a.uv01.zw * u + a.uv2.xy * v;
        }
        if VERTEX_COLORS {
            let k0 = a.color0.xyz;
            color = k0 + (a.color1.xyz - k0) * u + (a.color2.xyz - k0) * v;
        }
        let inputs = material_inputs[material];
        if NORMAL_MAPS && inputs.refs[REF_NORMAL] != NO_TEXTURE {
            n_s = normal_mapped(n_s, tangent_space_normal(inputs, uv), a, w, u, v);
        }
    }
    if dot3(n_s, n_g) < 0.0 {
        n_s = -n_s;
    }
    return Surface(
        c0 * w + c1 * u + c2 * v,
        n_g,
        n_s,
        barycentric_error(c0, c1, c2, vec3(w, u, v)),
        uv,
        color,
        material,
        bitcast<u32>(t.p1.w),
    );
}

// The shading normal `n` bent by the tangent-space normal `m` (zero: none) in the frame
// of the interpolated tangent (`Mesh::surface_point`).
fn normal_mapped(
    n: vec3<f32>,
    m: vec3<f32>,
    a: TriangleAttributes,
    w: f32,
    u: f32,
    v: f32,
) -> vec3<f32> {
    let tangent = a.tangent0 * w + a.tangent1 * u + a.tangent2 * v;
    let tan0 = try_normalized(tangent.xyz);
    if is_zero(m) || is_zero(tan0) {
        return n;
    }
    let sign = select(1.0, -1.0, tangent.w < 0.0);
    let tan = normalized_or(tan0 - n * dot3(n, tan0), vec3(0.0));
    let bitangent = cross3(n, tan) * sign;
    let mapped = tan * m.x + bitangent * m.y + n * m.z;
    return normalized_or(mapped, n);
}

// The lobes at surface point `s`: the host's where no texture or vertex colour changes
// them, else those of the material's inputs there (`Scene::bsdf`).
fn material_at(s: Surface) -> Material {
    let uniform_lobes = materials[s.material];
    if !VARYING_MATERIALS {
        return uniform_lobes;
    }
    let inputs = material_inputs[s.material];
    if (inputs.flags & UNIFORM_LOBES) != 0u {
        return uniform_lobes;
    }
    var p = bsdf_params(inputs, s.uv);
    p.base_color *= s.color;
    return mixture_new(p, (uniform_lobes.flags & DOUBLE_SIDED) != 0u);
}

// An area light's radiance at barycentrics `b` (`AreaLight::radiance_at`).
fn area_radiance(light: Light, b: vec3<f32>) -> vec3<f32> {
    let texture = bitcast<u32>(light.uv2.z);
    if !TEXTURE_COORDINATES || texture == NO_TEXTURE {
        return light.emission.xyz;
    }
    let uv = light.uv01.xy * b.x + light.uv01.zw * b.y + light.uv2.xy * b.z;
    return light.emission.xyz * lookup(texture, uv).xyz;
}

// The next float from x toward the sign of o (`step_toward` of ray_offset.rs).
fn step_toward(x: f32, o: f32) -> f32 {
    let step = i32(o > 0.0) - i32(o < 0.0);
    let bits = bitcast<i32>(x);
    let magnitude = bits & 0x7fffffff;
    let ordinal = select(magnitude, -magnitude, bits < 0);
    let moved = ordinal + step;
    let moved_bits = select(u32(moved), u32(-moved) | 0x80000000u, moved < 0);
    return select(x, bitcast<f32>(moved_bits), step != 0 && is_finite(x));
}

// The origin of a ray leaving point p toward w (`offset_ray_origin`).
fn offset_ray_origin(p: vec3<f32>, p_error: vec3<f32>, n_g: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    let d = dot3(abs(n_g), p_error);
    let offset = select(d * n_g, -d * n_g, dot3(w, n_g) < 0.0);
    let moved = p + offset;
    return vec3(
        step_toward(moved.x, offset.x),
        step_toward(moved.y, offset.y),
        step_toward(moved.z, offset.z),
    );
}

// The transmittance over `distance` in a medium of absorption `sigma` (Beer–Lambert per
// channel, `Medium::transmittance`).
fn transmittance(sigma: vec3<f32>, distance: f32) -> vec3<f32> {
    if !ABSORBING_VOLUMES || all(sigma == vec3(0.0)) {
        return vec3(1.0);
    }
    return select(exp(-sigma * distance), vec3(1.0), sigma == vec3(0.0));
}

// The absorption on the side of surface `s` that `w` leaves toward, coming from a medium of
// absorption `sigma` (`Medium::toward`): a volume boundary's inside, else outside.
fn medium_toward(sigma: vec3<f32>, s: Surface, w: vec3<f32>) -> vec3<f32> {
    if !ABSORBING_VOLUMES {
        return sigma;
    }
    let inputs = material_inputs[s.material];
    if (inputs.flags & BOUNDS_VOLUME) == 0u {
        return sigma;
    }
    return select(vec3(0.0), inputs.absorption, dot3(w, s.n_g) < 0.0);
}

// Veach's power heuristic for one sample of each technique.
fn power_heuristic(f: f32, g: f32) -> f32 {
    let f2 = f * f;
    let g2 = g * g;
    let sum = f2 + g2;
    let weight = select(0.0, f2 / sum, sum > 0.0);
    return select(weight, 1.0, abs(f) == infinity());
}

// The entry a number picks from the `count` entries of `picks` from `first` on (as
// `Distribution1D::sample` does): the last whose first number is at most `u`.
fn pick(first: u32, count: u32, u: f32) -> u32 {
    var lo = 0u;
    var hi = count;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if picks[first + mid].x <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// Emitted radiance toward a path that hit `s` along `dir` after `t`, MIS-weighted against
// light sampling when the segment was sampled by a BSDF with pdf `bsdf_pdf` (< 0: by the
// camera or a delta lobe, full weight).
fn emission(s: Surface, hit: Hit, dir: vec3<f32>, bsdf_pdf: f32) -> vec3<f32> {
    let t = hit.t;
    let emitted = area_emission(s, hit, dir);
    let radiance = emitted.xyz;
    if bsdf_pdf < 0.0 || emitted.w == 0.0 {
        return radiance;
    }
    let light = lights[s.light];
    let direct_pdf_a = 1.0 / light.c0.w;
    let cos_at_light = abs(dot3(s.n_g, -dir));
    let light_pdf_w = picks[s.light].y * direct_pdf_a * t * t / cos_at_light;
    return radiance * power_heuristic(bsdf_pdf, light_pdf_w);
}

// A light sample's shadow ray and what it adds unless blocked; `valid` false for none.
struct Shadow {
    valid: bool,
    origin: vec3<f32>,
    direction: vec3<f32>,
    tmax: f32,
    contribution: vec3<f32>,
}

fn no_shadow() -> Shadow {
    return Shadow(false, vec3(0.0), vec3(0.0), 0.0, vec3(0.0));
}

// A light seen from a receiver (`Illumination`); `valid` false where it sends nothing.
struct Illumination {
    valid: bool,
    direction: vec3<f32>,
    // Infinite for directional and environment lights.
    distance: f32,
    value: vec3<f32>,
    direct_pdf_w: f32,
    // The light's pdf of emitting the segment toward the receiver (no pick), and the cosine
    // at the light (1 for point-like lights).
    emission_pdf_w: f32,
    cos_at_light: f32,
}

fn no_illumination() -> Illumination {
    return Illumination(false, vec3(0.0), 0.0, vec3(0.0), 0.0, 0.0, 0.0);
}

// A point or spot light at `position` seen from `receiver`, emitting toward it with pdf
// `emission_pdf_w` (`illuminate_delta`).
fn illuminate_delta(
    position: vec3<f32>,
    receiver: vec3<f32>,
    value: vec3<f32>,
    emission_pdf_w: f32,
) -> Illumination {
    let to_light = position - receiver;
    let distance_sq = dot3(to_light, to_light);
    let distance = sqrt(distance_sq);
    let valid = distance > 0.0 && is_finite(distance);
    return Illumination(valid, to_light / distance, distance, value, distance_sq, emission_pdf_w, 1.0);
}

fn light_kind(light: Light) -> u32 {
    return bitcast<u32>(light.normal.w) & 0xffu;
}

// Whether an area light is there at barycentrics `b`, not cut out by its alpha mask
// (`AreaLight::present_at`).
fn present_at(light: Light, b: vec3<f32>) -> bool {
    if (bitcast<u32>(light.normal.w) & CUT_OUT) == 0u {
        return true;
    }
    let uv = light.uv01.xy * b.x + light.uv01.zw * b.y + light.uv2.xy * b.z;
    return light.c1.w * lookup(bitcast<u32>(light.uv2.w), uv).w >= light.c2.w;
}

// A uniform direction on the sphere (`sample_uniform_sphere`).
fn sample_uniform_sphere(u: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - 2.0 * u.x;
    let r = sqrt(max(1.0 - z * z, 0.0));
    let phi = 2.0 * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), z);
}

const UNIFORM_SPHERE_PDF: f32 = 0.25 * FRAC_1_PI;

fn environment_size(light: Light) -> vec2<u32> {
    return vec2(bitcast<u32>(light.c0.x), bitcast<u32>(light.c0.y));
}

fn has_environment_map(light: Light) -> bool {
    return ENVIRONMENT_MAP && light.c0.z != 0.0;
}

// The map's texture coordinates of a direction (`direction_to_uv`).
fn direction_to_uv(d: vec3<f32>) -> vec2<f32> {
    let u = 0.5 + atan2(d.z, d.x) / (2.0 * PI);
    let v = acos(clamp(d.y, -1.0, 1.0)) / PI;
    return vec2(u, v);
}

// The texel a point of [0, 1]² falls in (`image_cell`).
fn image_cell(size: vec2<u32>, point: vec2<f32>) -> vec2<u32> {
    let cell = max(point * vec2<f32>(size), vec2(0.0));
    return min(vec2<u32>(cell), size - vec2(1u));
}

// The environment's radiance from direction `d` (`EnvironmentLight::radiance_from`).
fn environment_radiance(light: Light, d: vec3<f32>) -> vec3<f32> {
    if !has_environment_map(light) {
        return light.emission.xyz;
    }
    let size = environment_size(light);
    let cell = image_cell(size, direction_to_uv(d));
    return light.emission.xyz * environment_texels[cell.y * size.x + cell.x].xyz;
}

// Where `u` falls within the span of the entry `i` it picked (of the `count` from `first`
// on), from the entry's first number to the next one's (`Distribution1D::sample_remapped`,
// here in f32).
fn remapped_in(first: u32, count: u32, i: u32, u: f32) -> f32 {
    let start = picks[first + i].x;
    var end = 1.0;
    if i + 1u < count {
        end = min(picks[first + i + 1u].x, 1.0);
    }
    if end > start {
        return min(max((u - start) / (end - start), 0.0), ONE_MINUS_EPSILON);
    }
    return 0.0;
}

// A direction toward the map drawn by its texels' weights (`EnvironmentMap::sample`).
fn sample_environment_map(light: Light, u: vec2<f32>) -> Illumination {
    if light.c0.w == 0.0 {
        return no_illumination();
    }
    let size = environment_size(light);
    let rows = params.environment_rows;
    let row = pick(rows, size.y, u.y);
    let v_in_row = remapped_in(rows, size.y, row, u.y);
    let columns = params.environment_columns + row * size.x;
    let column = pick(columns, size.x, u.x);
    let u_in_column = remapped_in(columns, size.x, column, u.x);
    let cell = vec2(f32(column) + u_in_column, f32(row) + v_in_row);
    let point = min(cell / vec2<f32>(size), vec2(ONE_MINUS_EPSILON));
    let pdf_uv = picks[rows + row].y * picks[columns + column].y * f32(size.x * size.y);
    let phi = (point.x - 0.5) * 2.0 * PI;
    let sin_theta = sin(point.y * PI);
    let cos_theta = cos(point.y * PI);
    let direction = vec3(sin_theta * cos(phi), cos_theta, sin_theta * sin(phi));
    if !(sin_theta > 0.0) {
        return no_illumination();
    }
    let pdf = pdf_uv / (2.0 * PI * PI * sin_theta);
    let radiance = environment_radiance(light, direction);
    let emission_pdf_w = pdf * entry_disk_pdf_a(light);
    return Illumination(true, direction, infinity(), radiance, pdf, emission_pdf_w, 1.0);
}

// The solid-angle pdf of `sample_environment_map` for direction `d` (`EnvironmentMap::pdf`).
fn environment_map_pdf(light: Light, d: vec3<f32>) -> f32 {
    let sin_theta = sqrt(d.x * d.x + d.z * d.z);
    if light.c0.w == 0.0 || !(sin_theta > 0.0) {
        return 0.0;
    }
    let size = environment_size(light);
    let cell = image_cell(size, direction_to_uv(d));
    let row_pmf = picks[params.environment_rows + cell.y].y;
    let column_pmf = picks[params.environment_columns + cell.y * size.x + cell.x].y;
    let pdf_uv = row_pmf * column_pmf * f32(size.x * size.y);
    return pdf_uv / (2.0 * PI * PI * sin_theta);
}

// A uniform point on a triangle as barycentrics (`sample_uniform_triangle`).
fn sample_uniform_triangle(u: vec2<f32>) -> vec3<f32> {
    let su = sqrt(u.x);
    let b0 = 1.0 - su;
    let b1 = u.y * su;
    return vec3(b0, b1, 1.0 - b0 - b1);
}

// An area light's point at barycentrics `b` (`AreaLight::point_at`).
fn area_point(light: Light, b: vec3<f32>) -> vec3<f32> {
    return light.c0.xyz * b.x + light.c1.xyz * b.y + light.c2.xyz * b.z;
}

// A spot light's attenuation at `cos_theta` from its axis, ramping between its cones
// (`SpotLight::falloff`).
fn spot_falloff(light: Light, cos_theta: f32) -> f32 {
    let cos_inner = light.c0.w;
    let cos_outer = light.c1.w;
    let scale = 1.0 / max(cos_inner - cos_outer, 1e-3);
    let t = clamp((cos_theta - cos_outer) * scale, 0.0, 1.0);
    return t * t;
}

// `Light::illuminate`: the light seen from `receiver`, at a point (or direction) `u` picks.
fn illuminate(light: Light, receiver: vec3<f32>, u: vec2<f32>) -> Illumination {
    switch light_kind(light) {
        case AREA_LIGHT: {
            if !has_light_kind(AREA_LIGHT) {
                return no_illumination();
            }
            let b = sample_uniform_triangle(u);
            if !present_at(light, b) {
                return no_illumination();
            }
            let to_light = area_point(light, b) - receiver;
            let distance_sq = dot3(to_light, to_light);
            let distance = sqrt(distance_sq);
            let direction = to_light / distance;
            let cos_at_light = dot3(light.normal.xyz, -direction);
            if !(cos_at_light > 0.0 && distance > 0.0) {
                return no_illumination();
            }
            let inv_area = 1.0 / light.c0.w;
            let pdf = inv_area * distance_sq / cos_at_light;
            let emission_pdf_w = inv_area * cosine_hemisphere_pdf(cos_at_light);
            let radiance = area_radiance(light, b);
            return Illumination(true, direction, distance, radiance, pdf, emission_pdf_w, cos_at_light);
        }
        case POINT_LIGHT: {
            if !has_light_kind(POINT_LIGHT) {
                return no_illumination();
            }
            return illuminate_delta(light.c0.xyz, receiver, light.emission.xyz, UNIFORM_SPHERE_PDF);
        }
        case SPOT_LIGHT: {
            if !has_light_kind(SPOT_LIGHT) {
                return no_illumination();
            }
            let cone_pdf = uniform_cone_pdf(light.c1.w);
            var seen = illuminate_delta(light.c0.xyz, receiver, light.emission.xyz, cone_pdf);
            let attenuation = spot_falloff(light, dot3(light.c1.xyz, -seen.direction));
            seen.valid = seen.valid && attenuation > 0.0;
            seen.value = light.emission.xyz * attenuation;
            return seen;
        }
        case DIRECTIONAL_LIGHT: {
            if !has_light_kind(DIRECTIONAL_LIGHT) {
                return no_illumination();
            }
            let disk_pdf = entry_disk_pdf_a(light);
            return Illumination(true, -light.c0.xyz, infinity(), light.emission.xyz, 1.0, disk_pdf, 1.0);
        }
        default: {
            if !has_light_kind(ENVIRONMENT_LIGHT) {
                return no_illumination();
            }
            if has_environment_map(light) {
                return sample_environment_map(light, u);
            }
            let direction = sample_uniform_sphere(u);
            let pdf = UNIFORM_SPHERE_PDF;
            let emission_pdf_w = pdf * entry_disk_pdf_a(light);
            return Illumination(true, direction, infinity(), light.emission.xyz, pdf, emission_pdf_w, 1.0);
        }
    }
}

// A light path's start (`Emission`); `valid` false where the light emits nothing there.
struct Emitted {
    valid: bool,
    // Radiance (area), intensity (point, spot) or irradiance (directional, environment).
    value: vec3<f32>,
    position: vec3<f32>,
    direction: vec3<f32>,
    // Area pdf of the position times solid-angle pdf of the direction.
    emission_pdf_w: f32,
    // The pdf with which light sampling picks this point: its area pdf on an area light,
    // the direction's solid-angle pdf for the environment, 1 for the delta lights.
    direct_pdf_a: f32,
    cos_at_light: f32,
}

fn no_emission() -> Emitted {
    return Emitted(false, vec3(0.0), vec3(0.0), vec3(0.0), 0.0, 1.0, 0.0);
}

// A uniform direction in the cone of directions within θmax of +z (`sample_uniform_cone`).
fn sample_uniform_cone(u: vec2<f32>, cos_max: f32) -> vec3<f32> {
    let cos_theta = (1.0 - u.x) + u.x * cos_max;
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    let phi = 2.0 * PI * u.y;
    return vec3(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta);
}

// The pdf of `sample_uniform_cone` (`uniform_cone_pdf`).
fn uniform_cone_pdf(cos_max: f32) -> f32 {
    return 1.0 / (2.0 * PI * (1.0 - cos_max));
}

// Where a light path from a light at infinity enters the scene's bounding sphere (c1 of
// `light`), shining along `direction` (`entry_point`), and the area pdf of that point
// (`entry_disk_pdf_a`).
fn entry_point(light: Light, direction: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let radius = light.c1.w;
    let disk = sample_concentric_disk(u) * radius;
    let offset = to_world(frame_from_z(direction), vec3(disk.x, disk.y, 0.0));
    return light.c1.xyz + offset - direction * radius;
}

fn entry_disk_pdf_a(light: Light) -> f32 {
    return 1.0 / (PI * light.c1.w * light.c1.w);
}

// `Light::emit`: a light path's first point and direction, from numbers `u_pos` and `u_dir`.
fn emit(light: Light, u_pos: vec2<f32>, u_dir: vec2<f32>) -> Emitted {
    var e = no_emission();
    e.cos_at_light = 1.0;
    switch light_kind(light) {
        case AREA_LIGHT: {
            if !has_light_kind(AREA_LIGHT) {
                return e;
            }
            let b = sample_uniform_triangle(u_pos);
            let local = sample_cosine_hemisphere(u_dir);
            if local.z <= 0.0 || !present_at(light, b) {
                return e;
            }
            let inv_area = 1.0 / light.c0.w;
            e.value = area_radiance(light, b);
            e.position = area_point(light, b);
            e.direction = to_world(frame_from_z(light.normal.xyz), local);
            e.emission_pdf_w = inv_area * cosine_hemisphere_pdf(local.z);
            e.direct_pdf_a = inv_area;
            e.cos_at_light = local.z;
        }
        case POINT_LIGHT: {
            if !has_light_kind(POINT_LIGHT) {
                return e;
            }
            e.value = light.emission.xyz;
            e.position = light.c0.xyz;
            e.direction = sample_uniform_sphere(u_dir);
            e.emission_pdf_w = UNIFORM_SPHERE_PDF;
        }
        case SPOT_LIGHT: {
            if !has_light_kind(SPOT_LIGHT) {
                return e;
            }
            let cos_outer = light.c1.w;
            let local = sample_uniform_cone(u_dir, cos_outer);
            e.value = light.emission.xyz * spot_falloff(light, local.z);
            e.position = light.c0.xyz;
            e.direction = to_world(frame_from_z(light.c1.xyz), local);
            e.emission_pdf_w = uniform_cone_pdf(cos_outer);
        }
        case DIRECTIONAL_LIGHT: {
            if !has_light_kind(DIRECTIONAL_LIGHT) {
                return e;
            }
            e.value = light.emission.xyz;
            e.direction = light.c0.xyz;
            e.position = entry_point(light, e.direction, u_pos);
            e.emission_pdf_w = entry_disk_pdf_a(light);
        }
        default: {
            // Toward the sky as light sampling draws it; the path shines back from there.
            let sky = illuminate(light, vec3(0.0), u_dir);
            if !sky.valid {
                return e;
            }
            e.value = sky.value;
            e.direction = -sky.direction;
            e.position = entry_point(light, e.direction, u_pos);
            e.emission_pdf_w = sky.direct_pdf_w * entry_disk_pdf_a(light);
            e.direct_pdf_a = sky.direct_pdf_w;
        }
    }
    e.valid = true;
    return e;
}

// Where a light path leaves `light`'s point `p` toward `w`: off an emitting triangle's
// surface (any barycentrics are at most 1, which bounds the point's error), else `p`
// (`offset_off_light`).
fn offset_off_light(light: Light, p: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    if light_kind(light) != AREA_LIGHT {
        return p;
    }
    let corners_error = barycentric_error(light.c0.xyz, light.c1.xyz, light.c2.xyz, vec3(1.0));
    return offset_ray_origin(p, corners_error, light.normal.xyz, w);
}

// Radiance from the environment toward a path that left the scene along `dir`, MIS-weighted
// against light sampling like `emission` (`escaped` of shade.rs).
fn escaped(dir: vec3<f32>, bsdf_pdf: f32) -> vec3<f32> {
    if !has_light_kind(ENVIRONMENT_LIGHT) || params.environment == NO_LIGHT {
        return vec3(0.0);
    }
    let light = lights[params.environment];
    let radiance = environment_radiance(light, dir);
    if bsdf_pdf < 0.0 {
        return radiance;
    }
    var direction_pdf = UNIFORM_SPHERE_PDF;
    if has_environment_map(light) {
        direction_pdf = environment_map_pdf(light, dir);
    }
    let light_pdf_w = picks[params.environment].y * direction_pdf;
    return radiance * power_heuristic(bsdf_pdf, light_pdf_w);
}

// Russian roulette after a scattering (`Roulette::survives`), `scale` the roulette's factor
// (refraction's radiance scaling undone, or a light path's emission): whether the path goes
// on, its throughput divided by the probability that it did.
fn survives(
    rng: ptr<function, Sampler>,
    segments: u32,
    throughput: ptr<function, vec3<f32>>,
    scale: f32,
) -> bool {
    if segments < ROULETTE_AFTER_SEGMENTS {
        return true;
    }
    let cap = select(CAPPED_CONTINUATION, 1.0, segments < CAPPED_AFTER_SEGMENTS);
    let continuation = min(max_element(*throughput) * scale, cap);
    if !(continuation < 1.0) {
        return true;
    }
    if uniform1(rng) >= continuation {
        return false;
    }
    *throughput = *throughput / continuation;
    return true;
}

// The light kinds with a delta position or direction (`Light::is_delta`), and those at a
// finite position (`Light::is_finite`).
fn is_delta_light(kind: u32) -> bool {
    return kind == POINT_LIGHT || kind == SPOT_LIGHT || kind == DIRECTIONAL_LIGHT;
}

fn is_finite_light(kind: u32) -> bool {
    return kind != DIRECTIONAL_LIGHT && kind != ENVIRONMENT_LIGHT;
}

// A light picked by power and a point on it, seen from `s` with the BSDF `b` from `out`
// (`LightSample::sample`: three numbers from `rng`); `valid` false where it sends nothing
// the BSDF takes. `reverse`: with the BSDF's reverse pdf.
struct LightSample {
    valid: bool,
    light: Light,
    pick_pmf: f32,
    seen: Illumination,
    eval: Evaluation,
}

fn sample_light(
    rng: ptr<function, Sampler>,
    s: Surface,
    b: Bsdf,
    out: Outgoing,
    reverse: bool,
) -> LightSample {
    var sample: LightSample;
    sample.valid = false;
    let u_pick = uniform1(rng);
    let u_light = uniform2(rng);
    if params.light_count == 0u {
        return sample;
    }
    let index = pick(0u, params.light_count, u_pick);
    sample.pick_pmf = picks[index].y;
    sample.light = lights[index];
    sample.seen = illuminate(sample.light, s.position, u_light);
    if !sample.seen.valid {
        return sample;
    }
    sample.eval = bsdf_eval(b, out, sample.seen.direction, false, reverse);
    sample.valid = any(sample.eval.f_cos != vec3(0.0));
    return sample;
}

// The shadow ray from `s` to the point `seen` of `light`, off an emitting triangle's
// surface, or toward infinity for lights at infinity (`LightSample::shadow_ray`,
// `shadow_segment`), adding `contribution` unless blocked.
fn shadow_to_light(s: Surface, light: Light, seen: Illumination, contribution: vec3<f32>) -> Shadow {
    var shadow = Shadow(true, vec3(0.0), vec3(0.0), 0.0, contribution);
    shadow.origin = offset_ray_origin(s.position, s.error, s.n_g, seen.direction);
    if !is_finite(seen.distance) {
        shadow.direction = seen.direction;
        shadow.tmax = MISSED;
    } else {
        let light_point = s.position + seen.direction * seen.distance;
        let target_point = offset_off_light(light, light_point, -seen.direction);
        shadow.direction = target_point - shadow.origin;
        shadow.tmax = 1.0 - GAMMA_16;
    }
    return shadow;
}

// Whether nothing blocks `shadow` (and its ray is counted in `rays`).
fn unblocked(shadow: Shadow, rays: ptr<function, u32>) -> bool {
    *rays += 1u;
    return trace(Ray(shadow.origin, 0.0, shadow.direction, shadow.tmax), true).prim == NO_HIT;
}

// What a path carries from vertex to vertex (`Walk`): its next segment, its throughput, the
// absorption of the medium the segment runs through, its segments so far and Russian
// roulette's factor (refraction's radiance scaling undone, or a light path's emission).
struct Walk {
    origin: vec3<f32>,
    direction: vec3<f32>,
    throughput: vec3<f32>,
    medium: vec3<f32>,
    segments: u32,
    roulette_scale: f32,
}

// The continuation's BSDF sample from `s` (`Walk::scatter`): a lobe and a direction with the
// next two pairs of numbers, in importance or radiance transport, with the reverse pdf where
// asked.
fn scatter(
    rng: ptr<function, Sampler>,
    b: Bsdf,
    out: Outgoing,
    importance: bool,
    reverse: bool,
) -> BsdfSample {
    let u_lobe = uniform1(rng);
    let u = uniform2(rng);
    return bsdf_sample(b, out, u_lobe, u, importance, reverse);
}

// Moves `walk` on from `s` along the valid `sample` (`Walk::scatter` from the throughput on):
// the throughput, Russian roulette, the next segment; false where roulette ends the path.
fn walk_on(
    walk: ptr<function, Walk>,
    rng: ptr<function, Sampler>,
    s: Surface,
    sample: BsdfSample,
    importance: bool,
) -> bool {
    if !importance {
        (*walk).roulette_scale *= sample.eta * sample.eta;
    }
    var throughput = (*walk).throughput * (sample.f_cos / sample.pdf_fwd);
    let alive = survives(rng, (*walk).segments, &throughput, (*walk).roulette_scale);
    (*walk).throughput = throughput;
    if !alive {
        return false;
    }
    (*walk).origin = offset_ray_origin(s.position, s.error, s.n_g, sample.wi);
    (*walk).direction = sample.wi;
    (*walk).segments += 1u;
    (*walk).medium = medium_toward((*walk).medium, s, sample.wi);
    return true;
}

// The radiance an emitting triangle sends from `s` toward a path that hit it along `dir`
// (`AreaLight::radiance_on_hit`), and in w the cosine at the light; zero where `s` emits
// nothing that way.
fn area_emission(s: Surface, hit: Hit, dir: vec3<f32>) -> vec4<f32> {
    if !has_light_kind(AREA_LIGHT) || s.light == NO_LIGHT {
        return vec4(0.0);
    }
    let light = lights[s.light];
    let cos_out = dot3(light.normal.xyz, -dir);
    if !(cos_out > 0.0) {
        return vec4(0.0);
    }
    return vec4(area_radiance(light, vec3(1.0 - hit.u - hit.v, hit.u, hit.v)), cos_out);
}
