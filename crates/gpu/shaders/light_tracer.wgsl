// Light tracing as one kernel: vcm's light pass with its camera connections (bidir's
// light_pass.rs), and the camera pass that light tracing keeps, which finds the lights seen
// directly (camera_pass.rs). Invocation k of a frame's dispatches takes index i = k / samples
// of iteration first_sample + k % samples: pixel i's camera sample and the iteration's light
// path i, each drawing the CPU's numbers for it, so that both backends follow the same
// paths. A light path's vertices that scatter toward the camera and see it make splats.
// Camera samples and splats go to the film (film.wgsl). Outputs (group 0): 1–4 the film, 5
// the rays traced (camera, light, shadow).

// The light paths' random stream (`LIGHT_STREAM` of light_pass.rs).
const LIGHT_STREAM: u32 = 1u;
// Pairs of numbers per light vertex (vcm's `LIGHT` layout: lobe, direction, roulette; the
// emission's `EMISSION` layout has as many: light pick, light point, direction).
const LIGHT_PAIRS: u32 = 3u;

@group(0) @binding(5) var<storage, read_write> ray_counts: array<atomic<u32>, 3>;

// The raster position `p` projects to, or (−1, −1) where it lies behind the camera or
// outside the image (`Projection::raster_of`).
fn raster_of(p: vec3<f32>) -> vec2<f32> {
    let outside = vec2(-1.0);
    let d = p - params.camera_position;
    let z = dot3(d, params.camera_forward);
    if z <= 0.0 {
        return outside;
    }
    let ndc = vec2(
        dot3(d, params.camera_right) / (z * params.half_extent.x),
        dot3(d, params.camera_up) / (z * params.half_extent.y),
    );
    let raster = vec2((ndc.x + 1.0) * 0.5 * params.size.x, (1.0 - ndc.y) * 0.5 * params.size.y);
    let inside = raster.x >= 0.0 && raster.y >= 0.0 && raster.x < params.size.x
        && raster.y < params.size.y;
    return select(outside, raster, inside);
}

// A light vertex's connection to the camera: its pixel, and the shadow ray with what it adds
// unless blocked; `shadow.valid` false for none.
struct Splat {
    pixel: u32,
    shadow: Shadow,
}

// Connects the light vertex at `s`, reached through `medium` with `throughput`, to the camera
// (`connect_to_camera`): a splat where the vertex projects into the image and scatters toward
// the camera. Light tracing alone weighs it 1.
fn connect_to_camera(
    s: Surface,
    b: Bsdf,
    out: Outgoing,
    throughput: vec3<f32>,
    medium: vec3<f32>,
) -> Splat {
    var splat = Splat(0u, Shadow(false, vec3(0.0), vec3(0.0), 0.0, vec3(0.0)));
    let raster = raster_of(s.position);
    if raster.x < 0.0 {
        return splat;
    }
    let to_camera = params.camera_position - s.position;
    let distance_sq = dot3(to_camera, to_camera);
    let distance = sqrt(distance_sq);
    let direction = to_camera / distance;
    let eval = bsdf_eval(b, out, direction, true);
    if all(eval.f_cos == vec3(0.0)) {
        return splat;
    }
    // The camera's solid-angle pdf per pixel sample, d_image² / (pixel_area · cos θ) with
    // d_image = 1 / cos θ.
    let cos_camera = dot3(params.camera_forward, -direction);
    let camera_pdf_w = 1.0 / (params.pixel_area * (cos_camera * cos_camera * cos_camera));
    let toward_camera = transmittance(medium_toward(medium, s, direction), distance);
    splat.shadow.contribution = throughput * toward_camera * eval.f_cos
        * (camera_pdf_w / (distance_sq * params.light_paths));
    splat.shadow.origin = offset_ray_origin(s.position, s.error, s.n_g, direction);
    // To the camera's point (`segment_to`).
    splat.shadow.direction = params.camera_position - splat.shadow.origin;
    splat.shadow.tmax = 1.0 - GAMMA_16;
    splat.shadow.valid = true;
    let pixel = min(vec2<u32>(raster), vec2(params.width - 1u, params.height - 1u));
    splat.pixel = pixel.y * params.width + pixel.x;
    return splat;
}

