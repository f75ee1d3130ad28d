// The CPU's random numbers on the GPU: the same keyed, Owen-scrambled Sobol pairs
// (vcm-scene's sampling/sobol.rs) from the same 64-bit key hashes (sampling/rng.rs), so that
// a path draws the same numbers on both. WGSL has no 64-bit integers: a u64 is a vec2<u32>
// (x the low word, y the high word).

// The full 64-bit product of two u32, from 16-bit halves.
fn mul_wide(a: u32, b: u32) -> vec2<u32> {
    let a_lo = a & 0xffffu;
    let a_hi = a >> 16u;
    let b_lo = b & 0xffffu;
    let b_hi = b >> 16u;
    let ll = a_lo * b_lo;
    let lh = a_lo * b_hi;
    let hl = a_hi * b_lo;
    let mid = (ll >> 16u) + (lh & 0xffffu) + (hl & 0xffffu);
    let lo = (ll & 0xffffu) | (mid << 16u);
    let hi = a_hi * b_hi + (lh >> 16u) + (hl >> 16u) + (mid >> 16u);
    return vec2(lo, hi);
}

// a · b mod 2⁶⁴.
fn mul64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let low = mul_wide(a.x, b.x);
    return vec2(low.x, low.y + a.x * b.y + a.y * b.x);
}

// a + b mod 2⁶⁴.
fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2(lo, a.y + b.y + u32(lo < a.x));
}

// a >> n for 0 < n < 32.
fn shr64(a: vec2<u32>, n: u32) -> vec2<u32> {
    return vec2((a.x >> n) | (a.y << (32u - n)), a.y >> n);
}

// splitmix64's finalizer (Steele et al. 2014), as `splitmix64` in rng.rs.
fn splitmix64(x: vec2<u32>) -> vec2<u32> {
    var z = add64(x, vec2(0x7F4A7C15u, 0x9E3779B9u));
    z = mul64(z ^ shr64(z, 30u), vec2(0x1CE4E5B9u, 0xBF58476Du));
    z = mul64(z ^ shr64(z, 27u), vec2(0x133111EBu, 0x94D049BBu));
    return z ^ shr64(z, 31u);
}

// One more element `k` folded into a key's hash `h` (a step of `hash_key` in rng.rs).
fn hash_more(h: vec2<u32>, k: vec2<u32>) -> vec2<u32> {
    return splitmix64(h ^ splitmix64(k));
}

// The start of `hash_key`.
const KEY_START: vec2<u32> = vec2(0x85A308D3u, 0x243F6A88u);

// `hash_key` of rng.rs for a key of two elements.
fn hash_key2(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    return hash_more(hash_more(KEY_START, a), b);
}

// `hash_key` of rng.rs for a key of three elements.
fn hash_key3(a: vec2<u32>, b: vec2<u32>, c: vec2<u32>) -> vec2<u32> {
    return hash_more(hash_key2(a, b), c);
}

// The numbers of one path: `SobolSampler` without its prefetching.
struct Sampler {
    // Hash of the key and of the sample's block of 2^16 samples.
    seed: u32,
    // Index of the sample within its block, bit-reversed.
    index_rev: u32,
    // Next unused pair of dimensions.
    pair: u32,
}

// `SobolSampler::new(key, index)` for a key hashed to `key_hash` (`hash_key`).
fn sampler_from_hash(key_hash: vec2<u32>, index: vec2<u32>) -> Sampler {
    let block = vec2((index.x >> 16u) | (index.y << 16u), index.y >> 16u);
    let seed = splitmix64(key_hash ^ splitmix64(block));
    return Sampler(seed.x ^ seed.y, reverseBits(index.x & 0xffffu), 0u);
}

// `SampleSequence::sampler(key, index)` for a key hashed to `key_hash`: Sobol (`independent`
// false) or independent samples.
fn sequence_sampler(key_hash: vec2<u32>, index: u32, independent: bool) -> Sampler {
    if independent {
        return sampler_from_hash(hash_key2(key_hash, vec2(index, 0u)), vec2(0u));
    }
    return sampler_from_hash(key_hash, vec2(index, 0u));
}

