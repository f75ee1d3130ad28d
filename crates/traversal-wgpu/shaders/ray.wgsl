// Rays, hits and the watertight ray/triangle test (Woop, Benthin and Wald 2013), shared by the
// traversal kernels and by kernels that trace rays of their own (the GPU path tracer). The
// same arithmetic as the CPU backend's, so both report the same triangle and nearly the same t.

struct Ray {
    origin: vec3<f32>,
    tmin: f32,
    dir: vec3<f32>,
    tmax: f32,
}

struct Hit {
    t: f32,
    prim: u32,
    u: f32,
    v: f32,
}

const NO_HIT: u32 = 0xffffffffu;
// Entry distance reported for boxes a ray misses (the largest finite f32).
const MISSED: f32 = 3.40282347e38;
// Direction components below this magnitude are clamped before taking reciprocals.
const MIN_DIR_COMPONENT: f32 = 1e-18;
// Relative widening of a box's exit distance: 2γ(3) covers the slab test's rounding, so
// geometry lying exactly on a box face is never culled by a one-ulp miss.
const SLAB_SLACK: f32 = 4e-7;

@group(1) @binding(1) var<storage, read> vertices: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read> ids: array<u32>;

// A ray with what the box and triangle tests derive from it.
struct PreparedRay {
    origin: vec3<f32>,
    inv_dir: vec3<f32>,
    tmin: f32,
    // Permuted axes: kz is the dominant direction axis.
    kx: u32,
    ky: u32,
    kz: u32,
    // Shear constants mapping the ray onto +z in the permuted frame.
    shear: vec3<f32>,
}

fn prepare_ray(ray: Ray) -> PreparedRay {
    let d = ray.dir;
    let a = abs(d);
    var kz = 2u;
    if a.x >= a.y && a.x >= a.z {
        kz = 0u;
    } else if a.y >= a.z {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kz + 2u) % 3u;
    if d[kz] < 0.0 {
        let swap = kx;
        kx = ky;
        ky = swap;
    }
    let sign = select(vec3(-1.0), vec3(1.0), d >= vec3(0.0));
    let inv_dir = 1.0 / (sign * max(a, vec3(MIN_DIR_COMPONENT)));
    let sz = 1.0 / d[kz];
    return PreparedRay(ray.origin, inv_dir, ray.tmin, kx, ky, kz, vec3(d[kx] * sz, d[ky] * sz, sz));
}

// Entry distance of the ray into the box, or MISSED if it misses it within [tmin, tmax).
fn box_entry(lo: vec3<f32>, hi: vec3<f32>, ray: PreparedRay, tmax: f32) -> f32 {
    let t0 = (lo - ray.origin) * ray.inv_dir;
    let t1 = (hi - ray.origin) * ray.inv_dir;
    let near = min(t0, t1);
    let far = max(t0, t1);
    let enter = max(max(near.x, near.y), max(near.z, ray.tmin));
    let leave = min(min(far.x, far.y), min(far.z, tmax));
    return select(MISSED, enter, enter <= leave + abs(leave) * SLAB_SLACK);
}

// Intersects leaf-order triangle `index`: returns (t, u, v), with t = MISSED on a miss. The
// caller checks t against the ray's interval.
fn intersect_triangle(index: u32, ray: PreparedRay) -> vec3<f32> {
    let miss = vec3(MISSED, 0.0, 0.0);
    let a = vertices[3u * index].xyz - ray.origin;
    let b = vertices[3u * index + 1u].xyz - ray.origin;
    let c = vertices[3u * index + 2u].xyz - ray.origin;
    let z = vec3(a[ray.kz], b[ray.kz], c[ray.kz]);
    let x = vec3(a[ray.kx], b[ray.kx], c[ray.kx]) - ray.shear.x * z;
    let y = vec3(a[ray.ky], b[ray.ky], c[ray.ky]) - ray.shear.y * z;
    // Edge functions: component i belongs to the edge opposite vertex i.
    let edges = x.zxy * y.yzx - y.zxy * x.yzx;
    let negative = any(edges < vec3(0.0));
    let positive = any(edges > vec3(0.0));
    let det = edges.x + edges.y + edges.z;
    if (negative && positive) || det == 0.0 {
        return miss;
    }
    let t = dot(edges, z * ray.shear.z) / det;
    return vec3(t, edges.y / det, edges.z / det);
}

// Tests leaf-order triangle `leaf` against the closest hit so far; `best.prim` is a leaf
// position until the end of the traversal. At equal t the smaller caller id wins, as on the
// CPU backend, so the answer does not depend on the traversal order.
fn closer_hit(leaf: u32, ray: PreparedRay, best: Hit) -> Hit {
    let h = intersect_triangle(leaf, ray);
    let closer = h.x < best.t
        || (h.x == best.t && best.prim != NO_HIT && ids[leaf] < ids[best.prim]);
    if h.x >= ray.tmin && closer && is_opaque(leaf, h.y, h.z) {
        return Hit(h.x, leaf, h.y, h.z);
    }
    return best;
}
