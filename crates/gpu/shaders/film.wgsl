// The frame's film on the device: per pixel and channel the exact sum of the values added to
// it, vcm's `ExactSum` (exact_sum.rs) — a 320-bit two's complement fixed-point integer in
// units of 2⁻¹⁴⁹, the smallest f32, which holds every finite f32 exactly with 2⁴² of the
// largest of headroom — as ten u32 limbs, least significant first. Values are added with
// atomic additions (subtractions) limb by limb, each passing its carry (borrow) to the next
// limb: integer addition modulo 2³²⁰ commutes, so the sums are exact and the same whatever
// order the invocations add in. Every pixel's sample count is the frame's samples per pixel,
// which the host knows; a sample with a non-finite channel adds nothing and is counted.
//
// Bindings (group 0): 1, 2, 3 the red, green and blue sums (one binding each, so that an
// image may have a third of a binding's largest size in sums), 4 the dropped samples.

const SUM_LIMBS: u32 = 10u;

@group(0) @binding(1) var<storage, read_write> film_red: array<atomic<u32>>;
@group(0) @binding(2) var<storage, read_write> film_green: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> film_blue: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> film_dropped: atomic<u32>;

// Adds `value` to limb `index` of channel `channel`'s sums (subtracts it where `negative`),
// and returns whether that wrapped around: the carry (borrow) into the next limb.
fn add_to_limb(channel: u32, index: u32, value: u32, negative: bool) -> bool {
    var old: u32;
    switch channel {
        case 0u: {
            if negative {
                old = atomicSub(&film_red[index], value);
            } else {
                old = atomicAdd(&film_red[index], value);
            }
        }
        case 1u: {
            if negative {
                old = atomicSub(&film_green[index], value);
            } else {
                old = atomicAdd(&film_green[index], value);
            }
        }
        default: {
            if negative {
                old = atomicSub(&film_blue[index], value);
            } else {
                old = atomicAdd(&film_blue[index], value);
            }
        }
    }
    return select(old > 0xffffffffu - value, old < value, negative);
}

// Adds the finite `value` exactly to pixel `pixel`'s sum of channel `channel`
// (`ExactSum::add_f32`): its significand, shifted to its exponent, spans two limbs; the carry
// (borrow) goes up from there.
fn exact_add(channel: u32, pixel: u32, value: f32) {
    let bits = bitcast<u32>(value);
    let exponent = (bits >> 23u) & 0xffu;
    let fraction = bits & 0x7fffffu;
    if exponent == 0u && fraction == 0u {
        return;
    }
    // A normal value is (1.fraction) · 2^(exponent − 127) = (2²³ + fraction) · 2^(exponent − 1)
    // units of 2⁻¹⁴⁹; a subnormal one fraction units.
    var significand = fraction;
    var shift = 0u;
    if exponent != 0u {
        significand = fraction | 0x800000u;
        shift = exponent - 1u;
    }
    let first = shift / 32u;
    let offset = shift % 32u;
    let low = significand << offset;
    let high = select(0u, significand >> (32u - offset), offset != 0u);
    let negative = (bits >> 31u) != 0u;
    let base = pixel * SUM_LIMBS;
    var carry = add_to_limb(channel, base + first, low, negative);
    if first + 1u >= SUM_LIMBS {
        return;
    }
    // high < 2²³: high + 1 does not wrap.
    let next = high + u32(carry);
    if next == 0u {
        return;
    }
    carry = add_to_limb(channel, base + first + 1u, next, negative);
    for (var limb = first + 2u; carry && limb < SUM_LIMBS; limb++) {
        carry = add_to_limb(channel, base + limb, 1u, negative);
    }
}

// Adds `rgb` to pixel `pixel` (`Film::add` and `Film::add_splat` but for the sample count):
// a value with a non-finite channel is dropped and counted.
fn film_add(pixel: u32, rgb: vec3<f32>) {
    if !all_finite(rgb) {
        atomicAdd(&film_dropped, 1u);
        return;
    }
    for (var channel = 0u; channel < 3u; channel++) {
        exact_add(channel, pixel, rgb[channel]);
    }
}
