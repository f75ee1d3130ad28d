// The surface scattering model of vcm-scene (bsdf/), radiance transport with forward pdfs,
// for the lobes the GPU shades so far: plain Lambert (no specular layer), Schlick mirror
// reflection, and smooth dielectric interfaces, thick and thin-walled. Each function is the
// CPU's of the same name, in the same order of operations; the host refuses scenes with
// other lobes (rough GGX, layered diffuse) before any of this runs.

const GRAZING_COS: f32 = 1e-6;
const FRAC_1_PI: f32 = 0.31830987;
const FRAC_PI_4: f32 = 0.7853982;
// 1 − ε/2: the largest f32 below 1.
const ONE_MINUS_EPSILON: f32 = 0.99999994;
// The specular lobe's smallest selection weight, relative to its largest reflectance.
const MIN_SELECTION: f32 = 1e-3;

// `Material::flags` bits: which lobes exist, and how the material is seen.
const HAS_SPECULAR: u32 = 1u;
const HAS_DIFFUSE: u32 = 2u;
const HAS_DIELECTRIC: u32 = 4u;
const HAS_THIN: u32 = 8u;
const DOUBLE_SIDED: u32 = 16u;
const CONSTANT_SELECTION: u32 = 32u;

// `LobeKind`.
const KIND_DIFFUSE: u32 = 0u;
const KIND_SPECULAR: u32 = 2u;

// One material's lobes, `FlatLobes` with the material's sidedness (`GpuMaterial` on the host).
struct Material {
    f0: vec3<f32>,
    ior: f32,
    f90: vec3<f32>,
    flags: u32,
    diffuse_albedo: vec3<f32>,
    dielectric_weight: f32,
    diffuse_scale: vec3<f32>,
    thin_weight: f32,
    dielectric_tint: vec3<f32>,
    unused0: u32,
    thin_tint: vec3<f32>,
    unused1: u32,
    selection: vec4<f32>,
}

fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn all_finite(v: vec3<f32>) -> bool {
    return is_finite(v.x) && is_finite(v.y) && is_finite(v.z);
}

// glam's `dot`, left to right.
fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

// glam's `normalize`: times the reciprocal of the length.
fn normalized(v: vec3<f32>) -> vec3<f32> {
    return v * (1.0 / sqrt(dot3(v, v)));
}

fn max_element(v: vec3<f32>) -> f32 {
    return max(max(v.x, v.y), v.z);
}

fn mean3(v: vec3<f32>) -> f32 {
    return (v.x + v.y + v.z) / 3.0;
}

// An orthonormal frame around a unit z (Duff et al. 2017), `Frame::from_z`.
struct Frame {
    x: vec3<f32>,
    y: vec3<f32>,
    z: vec3<f32>,
}

fn frame_from_z(n: vec3<f32>) -> Frame {
    let sign = bitcast<f32>((bitcast<u32>(n.z) & 0x80000000u) | 0x3f800000u);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return Frame(
        vec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        vec3(b, sign + n.y * n.y * a, -n.y),
        n,
    );
}

fn to_local(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return vec3(dot3(v, f.x), dot3(v, f.y), dot3(v, f.z));
}

fn to_world(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return f.x * v.x + f.y * v.y + f.z * v.z;
}

// sin and cos on [−π/4, π/4] (`sin_cos_octant` of warps.rs).
fn sin_cos_octant(x: f32) -> vec2<f32> {
    let z = x * x;
    let s = ((-1.9515296e-4 * z + 8.332161e-3) * z + -1.6666655e-1) * z * x + x;
    let c = ((2.4433157e-5 * z + -1.3887316e-3) * z + 4.1666646e-2) * z * z - 0.5 * z + 1.0;
    return vec2(s, c);
}

fn sample_concentric_disk(u: vec2<f32>) -> vec2<f32> {
    let p = 2.0 * u - vec2(1.0);
    if p.x == 0.0 && p.y == 0.0 {
        return vec2(0.0);
    }
    let x_major = abs(p.x) > abs(p.y);
    let major = select(p.y, p.x, x_major);
    let minor = select(p.x, p.y, x_major);
    let sc = sin_cos_octant(FRAC_PI_4 * (minor / major));
    let xy = select(sc, sc.yx, x_major);
    return major * xy;
}

fn sample_cosine_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let d = sample_concentric_disk(u);
    let z = sqrt(max(1.0 - (d.x * d.x + d.y * d.y), 0.0));
    return vec3(d.x, d.y, z);
}

fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    return max(cos_theta, 0.0) * FRAC_1_PI;
}

fn schlick(f0: vec3<f32>, f90: vec3<f32>, cos_theta: f32) -> vec3<f32> {
    let m = clamp(1.0 - cos_theta, 0.0, 1.0);
    let m2 = m * m;
    return f0 + (f90 - f0) * (m2 * m2 * m);
}

fn fresnel_dielectric(cos_in: f32, eta: f32) -> f32 {
    let cos_i = clamp(cos_in, 0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular);
}

