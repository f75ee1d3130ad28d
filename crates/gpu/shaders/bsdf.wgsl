// The surface scattering model of vcm-scene (bsdf/), radiance or importance transport
// (`importance`: light paths) with forward pdfs and, where asked (`reverse`), reverse ones:
// the glTF metallic-roughness mixture of a Schlick reflection lobe (mirror or GGX), a
// diffuse base (plain Lambert or energy-compensated under a specular layer) and a dielectric
// interface (thick or thin-walled, smooth or GGX). Each function is the CPU's of the same
// name, in the same order of operations, so that a path takes the CPU's decisions.

const GRAZING_COS: f32 = 1e-6;
const PI: f32 = 3.1415927;
const FRAC_1_PI: f32 = 0.31830987;
const FRAC_PI_4: f32 = 0.7853982;
// 1 − ε/2: the largest f32 below 1.
const ONE_MINUS_EPSILON: f32 = 0.99999994;
// The specular lobe's smallest selection weight, relative to its largest reflectance.
const MIN_SELECTION: f32 = 1e-3;
// A Schlick albedo without a table row (a mirror's).
const NO_ROW: u32 = 0xffffffffu;
// The albedo tables' columns (over √μ) and rows (over the roughness); the host defines
// ALBEDO_COLUMNS and ALBEDO_ROWS.

// `Material::flags` bits: which lobes exist, and how the material is seen.
const HAS_SPECULAR: u32 = 1u;
const HAS_DIFFUSE: u32 = 2u;
const HAS_DIELECTRIC: u32 = 4u;
const HAS_THIN: u32 = 8u;
const DOUBLE_SIDED: u32 = 16u;
const CONSTANT_SELECTION: u32 = 32u;
const HAS_LAYER: u32 = 64u;

// `LobeKind`.
const KIND_DIFFUSE: u32 = 0u;
const KIND_GLOSSY: u32 = 1u;
const KIND_SPECULAR: u32 = 2u;

// One material's lobes, `FlatLobes` with the material's sidedness (`GpuMaterial` on the
// host). An α of 0 is a smooth (Dirac delta) lobe.
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
    specular_alpha: f32,
    thin_tint: vec3<f32>,
    dielectric_alpha: f32,
    // The diffuse base's specular layer (its albedo compensates the base's energy).
    layer_f0: vec3<f32>,
    thin_alpha: f32,
    layer_f90: vec3<f32>,
    specular_row_t: f32,
    selection: vec4<f32>,
    specular_row: u32,
    layer_row: u32,
    layer_row_t: f32,
    unused: u32,
}

fn infinity() -> f32 {
    return bitcast<f32>(0x7f800000u);
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

// glam's `try_normalize`, with `fallback` where it gives `None`.
fn normalized_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let rcp = 1.0 / sqrt(dot3(v, v));
    if is_finite(rcp) && rcp > 0.0 {
        return v * rcp;
    }
    return fallback;
}

// glam's `try_normalize`: a zero vector where it gives `None`.
fn try_normalized(v: vec3<f32>) -> vec3<f32> {
    return normalized_or(v, vec3(0.0));
}

