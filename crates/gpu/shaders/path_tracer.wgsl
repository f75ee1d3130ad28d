// The path tracer as a wavefront (pbrt-v4's wavefront integrator): the paths of a dispatch
// keep their state in `path_states` between kernels, and queues in storage buffers say which
// paths each kernel takes. `start_paths` starts every path of the dispatch at the camera and
// queues it; then, round by round, `extend_paths` takes each queued path one vertex further
// — traces its ray with `trace` (the traversal functions of vcm-traversal-wgpu) and shades
// the hit as the CPU's `shade` does (vcm's shade.rs, walk.rs, roulette.rs, shadow.rs) —
// queueing it again where it goes on and in the shadow queue where its light sample needs a
// shadow ray; `trace_shadows` traces those (rays that all test occlusion only); and
// `advance_paths` (one invocation) makes the next queue the one taken and sizes the next
// round's dispatches (indirect dispatches: the host copies their workgroups from `wave`).
// Once few paths are left, `finish_paths` takes each to its end in one invocation. A path
// adds its radiance to its pixel in the film (film.wgsl) once it has ended and its last
// shadow ray is traced. Each path sums its radiance in the order of the CPU's path, so the
// queues' order (atomic appends) changes nothing: the film's sums are exact. Paths are
// numbered pixel · samples + sample, the CPU's key: path k draws the CPU's numbers for that
// pixel and sample.
//
// Bindings (group 0): 1–4 the film, 5 the closest-hit and shadow rays traced, 11 the paths'
// states, 12 the queues (three parts of `params.path_count` entries: the two round queues,
// taken in turn, and the shadow queue), 13 the queues' counts.

// Pairs of numbers per path vertex (vcm's `PATH_TRACER` layout: light pick, light point,
// lobe, direction, roulette).
const PAIRS_PER_VERTEX: u32 = 5u;

// Closest-hit and shadow rays traced by this dispatch.
@group(0) @binding(5) var<storage, read_write> ray_counts: array<atomic<u32>, 2>;

// What a path carries between kernels besides its walk and its numbers.
struct PathProgress {
    // The radiance it has found so far.
    radiance: vec3<f32>,
    // The pdf the current segment was sampled with by a non-delta BSDF lobe; −1 for the
    // camera and delta lobes (`SegmentOrigin`).
    bsdf_pdf: f32,
    // Its light sample's shadow ray while it waits in the shadow queue, and what that adds
    // unless blocked.
    shadow_origin: vec3<f32>,
    shadow_tmax: f32,
    shadow_direction: vec3<f32>,
    pixel: u32,
    shadow_contribution: vec3<f32>,
    // 1 once it has ended: its last shadow ray, if any, adds its radiance to the film.
    ended: u32,
    closest_rays: u32,
    shadow_rays: u32,
}

struct PathState {
    walk: Walk,
    rng: Sampler,
    progress: PathProgress,
}

// The queues' counts: the workgroups of the next round's dispatches (indirect arguments),
// the paths in the queue taken this round, those queued for the next round and for shadow
// rays, and which round queue is taken (0 or 1).
struct Wave {
    workgroups: vec3<u32>,
    taken: u32,
    next: atomic<u32>,
    shadows: atomic<u32>,
    parity: u32,
}

@group(0) @binding(11) var<storage, read_write> path_states: array<PathState>;
@group(0) @binding(12) var<storage, read_write> queues: array<u32>;
@group(0) @binding(13) var<storage, read_write> wave: Wave;

// Where round queue `parity` starts in `queues`; the shadow queue starts at 2.
fn queue_start(parity: u32) -> u32 {
    return parity * params.path_count;
}

// What `extend` leaves a path with: it goes on to another vertex, its light sample waits
// for a shadow ray.
const GOES_ON: u32 = 1u;
const CASTS_SHADOW: u32 = 2u;

// One light sample from `s` (`next_event` of shade.rs).
fn next_event(
    rng: ptr<function, Sampler>,
    s: Surface,
    b: Bsdf,
    out: Outgoing,
    throughput: vec3<f32>,
    medium: vec3<f32>,
) -> Shadow {
    let sample = sample_light(rng, s, b, out, false);
    if !sample.valid {
        return no_shadow();
    }
    let seen = sample.seen;
    let light_pdf_w = seen.direct_pdf_w * sample.pick_pmf;
    let weight = select(
        power_heuristic(light_pdf_w, sample.eval.pdf_fwd),
        1.0,
        is_delta_light(light_kind(sample.light)),
    );
    let toward_light = transmittance(medium_toward(medium, s, seen.direction), seen.distance);
    let contribution = throughput * toward_light * seen.value * sample.eval.f_cos
        * (weight / light_pdf_w);
    return shadow_to_light(s, sample.light, seen, contribution);
}

@compute @workgroup_size(WORKGROUP)
fn start_paths(@builtin(global_invocation_id) id: vec3<u32>) {
    let path = frame_path(id);
    if path == NO_PATH {
        return;
    }
    let slot = path - params.first_path;
    let pixel = path / params.samples;
    let sample = path % params.samples;
    var rng = path_sampler(params.seed, pixel, params.first_sample + sample, params.independent != 0u);
    let direction = pixel_direction(&rng, pixel);
    let walk = Walk(params.camera_position, direction, vec3(1.0), vec3(0.0), 1u, 1.0);
    let progress = PathProgress(vec3(0.0), -1.0, vec3(0.0), 0.0, vec3(0.0), pixel, vec3(0.0), 0u, 0u, 0u);
    path_states[slot] = PathState(walk, rng, progress);
    queues[queue_start(0u) + slot] = slot;
}