// The path tracer's sampler of a pixel's sample `index` (key [seed, pixel]).
fn path_sampler(seed: vec2<u32>, pixel: u32, index: u32, independent: bool) -> Sampler {
    return sequence_sampler(hash_key2(seed, vec2(pixel, 0u)), index, independent);
}

// Moves on to the pairs of step `step` of a path, `pairs` per step (`start_step`).
fn start_step(s: ptr<function, Sampler>, step: u32, pairs: u32) {
    (*s).pair = max((*s).pair, step * pairs);
}

const SCRAMBLE_X: u32 = 0x912F69BAu;
const SCRAMBLE_Y: u32 = 0x174F18ABu;

fn pair_seed(seed: u32, pair: u32) -> u32 {
    return seed ^ (pair * 0x9E3779B9u);
}

// Wellons' mixer with zero not mapped to zero.
fn hash32(x: u32) -> u32 {
    var n = x ^ 0xE6FE3BEBu;
    n ^= n >> 16u;
    n *= 0x7FEB352Du;
    n ^= n >> 15u;
    n *= 0x846CA68Bu;
    n ^= n >> 16u;
    return n;
}

// Owen scramble of a bit-reversed value (Vegdahl's hash).
fn owen_scramble_rev(x: u32, scramble: u32) -> u32 {
    var n = x;
    n ^= n * 0x3D20ADEAu;
    n += scramble;
    n *= (scramble >> 16u) | 1u;
    n ^= n * 0x05526C56u;
    n ^= n * 0x53A22864u;
    return n;
}

// The shuffled index of the sample and the seed its dimensions' scrambles derive from.
fn shuffle(index_rev: u32, seed: u32) -> vec2<u32> {
    let shuffled = owen_scramble_rev(index_rev, hash32(seed ^ 0x79C68E4Au));
    return vec2(reverseBits(shuffled) & 0xffffu, seed * 0x9C8F2D3Bu);
}

// The scrambled value as a float in [0, 1): its top 23 bits.
fn owen_to_unit(sobol: u32, scramble: u32) -> f32 {
    let n = reverseBits(owen_scramble_rev(sobol, scramble));
    return bitcast<f32>((n >> 9u) | 0x3F800000u) - 1.0;
}

// Both numbers of the pair with seed `seed`.
fn pair_numbers(index_rev: u32, seed: u32) -> vec2<f32> {
    let shuffled = shuffle(index_rev, seed);
    let bits = shuffled.x;
    // Dimension 1, the Pascal matrix mod 2: bit j gets every index bit k ⊇ j.
    var pascal = bits;
    pascal ^= (pascal & 0xAAAAu) >> 1u;
    pascal ^= (pascal & 0xCCCCu) >> 2u;
    pascal ^= (pascal & 0xF0F0u) >> 4u;
    pascal ^= (pascal & 0xFF00u) >> 8u;
    return vec2(
        owen_to_unit(bits, hash32(shuffled.y ^ SCRAMBLE_X)),
        owen_to_unit(pascal, hash32(shuffled.y ^ SCRAMBLE_Y)),
    );
}

// The first number of the next pair (`Sampler::uniform`).
fn uniform1(s: ptr<function, Sampler>) -> f32 {
    let seed = pair_seed((*s).seed, (*s).pair);
    (*s).pair += 1u;
    let shuffled = shuffle((*s).index_rev, seed);
    return owen_to_unit(shuffled.x, hash32(shuffled.y ^ SCRAMBLE_X));
}

// The next pair (`Sampler::uniform2`).
fn uniform2(s: ptr<function, Sampler>) -> vec2<f32> {
    let value = pair_numbers((*s).index_rev, pair_seed((*s).seed, (*s).pair));
    (*s).pair += 1u;
    return value;
}
