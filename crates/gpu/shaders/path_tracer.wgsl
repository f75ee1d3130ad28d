// The path tracer as one kernel: an invocation follows one path from the camera to its end,
// tracing its rays with `trace` (the traversal functions of vcm-traversal-wgpu), shading each
// vertex as the CPU's `shade` does (vcm's shade.rs, walk.rs, roulette.rs, shadow.rs), and
// adds the path's radiance to its pixel in the film (film.wgsl). Paths are numbered
// pixel · samples + sample, the CPU's key: path k draws the CPU's numbers for that pixel and
// sample. Outputs (group 0): 1–4 the film, 5 the closest-hit and shadow rays traced.

// Pairs of numbers per path vertex (vcm's `PATH_TRACER` layout: light pick, light point,
// lobe, direction, roulette).
const PAIRS_PER_VERTEX: u32 = 5u;

// Closest-hit and shadow rays traced by this dispatch.
@group(0) @binding(5) var<storage, read_write> ray_counts: array<atomic<u32>, 2>;

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
fn render_paths(@builtin(global_invocation_id) id: vec3<u32>) {
    let path = frame_path(id);
    if path == NO_PATH {
        return;
    }
    let pixel = path / params.samples;
    let sample = path % params.samples;
    var rng = path_sampler(params.seed, pixel, params.first_sample + sample, params.independent != 0u);
    let direction = pixel_direction(&rng, pixel);
    var walk = Walk(params.camera_position, direction, vec3(1.0), vec3(0.0), 1u, 1.0);
    var radiance = vec3(0.0);
    // The pdf the current segment was sampled with by a non-delta BSDF lobe; −1 for the
    // camera and delta lobes (`SegmentOrigin`).
    var bsdf_pdf = -1.0;
    var closest_rays = 0u;
    var shadow_rays = 0u;
    loop {
        // An unbounded ray: MISSED, the largest float, is beyond every hit, and no missed
        // triangle's MISSED is below it (the traversal backend clamps infinity alike).
        let hit = trace(Ray(walk.origin, 0.0, walk.direction, MISSED), false);
        closest_rays += 1u;
        if walk.segments > params.max_segments {
            break;
        }
        if hit.prim == NO_HIT {
            radiance += walk.throughput * transmittance(walk.medium, infinity())
                * escaped(walk.direction, bsdf_pdf);
            break;
        }
        start_step(&rng, walk.segments, PAIRS_PER_VERTEX);
        walk.throughput *= transmittance(walk.medium, hit.t);
        let s = surface_at(hit.prim, hit.u, hit.v);
        radiance += walk.throughput * emission(s, hit, walk.direction, bsdf_pdf);
        if walk.segments >= params.max_segments {
            break;
        }
        let b = bsdf_new(material_at(s), s.n_g, s.n_s);
        let out = outgoing(b, -walk.direction);
        if !out.valid {
            break;
        }
        var shadow = no_shadow();
        if has_non_delta(b.m) {
            shadow = next_event(&rng, s, b, out, walk.throughput, walk.medium);
        }
        let sample = scatter(&rng, b, out, false, false);
        var alive = sample.valid;
        if alive {
            bsdf_pdf = select(sample.pdf_fwd, -1.0, sample.kind == KIND_SPECULAR);
            alive = walk_on(&walk, &rng, s, sample, false);
        }
        if shadow.valid && unblocked(shadow, &shadow_rays) {
            radiance += shadow.contribution;
        }
        if !alive {
            break;
        }
    }
    film_add(pixel, radiance);
    atomicAdd(&ray_counts[0], closest_rays);
    atomicAdd(&ray_counts[1], shadow_rays);
}