fn is_zero(v: vec3<f32>) -> bool {
    return all(v == vec3(0.0));
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

fn reflect(wo: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return 2.0 * dot3(wo, n) * n - wo;
}

// The refracted direction through the normal n, or a zero vector under total internal
// reflection.
fn refract(wo: vec3<f32>, n: vec3<f32>, eta: f32) -> vec3<f32> {
    let cos_i = dot3(wo, n);
    let sin2_t = max(1.0 - cos_i * cos_i, 0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return vec3(0.0);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    return -wo / eta + (cos_i / eta - cos_t) * n;
}

fn mirror_of(wo: vec3<f32>) -> vec3<f32> {
    return vec3(-wo.x, -wo.y, wo.z);
}

// The isotropic GGX distribution of width α (microfacet.rs).
fn ggx_d(alpha: f32, m: vec3<f32>) -> f32 {
    if m.z <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let t = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
    return 1.0 / (PI * a2 * t * t);
}

fn ggx_lambda(alpha: f32, w: vec3<f32>) -> f32 {
    let z2 = w.z * w.z;
    if z2 == 0.0 {
        return infinity();
    }
    let tan2 = (w.x * w.x + w.y * w.y) / z2;
    return 0.5 * (sqrt(1.0 + alpha * alpha * tan2) - 1.0);
}

fn ggx_g1(alpha: f32, w: vec3<f32>) -> f32 {
    return 1.0 / (1.0 + ggx_lambda(alpha, w));
}

fn ggx_g2(alpha: f32, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    return 1.0 / (1.0 + ggx_lambda(alpha, wo) + ggx_lambda(alpha, wi));
}

fn ggx_visible_pdf(alpha: f32, wo: vec3<f32>, m: vec3<f32>) -> f32 {
    return ggx_g1(alpha, wo) * max(dot3(wo, m), 0.0) * ggx_d(alpha, m) / wo.z;
}

// A visible normal (Dupuy & Benyoub 2023), or a zero vector where sampling fails.
fn ggx_sample_visible(alpha: f32, wo: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let wo_std = normalized(vec3(wo.x * alpha, wo.y * alpha, wo.z));
    let phi = 2.0 * PI * u.x;
    let z = (1.0 - u.y) * (1.0 + wo_std.z) - wo_std.z;
    let sin_theta = sqrt(clamp(1.0 - z * z, 0.0, 1.0));
    let c = vec3(sin_theta * cos(phi), sin_theta * sin(phi), z);
    let h = c + wo_std;
    let m = try_normalized(vec3(h.x * alpha, h.y * alpha, max(h.z, 0.0)));
    return select(vec3(0.0), m, m.z > 0.0);
}

// The directional albedo of a Schlick GGX lobe, `SpecularAlbedo::directional`: bilinear in
// the tables (A, then B, in `tables`) at row `row` + `row_t`.
fn albedo_directional(f0: vec3<f32>, f90: vec3<f32>, row: u32, row_t: f32, mu: f32) -> vec3<f32> {
    if row == NO_ROW {
        return schlick(f0, f90, mu);
    }
    let s = clamp(sqrt(max(mu, 0.0)), 0.0, 1.0) * f32(ALBEDO_COLUMNS - 1u);
    let j = min(u32(s), ALBEDO_COLUMNS - 2u);
    let tj = s - f32(j);
    let b_start = ALBEDO_ROWS * ALBEDO_COLUMNS;
    let i = row * ALBEDO_COLUMNS + j;
    let next = i + ALBEDO_COLUMNS;
    let a = lerp(
        lerp(tables[i], tables[i + 1u], tj),
        lerp(tables[next], tables[next + 1u], tj),
        row_t,
    );
    let b = lerp(
        lerp(tables[b_start + i], tables[b_start + i + 1u], tj),
        lerp(tables[b_start + next], tables[b_start + next + 1u], tj),
        row_t,
    );
    return f0 * a + f90 * b;
}

fn lerp(a: f32, b: f32, t: f32) -> f32 {
    return a + (b - a) * t;
}

// 1 − E(μ) of the diffuse base's specular layer (1 without one).
fn layer_transmission(m: Material, mu: f32) -> vec3<f32> {
    if (m.flags & HAS_LAYER) == 0u {
        return vec3(1.0);
    }
    let e = albedo_directional(m.layer_f0, m.layer_f90, m.layer_row, m.layer_row_t, mu);
    return max(vec3(1.0) - e, vec3(0.0));
}

// A BSDF placed at a surface point (`Bsdf`).
struct Bsdf {
    frame: Frame,
    n_g: vec3<f32>,
    m: Material,
}

fn transmits(m: Material) -> bool {
    return (m.flags & (HAS_DIELECTRIC | HAS_THIN)) != 0u;
}

fn has_non_delta(m: Material) -> bool {
    let glossy = ((m.flags & HAS_SPECULAR) != 0u && m.specular_alpha > 0.0)
        || ((m.flags & HAS_DIELECTRIC) != 0u && m.dielectric_alpha > 0.0)
        || ((m.flags & HAS_THIN) != 0u && m.thin_alpha > 0.0);
    return (m.flags & HAS_DIFFUSE) != 0u || glossy;
}

fn bsdf_new(m: Material, n_g: vec3<f32>, n_s_in: vec3<f32>) -> Bsdf {
    var n_s = n_s_in;
    if !all_finite(n_s) || dot3(n_s, n_s) < 0.25 {
        n_s = n_g;
    } else if dot3(n_s, n_g) < 0.0 {
        n_s = -n_s;
    }
    return Bsdf(frame_from_z(n_s), n_g, m);
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
        let e = albedo_directional(m.f0, m.f90, m.specular_row, m.specular_row_t, wo.z);
        w.x = max(max(mean3(e), MIN_SELECTION * max_element(max(m.f0, m.f90))), 0.0);
    }
    if (m.flags & HAS_DIFFUSE) != 0u {
        w.y = max(mean3(m.diffuse_albedo * layer_transmission(m, wo.z)), 0.0);
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
    let m = b.m;
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
    out.selection = selection(m, out.local, out.eta);
    return out;
}

// Lobe selection probabilities at local `wo` (`Mixture::selection`): the material's own
// where they do not depend on `wo`.
fn selection(m: Material, wo: vec3<f32>, eta: f32) -> vec4<f32> {
    if (m.flags & CONSTANT_SELECTION) != 0u {
        return m.selection;
    }
    return selection_at(m, wo, eta);
}

// |cos| of `wi` with the geometric normal where `wi` and its local form lie on the same
// side (`Bsdf::consistent`), else a negative number.
fn consistent(b: Bsdf, back: bool, wi: vec3<f32>, wi_local: vec3<f32>) -> f32 {
    let cos_gi = select(dot3(wi, b.n_g), -dot3(wi, b.n_g), back);
    let ok = abs(cos_gi) >= GRAZING_COS && abs(wi_local.z) >= GRAZING_COS
        && (cos_gi > 0.0) == (wi_local.z > 0.0);
    return select(-1.0, abs(cos_gi), ok);
}

// f·|cos| and the forward pdf (`BsdfEval`, `Pdfs::Forward`; of one lobe, its pdf).
struct BsdfEval {
    f_cos: vec3<f32>,
    pdf_fwd: f32,
}

fn specular_eval(m: Material, wo: vec3<f32>, wi: vec3<f32>) -> BsdfEval {
    let alpha = m.specular_alpha;
    let mh = try_normalized(wo + wi);
    if alpha == 0.0 || wi.z <= 0.0 || is_zero(mh) {
        return BsdfEval(vec3(0.0), 0.0);
    }
    let d = ggx_d(alpha, mh);
    let f_cos = schlick(m.f0, m.f90, dot3(wo, mh)) * (d * ggx_g2(alpha, wo, wi) / (4.0 * wo.z));
    return BsdfEval(f_cos, ggx_visible_pdf(alpha, wo, mh) / (4.0 * dot3(wo, mh)));
}

fn diffuse_eval(m: Material, wo: vec3<f32>, wi: vec3<f32>) -> BsdfEval {
    if wi.z <= 0.0 {
        return BsdfEval(vec3(0.0), 0.0);
    }
    let f = m.diffuse_scale * layer_transmission(m, wo.z) * layer_transmission(m, wi.z);
    return BsdfEval(f * wi.z, cosine_hemisphere_pdf(wi.z));
}

// The half vector of a refraction from wo into wi, or a zero vector (`transmission_half_vector`).
fn transmission_half_vector(wo: vec3<f32>, wi: vec3<f32>, eta: f32) -> vec3<f32> {
    var mh = try_normalized(wo + eta * wi);
    if is_zero(mh) {
        return mh;
    }
    if mh.z < 0.0 {
        mh = -mh;
    }
    return select(vec3(0.0), mh, dot3(wo, mh) > 0.0 && dot3(wi, mh) < 0.0);
}

// Radiance scaling of refracted transport, 1/η², or 1 for importance (`refraction_scale`).
fn refraction_scale(eta: f32, importance: bool) -> f32 {
    return select(1.0 / (eta * eta), 1.0, importance);
}

fn dielectric_eval(m: Material, wo: vec3<f32>, wi: vec3<f32>, eta: f32, importance: bool) -> BsdfEval {
    let none = BsdfEval(vec3(0.0), 0.0);
    let alpha = m.dielectric_alpha;
    if alpha == 0.0 {
        return none;
    }
    if wi.z > 0.0 {
        let mh = try_normalized(wo + wi);
        if is_zero(mh) {
            return none;
        }
        let f = fresnel_dielectric(dot3(wo, mh), eta);
        let f_cos = m.dielectric_weight * f * ggx_d(alpha, mh) * ggx_g2(alpha, wo, wi) / (4.0 * wo.z);
        return BsdfEval(vec3(f_cos), ggx_visible_pdf(alpha, wo, mh) * f / (4.0 * dot3(wo, mh)));
    }
    let mh = transmission_half_vector(wo, wi, eta);
    if is_zero(mh) {
        return none;
    }
    let wo_m = dot3(wo, mh);
    let wi_m = dot3(wi, mh);
    let root = wi_m + wo_m / eta;
    let denom = root * root;
    if denom <= 0.0 {
        return none;
    }
    let t = 1.0 - fresnel_dielectric(wo_m, eta);
    let f_cos = t * ggx_d(alpha, mh) * ggx_g2(alpha, wo, wi) * abs(wi_m * wo_m) / (wo.z * denom)
        * refraction_scale(eta, importance) * m.dielectric_weight;
    let pdf = ggx_visible_pdf(alpha, wo, mh) * abs(wi_m) / denom * t;
    return BsdfEval(m.dielectric_tint * f_cos, pdf);
}

fn thin_eval(m: Material, wo: vec3<f32>, wi: vec3<f32>) -> BsdfEval {
    let alpha = m.thin_alpha;
    let transmitted = wi.z < 0.0;
    let wr = select(wi, vec3(wi.x, wi.y, -wi.z), transmitted);
    let mh = try_normalized(wo + wr);
    if alpha == 0.0 || is_zero(mh) {
        return BsdfEval(vec3(0.0), 0.0);
    }
    let r = thin_sheet_reflectance(fresnel_dielectric(dot3(wo, mh), m.ior));
    let fresnel = select(r, 1.0 - r, transmitted);
    let tint = select(vec3(1.0), m.thin_tint, transmitted);
    let f_cos = m.thin_weight * fresnel * ggx_d(alpha, mh) * ggx_g2(alpha, wo, wr) / (4.0 * wo.z);
    return BsdfEval(tint * f_cos, ggx_visible_pdf(alpha, wo, mh) * fresnel / (4.0 * dot3(wo, mh)));
}

// Every lobe's f·|cos| summed, and the selection-weighted pdf (`Mixture::eval`).
fn mixture_eval(
    m: Material,
    p: vec4<f32>,
    wo: vec3<f32>,
    wi: vec3<f32>,
    eta: f32,
    importance: bool,
) -> BsdfEval {
    var f_cos = vec3(0.0);
    var pdf = 0.0;
    if (m.flags & HAS_SPECULAR) != 0u {
        let e = specular_eval(m, wo, wi);
        f_cos += e.f_cos;
        pdf += p.x * e.pdf_fwd;
    }
    if (m.flags & HAS_DIFFUSE) != 0u {
        let e = diffuse_eval(m, wo, wi);
        f_cos += e.f_cos;
        pdf += p.y * e.pdf_fwd;
    }
    if (m.flags & HAS_DIELECTRIC) != 0u {
        let e = dielectric_eval(m, wo, wi, eta, importance);
        f_cos += e.f_cos;
        pdf += p.z * e.pdf_fwd;
    }
    if (m.flags & HAS_THIN) != 0u {
        let e = thin_eval(m, wo, wi);
        f_cos += e.f_cos;
        pdf += p.w * e.pdf_fwd;
    }
    return BsdfEval(f_cos, pdf);
}

// Veach's shading-normal correction of importance transport (`Bsdf::adjoint`, Veach 1997
// §5.3): f·|wi·n_s| becomes f·|wo·n_s||wi·n_g| / |wo·n_g|; `cos_gi` = |wi·n_g|.
fn adjoint(
    b: Bsdf,
    f_cos: vec3<f32>,
    importance: bool,
    out: Outgoing,
    wi_local: vec3<f32>,
    cos_gi: f32,
) -> vec3<f32> {
    if !importance {
        return f_cos;
    }
    return f_cos * (out.local.z * cos_gi / (abs(dot3(out.world, b.n_g)) * abs(wi_local.z)));
}

// The BSDF's value at a pair of directions (`BsdfEval`): f·|cos|, the forward pdf and the
// reverse pdf (0 unless asked for).
struct Evaluation {
    f_cos: vec3<f32>,
    pdf_fwd: f32,
    pdf_rev: f32,
}

// The pdf where it is positive and finite, else 0 (`Bsdf::mixture_pdf`).
fn positive_pdf(pdf: f32) -> f32 {
    return select(0.0, pdf, is_finite(pdf) && pdf > 0.0);
}

// The solid-angle pdf of sampling `wi` from `wo` (`Bsdf::pdf`).
fn bsdf_pdf(b: Bsdf, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let out = outgoing(b, wo);
    if !out.valid {
        return 0.0;
    }
    let wi_l = local_on_side(b, out.back, wi);
    if consistent(b, out.back, wi, wi_l) < 0.0 {
        return 0.0;
    }
    return positive_pdf(mixture_eval(b.m, out.selection, out.local, wi_l, out.eta, false).pdf_fwd);
}

// The pdf of sampling `out`'s direction back from `wi` (`Bsdf::reverse_pdf`), `wi_l` its
// local form and `cos_gi` its |cos| with the geometric normal: a reflection keeps `out`'s
// side and η, the rest takes the general way.
fn reverse_pdf(b: Bsdf, out: Outgoing, wi: vec3<f32>, wi_l: vec3<f32>, cos_gi: f32) -> f32 {
    if !(wi_l.z > 0.0 && cos_gi > GRAZING_COS) {
        return bsdf_pdf(b, wi, out.world);
    }
    let p = selection(b.m, wi_l, out.eta);
    return positive_pdf(mixture_eval(b.m, p, wi_l, out.local, out.eta, false).pdf_fwd);
}

fn bsdf_eval(b: Bsdf, out: Outgoing, wi: vec3<f32>, importance: bool, reverse: bool) -> Evaluation {
    let none = Evaluation(vec3(0.0), 0.0, 0.0);
    let wi_l = local_on_side(b, out.back, wi);
    let cos_gi = consistent(b, out.back, wi, wi_l);
    if cos_gi < 0.0 {
        return none;
    }
    let e = mixture_eval(b.m, out.selection, out.local, wi_l, out.eta, importance);
    let f_cos = adjoint(b, e.f_cos, importance, out, wi_l, cos_gi);
    if !(all_finite(f_cos) && is_finite(e.pdf_fwd) && e.pdf_fwd > 0.0) {
        return none;
    }
    var pdf_rev = 0.0;
    if reverse {
        pdf_rev = reverse_pdf(b, out, wi, wi_l, cos_gi);
    }
    return Evaluation(f_cos, e.pdf_fwd, pdf_rev);
}

// The probability of sampling the same delta of lobe `k` (`transmitted` or not) back from
// `wi` to `wo` (`Bsdf::delta_pdf_rev`, `Mixture::delta_pdf`).
fn delta_pdf_rev(b: Bsdf, wo: vec3<f32>, wi: vec3<f32>, k: u32, transmitted: bool) -> f32 {
    let rev = outgoing(b, wi);
    if !rev.valid {
        return 0.0;
    }
    let wi_rev = local_on_side(b, rev.back, wo);
    if abs(wi_rev.z) < GRAZING_COS {
        return 0.0;
    }
    let m = b.m;
    var prob = 0.0;
    switch k {
        case 0u: {
            prob = select(0.0, 1.0, m.specular_alpha == 0.0 && !transmitted);
        }
        case 2u: {
            let r = fresnel_dielectric(rev.local.z, rev.eta);
            prob = select(0.0, select(r, 1.0 - r, transmitted), m.dielectric_alpha == 0.0);
        }
        case 3u: {
            let r = thin_sheet_reflectance(fresnel_dielectric(rev.local.z, m.ior));
            prob = select(0.0, select(r, 1.0 - r, transmitted), m.thin_alpha == 0.0);
        }
        default: {}
    }
    return rev.selection[k] * prob;
}

// A sampled direction (`BsdfSample`, the reverse pdf 0 unless asked for); `valid` false where
// sampling failed.
struct BsdfSample {
    valid: bool,
    wi: vec3<f32>,
    f_cos: vec3<f32>,
    pdf_fwd: f32,
    pdf_rev: f32,
    kind: u32,
    eta: f32,
}

// What one lobe sampled, in local space (`LobeSample`): a direction the whole mixture
// values, or a delta with its weight and probability; `ok` false where it failed.
struct LobeSample {
    ok: bool,
    delta: bool,
    wi: vec3<f32>,
    weight: vec3<f32>,
    prob: f32,
    transmitted: bool,
    eta: f32,
}

fn direction_sample(wi: vec3<f32>, ok: bool) -> LobeSample {
    return LobeSample(ok, false, wi, vec3(0.0), 0.0, false, 1.0);
}

fn delta_sample(wi: vec3<f32>, weight: vec3<f32>, prob: f32, transmitted: bool, eta: f32) -> LobeSample {
    return LobeSample(true, true, wi, weight, prob, transmitted, eta);
}

fn specular_sample(m: Material, wo: vec3<f32>, u: vec2<f32>) -> LobeSample {
    if m.specular_alpha == 0.0 {
        return delta_sample(mirror_of(wo), schlick(m.f0, m.f90, wo.z), 1.0, false, 1.0);
    }
    let mh = ggx_sample_visible(m.specular_alpha, wo, u);
    let wi = reflect(wo, mh);
    return direction_sample(wi, !is_zero(mh) && wi.z > 0.0);
}

fn dielectric_sample(
    m: Material,
    wo: vec3<f32>,
    eta: f32,
    u_sub: f32,
    u: vec2<f32>,
    importance: bool,
) -> LobeSample {
    let alpha = m.dielectric_alpha;
    if alpha == 0.0 {
        let r = fresnel_dielectric(wo.z, eta);
        if u_sub < r {
            return delta_sample(mirror_of(wo), vec3(m.dielectric_weight * r), r, false, 1.0);
        }
        let wi = refract(wo, vec3(0.0, 0.0, 1.0), eta);
        let t = 1.0 - r;
        let weight = m.dielectric_tint * (m.dielectric_weight * t * refraction_scale(eta, importance));
        return LobeSample(!is_zero(wi), true, wi, weight, t, true, eta);
    }
    let mh = ggx_sample_visible(alpha, wo, u);
    if is_zero(mh) {
        return direction_sample(vec3(0.0), false);
    }
    let f = fresnel_dielectric(dot3(wo, mh), eta);
    if u_sub < f {
        let wi = reflect(wo, mh);
        return direction_sample(wi, wi.z > 0.0);
    }
    let wi = refract(wo, mh, eta);
    return direction_sample(wi, !is_zero(wi) && wi.z < 0.0);
}

fn thin_sample(m: Material, wo: vec3<f32>, u_sub: f32, u: vec2<f32>) -> LobeSample {
    let alpha = m.thin_alpha;
    if alpha == 0.0 {
        let r = thin_sheet_reflectance(fresnel_dielectric(wo.z, m.ior));
        if u_sub < r {
            return delta_sample(mirror_of(wo), vec3(m.thin_weight * r), r, false, 1.0);
        }
        return delta_sample(-wo, m.thin_tint * (m.thin_weight * (1.0 - r)), 1.0 - r, true, 1.0);
    }
    let mh = ggx_sample_visible(alpha, wo, u);
    let wr = reflect(wo, mh);
    if is_zero(mh) || wr.z <= 0.0 {
        return direction_sample(vec3(0.0), false);
    }
    let r = thin_sheet_reflectance(fresnel_dielectric(dot3(wo, mh), m.ior));
    return direction_sample(select(vec3(wr.x, wr.y, -wr.z), wr, u_sub < r), true);
}

// The class of lobe k (`Lobe::kind`).
fn lobe_kind(m: Material, k: u32) -> u32 {
    var alpha = m.thin_alpha;
    switch k {
        case 0u: {
            alpha = m.specular_alpha;
        }
        case 1u: {
            return KIND_DIFFUSE;
        }
        case 2u: {
            alpha = m.dielectric_alpha;
        }
        default: {}
    }
    return select(KIND_SPECULAR, KIND_GLOSSY, alpha > 0.0);
}

fn bsdf_sample(
    b: Bsdf,
    out: Outgoing,
    u_lobe: f32,
    u: vec2<f32>,
    importance: bool,
    reverse: bool,
) -> BsdfSample {
    var s = BsdfSample(false, vec3(0.0), vec3(0.0), 0.0, 0.0, KIND_SPECULAR, 1.0);
    let m = b.m;
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
    var lobe: LobeSample;
    switch k {
        case 0u: {
            lobe = specular_sample(m, wo, u);
        }
        case 1u: {
            let wi = sample_cosine_hemisphere(u);
            lobe = direction_sample(wi, wi.z > 0.0);
        }
        case 2u: {
            lobe = dielectric_sample(m, wo, out.eta, u_sub, u, importance);
        }
        default: {
            lobe = thin_sample(m, wo, u_sub, u);
        }
    }
    if !lobe.ok {
        return s;
    }
    s.kind = lobe_kind(m, k);
    if lobe.delta {
        let prob = pk * lobe.prob;
        if !(prob > 0.0) {
            return s;
        }
        lobe.prob = prob;
    } else {
        lobe.transmitted = lobe.wi.z < 0.0;
        lobe.eta = select(1.0, out.eta, lobe.transmitted && (m.flags & HAS_DIELECTRIC) != 0u);
    }
    let wi = normalized(world_on_side(b, out.back, lobe.wi));
    if lobe.delta {
        let cos_gi = consistent(b, out.back, wi, lobe.wi);
        if cos_gi < 0.0 {
            return s;
        }
        s.f_cos = adjoint(b, lobe.weight, importance, out, lobe.wi, cos_gi);
        s.pdf_fwd = lobe.prob;
        if reverse {
            s.pdf_rev = delta_pdf_rev(b, out.world, wi, k, lobe.transmitted);
        }
    } else {
        let eval = bsdf_eval(b, out, wi, importance, reverse);
        if !(eval.pdf_fwd > 0.0) {
            return s;
        }
        s.f_cos = eval.f_cos;
        s.pdf_fwd = eval.pdf_fwd;
        s.pdf_rev = eval.pdf_rev;
    }
    s.wi = wi;
    s.eta = lobe.eta;
    let transmitted = dot3(wi, b.n_g) * dot3(out.world, b.n_g) < 0.0;
    s.valid = all_finite(s.f_cos) && is_finite(s.pdf_fwd) && s.pdf_fwd > 0.0 && all_finite(wi)
        && transmitted == lobe.transmitted;
    return s;
}
