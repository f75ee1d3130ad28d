// Materials that vary over their surface: textures (`Texture::sample` of vcm-scene's
// texture.rs, with its wrap modes, filters and sRGB table), the material's parameters at a
// point (`Material::bsdf_params`) and the mixture they make (`Mixture::new`), which the
// lobes of bsdf.wgsl then shade as they do the host's precomputed uniform materials.

// `Texture`: its texels' offset in `material_texels` and its size; flags: SRGB_TEXTURE,
// NEAREST_TEXTURE and the wrap modes of u (bits 2–3) and v (bits 4–5).
struct TextureInfo {
    offset: u32,
    width: u32,
    height: u32,
    flags: u32,
}

// `TextureRef`: a texture with its texture-coordinate transform (rows of the linear part
// in `linear`, `identity` 1 where there is none).
struct TextureRef {
    linear: vec4<f32>,
    offset: vec2<f32>,
    texture: u32,
    identity: u32,
}

// `Material`'s factors and texture references (NO_TEXTURE where a slot has none), in the
// order of REF_BASE_COLOR … REF_TRANSMISSION; flags: THIN_WALLED, UNIFORM_LOBES where the
// host has the lobes in `materials` already, BOUNDS_VOLUME (`Material::bounds_volume`).
struct MaterialInputs {
    base_color: vec4<f32>,
    specular_color: vec3<f32>,
    metallic: f32,
    // The absorption inside the solid a BOUNDS_VOLUME surface encloses.
    absorption: vec3<f32>,
    roughness: f32,
    specular: f32,
    transmission: f32,
    normal_scale: f32,
    ior: f32,
    flags: u32,
    refs: array<u32, 7>,
}

const SRGB_TEXTURE: u32 = 1u;
const NEAREST_TEXTURE: u32 = 2u;
const WRAP_REPEAT: u32 = 0u;
const WRAP_MIRRORED: u32 = 1u;
const NO_TEXTURE: u32 = 0xffffffffu;
const THIN_WALLED: u32 = 1u;
const UNIFORM_LOBES: u32 = 2u;
const BOUNDS_VOLUME: u32 = 4u;
const REF_BASE_COLOR: u32 = 0u;
const REF_METALLIC_ROUGHNESS: u32 = 1u;
const REF_NORMAL: u32 = 2u;
const REF_EMISSIVE: u32 = 3u;
const REF_SPECULAR: u32 = 4u;
const REF_SPECULAR_COLOR: u32 = 5u;
const REF_TRANSMISSION: u32 = 6u;

// Texel (x, y), decoded: sRGB channels through the CPU's table, alpha linear.
fn texel(t: TextureInfo, x: u32, y: u32) -> vec4<f32> {
    let p = material_texels[t.offset + y * t.width + x];
    let c = vec4(p & 0xffu, (p >> 8u) & 0xffu, (p >> 16u) & 0xffu, p >> 24u);
    if (t.flags & SRGB_TEXTURE) == 0u {
        return vec4<f32>(c) / 255.0;
    }
    let srgb = TABLE_SRGB;
    return vec4(tables[srgb + c.x], tables[srgb + c.y], tables[srgb + c.z], f32(c.w) / 255.0);
}

// `WrapMode::apply`.
fn wrap_texel(i: i32, size: u32, mode: u32) -> u32 {
    let n = i32(size);
    if mode == WRAP_REPEAT {
        return u32(((i % n) + n) % n);
    }
    if mode == WRAP_MIRRORED {
        let period = ((i % (2 * n)) + 2 * n) % (2 * n);
        return u32(select(2 * n - 1 - period, period, period < n));
    }
    return u32(clamp(i, 0, n - 1));
}

fn wrapped_texel(t: TextureInfo, x: i32, y: i32) -> vec4<f32> {
    let wrap_u = (t.flags >> 2u) & 3u;
    let wrap_v = (t.flags >> 4u) & 3u;
    return texel(t, wrap_texel(x, t.width, wrap_u), wrap_texel(y, t.height, wrap_v));
}

// glam's `Vec4::lerp`.
fn lerp4(a: vec4<f32>, b: vec4<f32>, s: f32) -> vec4<f32> {
    return a * (1.0 - s) + b * s;
}

