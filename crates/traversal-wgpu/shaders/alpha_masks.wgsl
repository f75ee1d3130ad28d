// Alpha masks: a masked triangle is opaque where alpha_factor × the filtered (bilinear or
// nearest-texel) alpha of its texture at the hit's texture coordinates reaches its cutoff
// (glTF MASK mode).

struct Mask {
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    uv2: vec2<f32>,
    alpha_factor: f32,
    cutoff: f32,
    texture: u32,
    pad: u32,
}

struct Texture {
    offset: u32,
    width: u32,
    height: u32,
    // Wrap mode along u in bits 0-7, along v in bits 8-15: 0 repeat, 1 mirrored, 2 clamp;
    // filter in bits 16-23: 0 bilinear, 1 nearest.
    sampler: u32,
}

const NO_MASK: u32 = 0xffffffffu;

// Per leaf-order triangle, its index in `masks` or NO_MASK.
@group(2) @binding(0) var<storage, read> leaf_masks: array<u32>;
@group(2) @binding(1) var<storage, read> masks: array<Mask>;
@group(2) @binding(2) var<storage, read> textures: array<Texture>;
// Alpha values, four to a word (lowest byte first).
@group(2) @binding(3) var<storage, read> texels: array<u32>;

fn wrap(i: i32, n: i32, mode: u32) -> i32 {
    if mode == 2u {
        return clamp(i, 0, n - 1);
    }
    if mode == 1u {
        let period = ((i % (2 * n)) + 2 * n) % (2 * n);
        return select(2 * n - 1 - period, period, period < n);
    }
    return ((i % n) + n) % n;
}

fn texel_alpha(texture: Texture, x: i32, y: i32) -> f32 {
    let index = texture.offset + u32(y) * texture.width + u32(x);
    let byte = (texels[index / 4u] >> (8u * (index % 4u))) & 0xffu;
    return f32(byte) / 255.0;
}

fn sample_alpha(texture: Texture, uv: vec2<f32>) -> f32 {
    let size = vec2<f32>(f32(texture.width), f32(texture.height));
    let w = i32(texture.width);
    let h = i32(texture.height);
    let wrap_u = texture.sampler & 0xffu;
    let wrap_v = (texture.sampler >> 8u) & 0xffu;
    if (texture.sampler >> 16u) == 1u {
        let i = vec2<i32>(floor(uv * size));
        return texel_alpha(texture, wrap(i.x, w, wrap_u), wrap(i.y, h, wrap_v));
    }
    let p = uv * size - 0.5;
    let p0 = floor(p);
    let f = p - p0;
    let i = vec2<i32>(p0);
    let x0 = wrap(i.x, w, wrap_u);
    let x1 = wrap(i.x + 1, w, wrap_u);
    let y0 = wrap(i.y, h, wrap_v);
    let y1 = wrap(i.y + 1, h, wrap_v);
    let top = mix(texel_alpha(texture, x0, y0), texel_alpha(texture, x1, y0), f.x);
    let bottom = mix(texel_alpha(texture, x0, y1), texel_alpha(texture, x1, y1), f.x);
    return mix(top, bottom, f.y);
}

fn is_opaque(leaf: u32, u: f32, v: f32) -> bool {
    let index = leaf_masks[leaf];
    if index == NO_MASK {
        return true;
    }
    let mask = masks[index];
    let uv = mask.uv0 * (1.0 - u - v) + mask.uv1 * u + mask.uv2 * v;
    var alpha = mask.alpha_factor;
    if mask.texture != NO_MASK {
        alpha *= sample_alpha(textures[mask.texture], uv);
    }
    return alpha >= mask.cutoff;
}
