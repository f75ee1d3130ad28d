// The light pass as one kernel: vcm's light pass with its camera connections (bidir's
// light_pass.rs) — for light tracing alone together with the camera pass it keeps, which
// finds the lights seen directly (camera_pass.rs); for the bidirectional algorithms run
// twice, first counting each path's cacheable vertices (keeping the first few), then storing
// them where the index says (bidir.wgsl). Invocation k of a frame's dispatches takes index
// i = k / samples of iteration first_sample + k % samples: pixel i's camera sample (light
// tracing alone) and the iteration's light path i, where there are such (the dispatches cover
// the pixels or the light paths, whichever are more), each drawing the CPU's numbers for it,
// so that both backends follow the same paths. A light path's vertices that scatter toward
// the camera and see it make splats. Camera samples and splats go to the film (film.wgsl).
// Outputs (group 0): 1–4 the film, 5 the rays traced (camera, light, shadow).

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

// Connects the light vertex `vertex` at `s`, reached through `medium`, to the camera
// (`connect_to_camera`): a splat where the vertex projects into the image and scatters toward
// the camera, weighted against the camera's own techniques where there are any.
fn connect_to_camera(
    s: Surface,
    b: Bsdf,
    out: Outgoing,
    vertex: LightVertex,
    medium: vec3<f32>,
) -> Splat {
    var splat = Splat(0u, no_shadow());
    let raster = raster_of(s.position);
    if raster.x < 0.0 {
        return splat;
    }
    let to_camera = params.camera_position - s.position;
    let distance_sq = dot3(to_camera, to_camera);
    let distance = sqrt(distance_sq);
    let direction = to_camera / distance;
    let light_tracing = params.light_pass == LIGHT_TRACING;
    let eval = bsdf_eval(b, out, direction, true, !light_tracing);
    if all(eval.f_cos == vec3(0.0)) {
        return splat;
    }
    // The camera's solid-angle pdf per pixel sample, d_image² / (pixel_area · cos θ) with
    // d_image = 1 / cos θ; its area pdf at the vertex adds |cos θ_surface| / d².
    let cos_camera = dot3(params.camera_forward, -direction);
    let camera_pdf_w = 1.0 / (params.pixel_area * (cos_camera * cos_camera * cos_camera));
    var weight = 1.0;
    if !light_tracing {
        let camera_pdf_a = camera_pdf_w * abs(dot3(s.n_g, direction)) / distance_sq;
        let mis = SubpathMis(vertex.mis.x, vertex.mis.y, vertex.mis.z);
        weight = camera_connection_weight(mis, camera_pdf_a, eval.pdf_rev, vertex.path_length == 1u);
    }
    let toward_camera = transmittance(medium_toward(medium, s, direction), distance);
    splat.shadow.contribution = vertex.throughput * toward_camera * eval.f_cos
        * (weight * camera_pdf_w / (distance_sq * params.light_paths));
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
    let direction = pixel_direction(&rng, pixel);
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

// The cacheable vertices of light path `path` (`index` of its iteration), from the index
// the device built: from where its vertices start to where the next path's do (or its
// iteration's end).
fn indexed_count(path: u32, index: u32) -> u32 {
    let sample = path % params.samples;
    var end = iterations[sample].cache_count;
    if index + 1u < params.light_path_count {
        end = vertex_index[path + params.samples];
    }
    return end - vertex_index[path];
}

// Follows light path `index` of `iteration` (the frame's path `path`) from its light to its
// end and does what `params.light_pass` says at each diffuse or glossy vertex: splat it
// (light tracing alone: weight 1); or count it, keep it in `scratch` if it is one of the
// first `params.kept_vertices` and splat it with the bidirectional weight; or store it in
// the cache — after copying the kept ones there, and only for a path with more than those.
// Returns the closest-hit and shadow rays it traced.
fn trace_light_path(path: u32, index: u32, iteration: u32) -> vec2<u32> {
    let mode = params.light_pass;
    let kept = params.kept_vertices;
    var light_rays = 0u;
    var shadow_rays = 0u;
    var stored = 0u;
    var first_slot = 0u;
    if mode == LATER_VERTICES {
        first_slot = iterations[path % params.samples].cache_start + vertex_index[path];
        let count = indexed_count(path, index);
        for (var k = 0u; k < min(count, kept); k++) {
            cache[first_slot + k] = scratch[path * kept + k];
        }
        if count <= kept {
            return vec2(0u);
        }
    }
    let key = hash_key3(params.seed, vec2(iteration, 0u), vec2(LIGHT_STREAM, 0u));
    var rng = sequence_sampler(key, index, params.independent != 0u);
    // The emission (`emit` of light_pass.rs).
    let u_pick = uniform1(&rng);
    let u_pos = uniform2(&rng);
    let u_dir = uniform2(&rng);
    loop {
        if params.light_count == 0u {
            break;
        }
        let light_index = pick(0u, params.light_count, u_pick);
        let pick_pmf = picks[light_index].y;
        let light = lights[light_index];
        let emitted = emit(light, u_pos, u_dir);
        if !emitted.valid {
            break;
        }
        let emission_pdf_w = emitted.emission_pdf_w * pick_pmf;
        let throughput = emitted.value * (emitted.cos_at_light / emission_pdf_w);
        if !(max_element(throughput) > 0.0 && all_finite(throughput)) {
            break;
        }
        let kind = light_kind(light);
        var mis = mis_light(
            emitted.direct_pdf_a * pick_pmf,
            emission_pdf_w,
            emitted.cos_at_light,
            is_delta_light(kind),
            is_finite_light(kind),
        );
        // Roulette judges a light path relative to its emission (`Roulette::relative_to`);
        // importance is not scaled by refraction.
        let origin = offset_off_light(light, emitted.position, emitted.direction);
        let roulette_scale = 1.0 / max_element(throughput);
        var walk = Walk(origin, emitted.direction, throughput, vec3(0.0), 1u, roulette_scale);
        loop {
            let hit = trace(Ray(walk.origin, 0.0, walk.direction, MISSED), false);
            light_rays += 1u;
            if hit.prim == NO_HIT {
                break;
            }
            // The vertex (`shade` of light_pass.rs).
            let segments = walk.segments;
            start_step(&rng, segments, LIGHT_PAIRS);
            walk.throughput *= transmittance(walk.medium, hit.t);
            let s = surface_at(hit.prim, hit.u, hit.v);
            let wo = -walk.direction;
            // A light at infinity's first segment has no length: its pdfs are per solid angle.
            let from_infinity = segments == 1u && !is_finite_light(kind);
            mis_arrive(&mis, select(hit.t * hit.t, -1.0, from_infinity), abs(dot3(s.n_g, wo)));
            let b = bsdf_new(material_at(s), s.n_g, s.n_s);
            let out = outgoing(b, wo);
            var splat = Splat(0u, no_shadow());
            if has_non_delta(b.m) {
                let vertex = LightVertex(
                    s.position,
                    segments,
                    wo,
                    hit.prim,
                    walk.throughput,
                    hit.u,
                    vec3(mis.d_vcm, mis.d_vc, mis.d_vm),
                    hit.v,
                );
                if mode == FIRST_VERTICES && stored < kept {
                    scratch[path * kept + stored] = vertex;
                } else if mode == LATER_VERTICES && stored >= kept {
                    cache[first_slot + stored] = vertex;
                }
                stored += 1u;
                let splats = mode != LATER_VERTICES && plan_has(SPLATS);
                // Not a delta light's first vertex where light samples find it
                // (`splats_here` of light_pass.rs).
                let left_to_light_samples = segments == 1u && is_delta_light(kind)
                    && !splats_first_of_delta();
                if splats && segments < params.max_segments && out.valid && !left_to_light_samples {
                    splat = connect_to_camera(s, b, out, vertex, walk.medium);
                }
            }
            // A further vertex has segments + 1 segments, and using it takes one more.
            var alive = out.valid && params.max_segments >= 2u
                && segments <= params.max_segments - 2u;
            if alive {
                // The continuation in importance transport, with the MIS update.
                let sample = scatter(&rng, b, out, true, mode != LIGHT_TRACING);
                alive = sample.valid;
                if alive {
                    let cos_out = abs(dot3(s.n_g, sample.wi));
                    let specular = sample.kind == KIND_SPECULAR;
                    let beside_light = segments == 1u;
                    mis_scatter(&mis, cos_out, sample.pdf_fwd, sample.pdf_rev, specular, beside_light);
                    alive = walk_on(&walk, &rng, s, sample, true);
                }
            }
            if splat.shadow.valid && unblocked(splat.shadow, &shadow_rays) {
                film_add(splat.pixel, splat.shadow.contribution);
            }
            if !alive {
                break;
            }
        }
        break;
    }
    if mode == FIRST_VERTICES {
        vertex_index[path] = stored;
    }
    return vec2(light_rays, shadow_rays);
}

@compute @workgroup_size(WORKGROUP)
fn trace_light_paths(@builtin(global_invocation_id) id: vec3<u32>) {
    let path = frame_path(id);
    if path == NO_PATH {
        return;
    }
    let index = path / params.samples;
    let sample = path % params.samples;
    let iteration = params.first_sample + sample;
    factors = iterations[sample].factors;
    if params.light_pass == LIGHT_TRACING && index < params.width * params.height {
        film_add(index, seen_directly(index, iteration));
        atomicAdd(&ray_counts[0], 1u);
    }
    if index >= params.light_path_count || (!plan_has(SPLATS) && params.light_pass == LIGHT_TRACING) {
        return;
    }
    let rays = trace_light_path(path, index, iteration);
    // A light path's rays count once, as on the CPU: not again where it is traced again to
    // store its later vertices.
    if params.light_pass != LATER_VERTICES {
        atomicAdd(&ray_counts[1], rays.x);
        atomicAdd(&ray_counts[2], rays.y);
    }
}