// `Texture::sample` at `uv` (the CPU scales uv in f64; here in f32, so texel positions may
// differ in their last bits).
fn sample_texture(index: u32, uv: vec2<f32>) -> vec4<f32> {
    let t = texture_infos[index];
    if !(is_finite(uv.x) && is_finite(uv.y)) {
        return texel(t, 0u, 0u);
    }
    let x = uv.x * f32(t.width);
    let y = uv.y * f32(t.height);
    if (t.flags & NEAREST_TEXTURE) != 0u {
        return wrapped_texel(t, i32(floor(x)), i32(floor(y)));
    }
    let xb = x - 0.5;
    let yb = y - 0.5;
    let x0 = floor(xb);
    let y0 = floor(yb);
    let fx = xb - x0;
    let fy = yb - y0;
    let xi = i32(x0);
    let yi = i32(y0);
    let top = lerp4(wrapped_texel(t, xi, yi), wrapped_texel(t, xi + 1, yi), fx);
    let bottom = lerp4(wrapped_texel(t, xi, yi + 1), wrapped_texel(t, xi + 1, yi + 1), fx);
    return lerp4(top, bottom, fy);
}

// `TextureRef::sample` for reference `r` (white where there is none: `lookup`).
fn lookup(r: u32, uv: vec2<f32>) -> vec4<f32> {
    if r == NO_TEXTURE {
        return vec4(1.0);
    }
    let t = texture_refs[r];
    var at = uv;
    if t.identity == 0u {
        at = vec2(t.linear.x, t.linear.y) * uv.x + vec2(t.linear.z, t.linear.w) * uv.y + t.offset;
    }
    return sample_texture(t.texture, at);
}

// The tangent-space normal of the material's normal map at `uv` (`tangent_space_normal`),
// or a zero vector.
fn tangent_space_normal(inputs: MaterialInputs, uv: vec2<f32>) -> vec3<f32> {
    let c = lookup(inputs.refs[REF_NORMAL], uv).xyz * 2.0 - vec3(1.0);
    return try_normalized(vec3(c.x * inputs.normal_scale, c.y * inputs.normal_scale, c.z));
}

// The material's inputs at `uv` (`BsdfParams`).
struct BsdfParams {
    base_color: vec3<f32>,
    metallic: f32,
    roughness: f32,
    specular: f32,
    specular_color: vec3<f32>,
    transmission: f32,
    ior: f32,
    thin_walled: bool,
}

fn bsdf_params(inputs: MaterialInputs, uv: vec2<f32>) -> BsdfParams {
    let base = inputs.base_color * lookup(inputs.refs[REF_BASE_COLOR], uv);
    let mr = lookup(inputs.refs[REF_METALLIC_ROUGHNESS], uv);
    let specular = inputs.specular * lookup(inputs.refs[REF_SPECULAR], uv).w;
    let specular_color = inputs.specular_color * lookup(inputs.refs[REF_SPECULAR_COLOR], uv).xyz;
    let transmission = inputs.transmission * lookup(inputs.refs[REF_TRANSMISSION], uv).x;
    return BsdfParams(
        base.xyz,
        clamp(inputs.metallic * mr.z, 0.0, 1.0),
        clamp(inputs.roughness * mr.y, 0.0, 1.0),
        clamp(specular, 0.0, 1.0),
        max(specular_color, vec3(0.0)),
        clamp(transmission, 0.0, 1.0),
        inputs.ior,
        (inputs.flags & THIN_WALLED) != 0u,
    );
}

// `sanitize` of mixture.rs: finite values clamped, others the default.
fn sanitize(x: f32, default_value: f32, lo: f32, hi: f32) -> f32 {
    return select(default_value, clamp(x, lo, hi), is_finite(x));
}

fn sanitize3(v: vec3<f32>, default_value: f32, lo: f32, hi: f32) -> vec3<f32> {
    return vec3(
        sanitize(v.x, default_value, lo, hi),
        sanitize(v.y, default_value, lo, hi),
        sanitize(v.z, default_value, lo, hi),
    );
}

// A row of the albedo tables and the fraction toward the next; NO_ROW for a mirror or a
// lobe that reflects nothing.
struct AlbedoRow {
    row: u32,
    t: f32,
}

// The albedo tables' row for GGX width α (`SpecularAlbedo::new`).
fn albedo_row(f0: vec3<f32>, f90: vec3<f32>, alpha: f32) -> AlbedoRow {
    if !(alpha > 0.0 && max_element(max(f0, f90)) > 0.0) {
        return AlbedoRow(NO_ROW, 0.0);
    }
    let node = sqrt(max((sqrt(alpha) - R_MIN) / (1.0 - R_MIN), 0.0));
    let s = clamp(node, 0.0, 1.0) * f32(ALBEDO_ROWS - 1u);
    let i = min(u32(s), ALBEDO_ROWS - 2u);
    return AlbedoRow(i, s - f32(i));
}