fn thin_sheet_reflectance(r: f32) -> f32 {
    if r >= 1.0 {
        return 1.0;
    }
    let t = 1.0 - r;
    return r + t * t * r / (1.0 - r * r);
}

// The refracted direction through the normal +z, or a zero vector under total internal
// reflection.
fn refract_z(wo: vec3<f32>, eta: f32) -> vec3<f32> {
    let cos_i = wo.z;
    let sin2_t = max(1.0 - cos_i * cos_i, 0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return vec3(0.0);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    return -wo / eta + (cos_i / eta - cos_t) * vec3(0.0, 0.0, 1.0);
}

// A BSDF placed at a surface point (`Bsdf`).
struct Bsdf {
    frame: Frame,
    n_g: vec3<f32>,
    material: u32,
}

fn transmits(m: Material) -> bool {
    return (m.flags & (HAS_DIELECTRIC | HAS_THIN)) != 0u;
}

fn has_non_delta(m: Material) -> bool {
    return (m.flags & HAS_DIFFUSE) != 0u;
}

fn bsdf_new(material: u32, n_g: vec3<f32>, n_s_in: vec3<f32>) -> Bsdf {
    var n_s = n_s_in;
    if !all_finite(n_s) || dot3(n_s, n_s) < 0.25 {
        n_s = n_g;
    } else if dot3(n_s, n_g) < 0.0 {
        n_s = -n_s;
    }
    return Bsdf(frame_from_z(n_s), n_g, material);
}

// The outgoing side and direction (`Outgoing`); `valid` false where the BSDF is black.
struct Outgoing {
    valid: bool,
    back: bool,
    eta: f32,
    world: vec3<f32>,
    local: vec3<f32>,
    selection: vec4<f32>,
}

fn local_on_side(b: Bsdf, back: bool, w: vec3<f32>) -> vec3<f32> {
    let l = to_local(b.frame, w);
    return select(l, vec3(l.x, l.y, -l.z), back);
}

fn world_on_side(b: Bsdf, back: bool, l: vec3<f32>) -> vec3<f32> {
    return to_world(b.frame, select(l, vec3(l.x, l.y, -l.z), back));
}

// Lobe selection probabilities at `wo` (`Mixture::selection_at`).
fn selection_at(m: Material, wo: vec3<f32>, eta: f32) -> vec4<f32> {
    var w = vec4(0.0);
    if (m.flags & HAS_SPECULAR) != 0u {
        let albedo = mean3(schlick(m.f0, m.f90, wo.z));
        w.x = max(max(albedo, MIN_SELECTION * max_element(max(m.f0, m.f90))), 0.0);
    }
    if (m.flags & HAS_DIFFUSE) != 0u {
        w.y = max(mean3(m.diffuse_albedo), 0.0);
    }
    if (m.flags & HAS_DIELECTRIC) != 0u {
        let r = fresnel_dielectric(wo.z, eta);
        w.z = max(m.dielectric_weight * (r + (1.0 - r) * mean3(m.dielectric_tint)), 0.0);
    }
    if (m.flags & HAS_THIN) != 0u {
        let r = thin_sheet_reflectance(fresnel_dielectric(wo.z, m.ior));
        w.w = max(m.thin_weight * (r + (1.0 - r) * mean3(m.thin_tint)), 0.0);
    }
    let total = w.x + w.y + w.z + w.w;
    if total > 0.0 && is_finite(total) {
        return w / total;
    }
    return vec4(0.0);
}

fn outgoing(b: Bsdf, wo: vec3<f32>) -> Outgoing {
    var out = Outgoing(false, false, 1.0, wo, vec3(0.0), vec4(0.0));
    let m = materials[b.material];
    let cos_g = dot3(wo, b.n_g);
    if !(abs(cos_g) > GRAZING_COS) {
        return out;
    }
    out.back = cos_g < 0.0;
    if out.back && !((m.flags & DOUBLE_SIDED) != 0u || transmits(m)) {
        return out;
    }
    out.eta = select(m.ior, 1.0 / m.ior, out.back);
    out.local = local_on_side(b, out.back, wo);
    if !(out.local.z >= GRAZING_COS) {
        return out;
    }
    out.valid = true;
    if (m.flags & CONSTANT_SELECTION) != 0u {
        out.selection = m.selection;
    } else {
        out.selection = selection_at(m, out.local, out.eta);
    }
    return out;
}

// |cos| of `wi` with the geometric normal where `wi` and its local form lie on the same
// side (`Bsdf::consistent`), else a negative number.
fn consistent(b: Bsdf, back: bool, wi: vec3<f32>, wi_local: vec3<f32>) -> f32 {
    let cos_gi = select(dot3(wi, b.n_g), -dot3(wi, b.n_g), back);
    let ok = abs(cos_gi) >= GRAZING_COS && abs(wi_local.z) >= GRAZING_COS
        && (cos_gi > 0.0) == (wi_local.z > 0.0);
    return select(-1.0, abs(cos_gi), ok);
}

// f·|cos| and the forward pdf of the non-delta lobes (`BsdfEval`, `Pdfs::Forward`).
struct BsdfEval {
    f_cos: vec3<f32>,
    pdf_fwd: f32,
}

fn bsdf_eval(b: Bsdf, out: Outgoing, wi: vec3<f32>) -> BsdfEval {
    let none = BsdfEval(vec3(0.0), 0.0);
    let wi_l = local_on_side(b, out.back, wi);
    if consistent(b, out.back, wi, wi_l) < 0.0 {
        return none;
    }
    let m = materials[b.material];
    var f_cos = vec3(0.0);
    var pdf = 0.0;
    if (m.flags & HAS_DIFFUSE) != 0u && wi_l.z > 0.0 {
        f_cos = m.diffuse_scale * wi_l.z;
        pdf = out.selection.y * cosine_hemisphere_pdf(wi_l.z);
    }
    if !(all_finite(f_cos) && is_finite(pdf) && pdf > 0.0) {
        return none;
    }
    return BsdfEval(f_cos, pdf);
}

// A sampled direction (`BsdfSample` without the reverse pdf); `valid` false where sampling
// failed.
struct BsdfSample {
    valid: bool,
    wi: vec3<f32>,
    f_cos: vec3<f32>,
    pdf_fwd: f32,
    kind: u32,
    eta: f32,
}

// A delta lobe's direction in local space, its weight and probability.
struct DeltaSample {
    wi: vec3<f32>,
    weight: vec3<f32>,
    prob: f32,
    transmitted: bool,
    eta: f32,
}

fn mirror_of(wo: vec3<f32>) -> vec3<f32> {
    return vec3(-wo.x, -wo.y, wo.z);
}

fn bsdf_sample(b: Bsdf, out: Outgoing, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    var s = BsdfSample(false, vec3(0.0), vec3(0.0), 0.0, KIND_SPECULAR, 1.0);
    let m = materials[b.material];
    let p = out.selection;
    // The lobe: the first k with u_lobe < p₀ + … + p_k among those with p_k > 0.
    var k = 4u;
    var start = 0.0;
    var cdf = 0.0;
    for (var i = 0u; i < 4u; i++) {
        if !(p[i] > 0.0) {
            continue;
        }
        k = i;
        start = cdf;
        if u_lobe < cdf + p[i] {
            break;
        }
        cdf += p[i];
    }
    if k == 4u {
        return s;
    }
    let pk = p[k];
    let u_sub = clamp((u_lobe - start) / pk, 0.0, ONE_MINUS_EPSILON);
    let wo = out.local;
    if k == 1u {
        // The diffuse lobe: a direction, valued by the whole BSDF.
        let wi_l = sample_cosine_hemisphere(u);
        if !(wi_l.z > 0.0) {
            return s;
        }
        let wi = normalized(world_on_side(b, out.back, wi_l));
        let eval = bsdf_eval(b, out, wi);
        if !(eval.pdf_fwd > 0.0) {
            return s;
        }
        s.wi = wi;
        s.f_cos = eval.f_cos;
        s.pdf_fwd = eval.pdf_fwd;
        s.kind = KIND_DIFFUSE;
        let transmitted = dot3(wi, b.n_g) * dot3(out.world, b.n_g) < 0.0;
        s.valid = all_finite(wi) && !transmitted;
        return s;
    }
    var d: DeltaSample;
    if k == 0u {
        d = DeltaSample(mirror_of(wo), schlick(m.f0, m.f90, wo.z), 1.0, false, 1.0);
    } else if k == 2u {
        let r = fresnel_dielectric(wo.z, out.eta);
        if u_sub < r {
            d = DeltaSample(mirror_of(wo), vec3(m.dielectric_weight * r), r, false, 1.0);
        } else {
            let wi = refract_z(wo, out.eta);
            if all(wi == vec3(0.0)) {
                return s;
            }
            let t = 1.0 - r;
            let scale = 1.0 / (out.eta * out.eta);
            d = DeltaSample(wi, m.dielectric_tint * (m.dielectric_weight * t * scale), t, true, out.eta);
        }
    } else {
        let r = thin_sheet_reflectance(fresnel_dielectric(wo.z, m.ior));
        if u_sub < r {
            d = DeltaSample(mirror_of(wo), vec3(m.thin_weight * r), r, false, 1.0);
        } else {
            d = DeltaSample(-wo, m.thin_tint * (m.thin_weight * (1.0 - r)), 1.0 - r, true, 1.0);
        }
    }
    let prob = pk * d.prob;
    if !(prob > 0.0) {
        return s;
    }
    let wi = normalized(world_on_side(b, out.back, d.wi));
    if consistent(b, out.back, wi, d.wi) < 0.0 {
        return s;
    }
    s.wi = wi;
    s.f_cos = d.weight;
    s.pdf_fwd = prob;
    s.eta = d.eta;
    let transmitted = dot3(wi, b.n_g) * dot3(out.world, b.n_g) < 0.0;
    s.valid = all_finite(d.weight) && is_finite(prob) && all_finite(wi)
        && transmitted == d.transmitted;
    return s;
}