// Takes a path one vertex further: traces its ray, adds the emission it finds, takes a light
// sample (left in `progress` for a shadow ray) and samples the continuation (the loop body
// of the CPU's path). Returns GOES_ON and CASTS_SHADOW as they apply.
fn extend(walk: ptr<function, Walk>, rng: ptr<function, Sampler>, progress: ptr<function, PathProgress>) -> u32 {
    // An unbounded ray: MISSED, the largest float, is beyond every hit, and no missed
    // triangle's MISSED is below it (the traversal backend clamps infinity alike).
    let hit = trace(Ray((*walk).origin, 0.0, (*walk).direction, MISSED), false);
    (*progress).closest_rays += 1u;
    if (*walk).segments > params.max_segments {
        return 0u;
    }
    if hit.prim == NO_HIT {
        (*progress).radiance += (*walk).throughput * transmittance((*walk).medium, infinity())
            * escaped((*walk).direction, (*progress).bsdf_pdf);
        return 0u;
    }
    start_step(rng, (*walk).segments, PAIRS_PER_VERTEX);
    (*walk).throughput *= transmittance((*walk).medium, hit.t);
    let s = surface_at(hit.prim, hit.u, hit.v);
    (*progress).radiance += (*walk).throughput * emission(s, hit, (*walk).direction, (*progress).bsdf_pdf);
    if (*walk).segments >= params.max_segments {
        return 0u;
    }
    let b = bsdf_new(material_at(s), s.n_g, s.n_s);
    let out = outgoing(b, -(*walk).direction);
    if !out.valid {
        return 0u;
    }
    var outcome = 0u;
    if has_non_delta(b.m) {
        let shadow = next_event(rng, s, b, out, (*walk).throughput, (*walk).medium);
        if shadow.valid {
            (*progress).shadow_origin = shadow.origin;
            (*progress).shadow_direction = shadow.direction;
            (*progress).shadow_tmax = shadow.tmax;
            (*progress).shadow_contribution = shadow.contribution;
            outcome |= CASTS_SHADOW;
        }
    }
    let sample = scatter(rng, b, out, false, false);
    if sample.valid {
        (*progress).bsdf_pdf = select(sample.pdf_fwd, -1.0, sample.kind == KIND_SPECULAR);
        if walk_on(walk, rng, s, sample, false) {
            outcome |= GOES_ON;
        }
    }
    return outcome;
}

// Adds an ended path's radiance to its pixel and its rays to the counts.
fn finish(progress: PathProgress) {
    film_add(progress.pixel, progress.radiance);
    atomicAdd(&ray_counts[0], progress.closest_rays);
    atomicAdd(&ray_counts[1], progress.shadow_rays);
}

// The path in place `i` of the queue taken this round.
fn taken_path(i: u32) -> u32 {
    return queues[queue_start(wave.parity) + i];
}

// Traces the shadow ray a path's light sample left in `progress`, adding what it brings
// unless blocked.
fn trace_shadow(progress: ptr<function, PathProgress>) {
    let shadow = Shadow(
        true,
        (*progress).shadow_origin,
        (*progress).shadow_direction,
        (*progress).shadow_tmax,
        (*progress).shadow_contribution,
    );
    var rays = (*progress).shadow_rays;
    if unblocked(shadow, &rays) {
        (*progress).radiance += shadow.contribution;
    }
    (*progress).shadow_rays = rays;
}

// Takes the path in `slot` one vertex further and queues it for what comes next (a round,
// a shadow ray, the film); or, `to_end`, takes it to its end, shadow rays and all.
fn run_path(slot: u32, to_end: bool) {
    let state = path_states[slot];
    var walk = state.walk;
    var rng = state.rng;
    var progress = state.progress;
    loop {
        let outcome = extend(&walk, &rng, &progress);
        if !to_end {
            if (outcome & GOES_ON) != 0u {
                queues[queue_start(1u - wave.parity) + atomicAdd(&wave.next, 1u)] = slot;
            } else {
                progress.ended = 1u;
            }
            if (outcome & CASTS_SHADOW) != 0u {
                queues[queue_start(2u) + atomicAdd(&wave.shadows, 1u)] = slot;
            } else if progress.ended != 0u {
                finish(progress);
            }
            path_states[slot] = PathState(walk, rng, progress);
            return;
        }
        if (outcome & CASTS_SHADOW) != 0u {
            trace_shadow(&progress);
        }
        if (outcome & GOES_ON) == 0u {
            break;
        }
    }
    finish(progress);
}

@compute @workgroup_size(WORKGROUP)
fn extend_paths(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < wave.taken {
        run_path(taken_path(id.x), false);
    }
}

@compute @workgroup_size(WORKGROUP)
fn trace_shadows(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= atomicLoad(&wave.shadows) {
        return;
    }
    let slot = queues[queue_start(2u) + id.x];
    var progress = path_states[slot].progress;
    trace_shadow(&progress);
    if progress.ended != 0u {
        finish(progress);
    }
    path_states[slot].progress = progress;
}

// The wavefront's tail: once few paths are left, rounds would be mostly empty dispatches,
// so each invocation takes one of the queued paths to its end.
@compute @workgroup_size(WORKGROUP)
fn finish_paths(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < wave.taken {
        run_path(taken_path(id.x), true);
    }
}

@compute @workgroup_size(1)
fn advance_paths() {
    let next = atomicLoad(&wave.next);
    wave.workgroups = vec3((next + WORKGROUP - 1u) / WORKGROUP, 1u, 1u);
    wave.taken = next;
    wave.parity = 1u - wave.parity;
    atomicStore(&wave.next, 0u);
    atomicStore(&wave.shadows, 0u);
}