// The cosine-weighted average of the albedo (`SpecularAlbedo::average`).
fn albedo_average(f0: vec3<f32>, f90: vec3<f32>, row: u32, t: f32) -> vec3<f32> {
    if row == NO_ROW {
        return f0 * (20.0f / 21.0f) + f90 / 21.0f;
    }
    let a = lerp(tables[TABLE_A_AVG + row], tables[TABLE_A_AVG + row + 1u], t);
    let b = lerp(tables[TABLE_B_AVG + row], tables[TABLE_B_AVG + row + 1u], t);
    return f0 * a + f90 * b;
}

// The lobes that `p` makes (`Mixture::new`), seen from one side unless `double_sided`.
fn mixture_new(p: BsdfParams, double_sided: bool) -> Material {
    var m: Material;
    let base = sanitize3(p.base_color, 0.0, 0.0, 1.0);
    let metallic = sanitize(p.metallic, 0.0, 0.0, 1.0);
    let roughness = sanitize(p.roughness, 1.0, 0.0, 1.0);
    let specular = sanitize(p.specular, 1.0, 0.0, 1.0);
    let specular_color = sanitize3(p.specular_color, 1.0, 0.0, 3.40282347e38);
    let transmission = sanitize(p.transmission, 0.0, 0.0, 1.0);
    let ior = select(1.5, p.ior, is_finite(p.ior) && p.ior >= 1.0);
    let alpha = select(0.0, max(roughness * roughness, MIN_ALPHA), roughness > 0.0);
    let w_interface = (1.0 - metallic) * transmission;
    let w_base = (1.0 - metallic) * (1.0 - transmission);
    let q = (ior - 1.0) / (ior + 1.0);
    let r0 = q * q;
    let layer_f0 = min(r0 * specular_color, vec3(1.0)) * specular;
    let layer_f90 = vec3(specular);
    let layer_row = albedo_row(layer_f0, layer_f90, alpha);
    let f0 = metallic * base + w_base * layer_f0;
    let f90 = metallic * vec3(1.0) + w_base * layer_f90;
    let diffuse_albedo = w_base * base;
    let index_matched = abs(ior - 1.0) < 1e-4;
    m.ior = ior;
    m.flags = select(0u, DOUBLE_SIDED, double_sided);
    m.specular_row = NO_ROW;
    m.layer_row = NO_ROW;
    if max_element(max(f0, f90)) > 0.0 {
        m.flags |= HAS_SPECULAR;
        m.f0 = f0;
        m.f90 = f90;
        m.specular_alpha = alpha;
        let row = albedo_row(f0, f90, alpha);
        m.specular_row = row.row;
        m.specular_row_t = row.t;
    }
    if max_element(diffuse_albedo) > 0.0 {
        m.flags |= HAS_DIFFUSE;
        m.diffuse_albedo = diffuse_albedo;
        let transmitted = vec3(1.0) - albedo_average(layer_f0, layer_f90, layer_row.row, layer_row.t);
        m.diffuse_scale = select(vec3(0.0), diffuse_albedo * FRAC_1_PI / transmitted, transmitted > vec3(1e-6));
        if max_element(max(layer_f0, layer_f90)) > 0.0 {
            m.flags |= HAS_LAYER;
            m.layer_f0 = layer_f0;
            m.layer_f90 = layer_f90;
            m.layer_row = layer_row.row;
            m.layer_row_t = layer_row.t;
        }
    }
    if w_interface > 0.0 && !p.thin_walled {
        m.flags |= HAS_DIELECTRIC;
        m.dielectric_weight = w_interface;
        m.dielectric_tint = base;
        m.dielectric_alpha = select(alpha, 0.0, index_matched);
    }
    if w_interface > 0.0 && p.thin_walled {
        m.flags |= HAS_THIN;
        m.thin_weight = w_interface;
        m.thin_tint = base;
        m.thin_alpha = alpha;
    }
    // Only a plain Lambert base alone selects the same lobe from every direction.
    if (m.flags & (HAS_SPECULAR | HAS_DIELECTRIC | HAS_THIN | HAS_LAYER)) == 0u {
        m.flags |= CONSTANT_SELECTION;
        let w = max(mean3(diffuse_albedo), 0.0);
        let selected = select(0.0, w / w, w > 0.0 && is_finite(w));
        m.selection = vec4(0.0, select(0.0, selected, (m.flags & HAS_DIFFUSE) != 0u), 0.0, 0.0);
    }
    return m;
}
