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
    var shadow = Shadow(false, vec3(0.0), vec3(0.0), 0.0, vec3(0.0));
    let u_pick = uniform1(rng);
    let u_light = uniform2(rng);
    if params.light_count == 0u {
        return shadow;
    }
    let index = pick(0u, params.light_count, u_pick);
    let pick_pmf = picks[index].y;
    let light = lights[index];
    let seen = illuminate(light, s.position, u_light);
    if !seen.valid {
        return shadow;
    }
    let eval = bsdf_eval(b, out, seen.direction, false);
    if all(eval.f_cos == vec3(0.0)) {
        return shadow;
    }
    let light_pdf_w = seen.direct_pdf_w * pick_pmf;
    let kind = light_kind(light);
    let delta = kind == POINT_LIGHT || kind == SPOT_LIGHT || kind == DIRECTIONAL_LIGHT;
    let weight = select(power_heuristic(light_pdf_w, eval.pdf_fwd), 1.0, delta);
    let toward_light = transmittance(medium_toward(medium, s, seen.direction), seen.distance);
    shadow.contribution = throughput * toward_light * seen.value * eval.f_cos * (weight / light_pdf_w);
    shadow.origin = offset_ray_origin(s.position, s.error, s.n_g, seen.direction);
    // To the light's point, off an emitting triangle's surface (`shadow_segment`); toward
    // infinity for lights at infinity.
    if !is_finite(seen.distance) {
        shadow.direction = seen.direction;
        shadow.tmax = MISSED;
    } else {
        let light_point = s.position + seen.direction * seen.distance;
        let target_point = offset_off_light(light, light_point, -seen.direction);
        shadow.direction = target_point - shadow.origin;
        shadow.tmax = 1.0 - GAMMA_16;
    }
    shadow.valid = true;
    return shadow;
}

@compute @workgroup_size(WORKGROUP)
fn render_paths(@builtin(global_invocation_id) id: vec3<u32>) {
    let local = id.x + id.y * params.row_threads;
    if local >= params.path_count {
        return;
    }
    let path = params.first_path + local;
    let pixel = path / params.samples;
    let sample = path % params.samples;
    var rng = path_sampler(params.seed, pixel, params.first_sample + sample, params.independent != 0u);
    let jitter = uniform2(&rng);
    let raster = vec2(f32(pixel % params.width) + jitter.x, f32(pixel / params.width) + jitter.y);
    var origin = params.camera_position;
    var direction = camera_direction(raster);
    var throughput = vec3(1.0);
    // The absorption of the medium the current segment runs through (`Medium`).
    var medium = vec3(0.0);
    var radiance = vec3(0.0);
    var segments = 1u;
    // The pdf the current segment was sampled with by a non-delta BSDF lobe; −1 for the
    // camera and delta lobes (`SegmentOrigin`).
    var bsdf_pdf = -1.0;
    // Russian roulette's factor that undoes refraction's radiance scaling.
    var roulette_scale = 1.0;
    var closest_rays = 0u;
    var shadow_rays = 0u;
    loop {
        // An unbounded ray: MISSED, the largest float, is beyond every hit, and no missed
        // triangle's MISSED is below it (the traversal backend clamps infinity alike).
        let hit = trace(Ray(origin, 0.0, direction, MISSED), false);
        closest_rays += 1u;
        if segments > params.max_segments {
            break;
        }
        if hit.prim == NO_HIT {
            radiance += throughput * transmittance(medium, infinity()) * escaped(direction, bsdf_pdf);
            break;
        }
        start_step(&rng, segments, PAIRS_PER_VERTEX);
        throughput *= transmittance(medium, hit.t);
        let s = surface_at(hit.prim, hit.u, hit.v);
        radiance += throughput * emission(s, hit, direction, bsdf_pdf);
        if segments >= params.max_segments {
            break;
        }
        let b = bsdf_new(material_at(s), s.n_g, s.n_s);
        let out = outgoing(b, -direction);
        if !out.valid {
            break;
        }
        var shadow = Shadow(false, vec3(0.0), vec3(0.0), 0.0, vec3(0.0));
        if has_non_delta(b.m) {
            shadow = next_event(&rng, s, b, out, throughput, medium);
        }
        // The continuation (`Walk::scatter`).
        let u_lobe = uniform1(&rng);
        let u_dir = uniform2(&rng);
        let sample = bsdf_sample(b, out, u_lobe, u_dir, false);
        var alive = sample.valid;
        if alive {
            bsdf_pdf = select(sample.pdf_fwd, -1.0, sample.kind == KIND_SPECULAR);
            roulette_scale *= sample.eta * sample.eta;
            throughput = throughput * (sample.f_cos / sample.pdf_fwd);
            alive = survives(&rng, segments, &throughput, roulette_scale);
        }
        if shadow.valid {
            shadow_rays += 1u;
            let blocker = trace(Ray(shadow.origin, 0.0, shadow.direction, shadow.tmax), true);
            if blocker.prim == NO_HIT {
                radiance += shadow.contribution;
            }
        }
        if !alive {
            break;
        }
        origin = offset_ray_origin(s.position, s.error, s.n_g, sample.wi);
        direction = sample.wi;
        segments += 1u;
        medium = medium_toward(medium, s, sample.wi);
    }
    film_add(pixel, radiance);
    atomicAdd(&ray_counts[0], closest_rays);
    atomicAdd(&ray_counts[1], shadow_rays);
}
