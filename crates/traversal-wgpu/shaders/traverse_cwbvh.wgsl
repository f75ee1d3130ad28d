// Closest-hit and any-hit traversal of a compressed 8-wide BVH (Ylitie, Karras and Laine
// 2017, in obvhs's node format): each node stores its children's boxes as 8-bit offsets on a
// per-node grid. The stack holds node groups (first child index, hit bits) as in the paper.
// STACK_SIZE (the hierarchy's depth + 1) is defined by the host when it composes the module,
// and is_opaque comes from alpha_none.wgsl or alpha_masks.wgsl.

// One node is five words of four u32: p.xyz and e012|imask; child_base, primitive_base,
// child_meta[0..4], child_meta[4..8]; then min/max x, y, z planes, four bytes per word.
@group(1) @binding(0) var<storage, read> nodes: array<vec4<u32>>;

// Relative error bound on a quantised slab distance, in units of its largest term (as on
// the CPU backend): covers obvhs's rounding of the grid.
const GRID_SLACK: f32 = 9.5367432e-7; // 8 ε

// Which children of `node` the ray overlaps within [tmin, tmax], as obvhs's hit mask: inner
// children in the top byte (in traversal order for the ray's octant), leaf triangles in the
// low 24 bits.
fn intersect_node(node: u32, ray: PreparedRay, oct_inv4: u32, tmax: f32) -> u32 {
    let w0 = nodes[5u * node];
    let w1 = nodes[5u * node + 1u];
    let p = bitcast<vec3<f32>>(w0.xyz);
    // Grid cell sizes: powers of two from the exponent bytes.
    let exponents = vec3(w0.w & 0xffu, (w0.w >> 8u) & 0xffu, (w0.w >> 16u) & 0xffu);
    let extent = bitcast<vec3<f32>>(exponents << vec3(23u));
    let offset = p - ray.origin;
    let base = offset * ray.inv_dir;
    let slack = (abs(offset) + extent * 255.0) * abs(ray.inv_dir) * GRID_SLACK;
    let scale = extent * ray.inv_dir;
    let near = base - slack;
    let far = base + slack;
    let planes_x = nodes[5u * node + 2u];
    let planes_y = nodes[5u * node + 3u];
    let planes_z = nodes[5u * node + 4u];
    // A ray going in -x enters a box through its max-x plane.
    let neg = ray.inv_dir < vec3(0.0);
    // Four children at a time: word 0 of a plane set holds children 0-3, word 1 children 4-7.
    var mask = 0u;
    for (var half = 0u; half < 2u; half++) {
        let min_x = vec4<f32>(unpack4xU8(planes_x[half]));
        let max_x = vec4<f32>(unpack4xU8(planes_x[half + 2u]));
        let min_y = vec4<f32>(unpack4xU8(planes_y[half]));
        let max_y = vec4<f32>(unpack4xU8(planes_y[half + 2u]));
        let min_z = vec4<f32>(unpack4xU8(planes_z[half]));
        let max_z = vec4<f32>(unpack4xU8(planes_z[half + 2u]));
        let entry_x = select(min_x, max_x, neg.x) * scale.x + near.x;
        let entry_y = select(min_y, max_y, neg.y) * scale.y + near.y;
        let entry_z = select(min_z, max_z, neg.z) * scale.z + near.z;
        let exit_x = select(max_x, min_x, neg.x) * scale.x + far.x;
        let exit_y = select(max_y, min_y, neg.y) * scale.y + far.y;
        let exit_z = select(max_z, min_z, neg.z) * scale.z + far.z;
        let entry = max(max(entry_x, entry_y), max(entry_z, vec4(ray.tmin)));
        let exit = min(min(exit_x, exit_y), min(exit_z, vec4(tmax)));
        // Child meta bytes: leaves carry a unary triangle count in bits 5-7 and their first
        // triangle's offset in bits 0-4; inner children 0b001 and 24 + slot, which the octant
        // reorders. Empty slots are 0 and contribute no bits.
        let child = unpack4xU8(w1[2u + half]);
        let inner = (child & vec4(0x18u)) == vec4(0x18u);
        let bit_index = (child ^ select(vec4(0u), vec4(oct_inv4 & 0xffu), inner)) & vec4(0x1fu);
        let bits = select(vec4(0u), ((child >> vec4(5u)) & vec4(7u)) << bit_index, entry <= exit);
        mask |= bits.x | bits.y | bits.z | bits.w;
    }
    return mask;
}

// Traces `ray`; with `any_hit` it returns the first hit found instead of the closest.
// `best.prim` is a leaf position until the end; at equal t the smaller caller id wins.
fn trace(ray_in: Ray, any_hit: bool) -> Hit {
    var best = Hit(ray_in.tmax, NO_HIT, 0.0, 0.0);
    if !(ray_in.tmin < ray_in.tmax) || arrayLength(&nodes) == 0u {
        return best;
    }
    let ray = prepare_ray(ray_in);
    let oct_inv4 = select(0u, 0x04040404u, ray.inv_dir.x >= 0.0)
        | select(0u, 0x02020202u, ray.inv_dir.y >= 0.0)
        | select(0u, 0x01010101u, ray.inv_dir.z >= 0.0);
    var stack: array<vec2<u32>, STACK_SIZE>;
    var depth = 0u;
    // The root alone: one hit bit in the top byte, resolving to node 0 for every octant.
    var current = vec2(0u, 0x80000000u);
    var triangles = vec2(0u, 0u);
    loop {
        while triangles.y != 0u {
            let local = firstLeadingBit(triangles.y);
            triangles.y &= ~(1u << local);
            best = closer_hit(triangles.x + local, ray, best);
            if any_hit && best.prim != NO_HIT {
                break;
            }
        }
        if any_hit && best.prim != NO_HIT {
            break;
        }
        if (current.y & 0xff000000u) != 0u {
            let hits_imask = current.y;
            let child_bit = firstLeadingBit(hits_imask);
            current.y &= ~(1u << child_bit);
            if (current.y & 0xff000000u) != 0u {
                stack[depth] = current;
                depth += 1u;
            }
            let slot = (child_bit - 24u) ^ (oct_inv4 & 0xffu);
            let relative = countOneBits(hits_imask & ~(0xffffffffu << slot));
            let node = current.x + relative;
            let hitmask = intersect_node(node, ray, oct_inv4, best.t);
            let w0 = nodes[5u * node];
            let w1 = nodes[5u * node + 1u];
            current = vec2(w1.x, (hitmask & 0xff000000u) | (w0.w >> 24u));
            triangles = vec2(w1.y, hitmask & 0x00ffffffu);
        } else {
            current = vec2(0u, 0u);
        }
        if triangles.y == 0u && (current.y & 0xff000000u) == 0u {
            if depth == 0u {
                break;
            }
            depth -= 1u;
            current = stack[depth];
        }
    }
    if best.prim != NO_HIT {
        best.prim = ids[best.prim];
    }
    return best;
}