// Emission that pixel `pixel`'s camera sample of `iteration` sees directly (light tracing's
// camera pass: the path ends at its first hit).
fn seen_directly(pixel: u32, iteration: u32) -> vec3<f32> {
    let key = hash_key3(params.seed, vec2(pixel, 0u), vec2(0u));
    var rng = sequence_sampler(key, iteration, params.independent != 0u);
    let jitter = uniform2(&rng);
    let raster = vec2(f32(pixel % params.width) + jitter.x, f32(pixel / params.width) + jitter.y);
    let direction = camera_direction(raster);
    let hit = trace(Ray(params.camera_position, 0.0, direction, MISSED), false);
    if params.max_segments < 1u {
        return vec3(0.0);
    }
    if hit.prim == NO_HIT {
        return escaped(direction, -1.0);
    }
    let s = surface_at(hit.prim, hit.u, hit.v);
    return emission(s, hit, direction, -1.0);
}

// Follows light path `index` of `iteration` from its light to its end, adding the splats
// that reach the camera to the film, and returns the closest-hit and shadow rays it traced.
fn trace_light_path(index: u32, iteration: u32) -> vec2<u32> {
    var rays = vec2(0u);
    let key = hash_key3(params.seed, vec2(iteration, 0u), vec2(LIGHT_STREAM, 0u));
    var rng = sequence_sampler(key, index, params.independent != 0u);
    // The emission (`emit` of light_pass.rs).
    let u_pick = uniform1(&rng);
    let u_pos = uniform2(&rng);
    let u_dir = uniform2(&rng);
    if params.light_count == 0u {
        return rays;
    }
    let light_index = pick(0u, params.light_count, u_pick);
    let light = lights[light_index];
    let emitted = emit(light, u_pos, u_dir);
    if !emitted.valid {
        return rays;
    }
    let emission_pdf_w = emitted.emission_pdf_w * picks[light_index].y;
    var throughput = emitted.value * (emitted.cos_at_light / emission_pdf_w);
    if !(max_element(throughput) > 0.0 && all_finite(throughput)) {
        return rays;
    }
    // Roulette judges a light path relative to its emission (`Roulette::relative_to`);
    // importance is not scaled by refraction.
    let roulette_scale = 1.0 / max_element(throughput);
    var origin = offset_off_light(light, emitted.position, emitted.direction);
    var direction = emitted.direction;
    var medium = vec3(0.0);
    var segments = 1u;
    loop {
        let hit = trace(Ray(origin, 0.0, direction, MISSED), false);
        rays.x += 1u;
        if hit.prim == NO_HIT {
            break;
        }
        // The vertex (`shade` of light_pass.rs).
        start_step(&rng, segments, LIGHT_PAIRS);
        throughput *= transmittance(medium, hit.t);
        let s = surface_at(hit.prim, hit.u, hit.v);
        let b = bsdf_new(material_at(s), s.n_g, s.n_s);
        let out = outgoing(b, -direction);
        var splat = Splat(0u, Shadow(false, vec3(0.0), vec3(0.0), 0.0, vec3(0.0)));
        if has_non_delta(b.m) && segments < params.max_segments && out.valid {
            splat = connect_to_camera(s, b, out, throughput, medium);
        }
        // A further vertex has segments + 1 segments, and using it takes one more.
        var alive = out.valid && params.max_segments >= 2u && segments <= params.max_segments - 2u;
        if alive {
            // The continuation (`Walk::scatter` in importance mode).
            let u_lobe = uniform1(&rng);
            let u_scatter = uniform2(&rng);
            let sample = bsdf_sample(b, out, u_lobe, u_scatter, true);
            alive = sample.valid;
            if alive {
                throughput = throughput * (sample.f_cos / sample.pdf_fwd);
                alive = survives(&rng, segments, &throughput, roulette_scale);
            }
            if alive {
                origin = offset_ray_origin(s.position, s.error, s.n_g, sample.wi);
                direction = sample.wi;
                segments += 1u;
                medium = medium_toward(medium, s, sample.wi);
            }
        }
        if splat.shadow.valid {
            rays.y += 1u;
            let shadow = splat.shadow;
            let blocker = trace(Ray(shadow.origin, 0.0, shadow.direction, shadow.tmax), true);
            if blocker.prim == NO_HIT {
                film_add(splat.pixel, shadow.contribution);
            }
        }
        if !alive {
            break;
        }
    }
    return rays;
}

@compute @workgroup_size(WORKGROUP)
fn trace_light_paths(@builtin(global_invocation_id) id: vec3<u32>) {
    let local = id.x + id.y * params.row_threads;
    if local >= params.path_count {
        return;
    }
    let path = params.first_path + local;
    let index = path / params.samples;
    let iteration = params.first_sample + path % params.samples;
    film_add(index, seen_directly(index, iteration));
    let rays = trace_light_path(index, iteration);
    atomicAdd(&ray_counts[0], 1u);
    atomicAdd(&ray_counts[1], rays.x);
    atomicAdd(&ray_counts[2], rays.y);
}
