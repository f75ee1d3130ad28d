// The camera pass of the bidirectional algorithms as one kernel (bidir's camera_pass.rs): an
// invocation follows one camera path to its end, weighing by MIS what it finds by itself
// (emission), one light sample per vertex and its connections to light vertices of its
// iteration's cache picked uniformly (BPT, VCM), and its merges with the light vertices
// within the iteration's radius, found in its hash grid (PPM, BPM, VCM: bidir.wgsl); then
// adds the path's radiance to the film (film.wgsl). Paths are numbered pixel · samples + sample, and path k draws the CPU's numbers
// for that pixel and iteration. Outputs (group 0): 1–4 the film, 5 the rays traced (closest
// hits, —, shadow).

// Pairs of numbers per camera vertex (vcm's `CAMERA` layout: cache picks, light pick, light
// point, lobe, direction, roulette), and where the light sample's start.
const CAMERA_PAIRS: u32 = 6u;
const CAMERA_LIGHT_PICK: u32 = 1u;

@group(0) @binding(5) var<storage, read_write> ray_counts: array<atomic<u32>, 3>;
// Each iteration's hash grid (`Iteration`): its buckets' first entries, then its entries.
@group(0) @binding(9) var<storage, read> grid_starts: array<u32>;
@group(0) @binding(10) var<storage, read> grid_entries: array<GridEntry>;

const NO_BUCKET: u32 = 0xffffffffu;

// The weight of emission the camera path found by itself at its `segments`-th vertex, from
// light `light` whose light sampling picks that point with (area or solid-angle) pdf
// `direct_pdf_a` and emits toward the path with pdf `emission_pdf_w`
// (`found_emission_weight`): a light seen directly has no other technique.
fn found_emission_weight(
    mis: SubpathMis,
    segments: u32,
    light: u32,
    direct_pdf_a: f32,
    emission_pdf_w: f32,
) -> f32 {
    // Photon mapping proper finds a light only through specular vertices, which nothing else
    // samples.
    if segments == 1u || plan_has(PPM) {
        return 1.0;
    }
    let pick_pmf = picks[light].y;
    return emission_hit_weight(mis, pick_pmf * direct_pdf_a, pick_pmf * emission_pdf_w);
}

// Emitted radiance at the surface `s` the path hit along `dir`, MIS-weighted (`emission`).
fn found_emission(s: Surface, hit: Hit, dir: vec3<f32>, mis: SubpathMis, segments: u32) -> vec3<f32> {
    let emitted = area_emission(s, hit, dir);
    if emitted.w == 0.0 {
        return vec3(0.0);
    }
    let inv_area = 1.0 / lights[s.light].c0.w;
    let emission_pdf_w = inv_area * cosine_hemisphere_pdf(emitted.w);
    return emitted.xyz * found_emission_weight(mis, segments, s.light, inv_area, emission_pdf_w);
}

// Radiance from the environment toward a path that left the scene along `dir`, MIS-weighted
// (`escaped`): its pdfs are per solid angle.
fn found_escape(dir: vec3<f32>, mis: SubpathMis, segments: u32) -> vec3<f32> {
    if !has_light_kind(ENVIRONMENT_LIGHT) || params.environment == NO_LIGHT {
        return vec3(0.0);
    }
    let light = lights[params.environment];
    var direct_pdf_w = UNIFORM_SPHERE_PDF;
    if has_environment_map(light) {
        direct_pdf_w = environment_map_pdf(light, dir);
    }
    let emission_pdf_w = direct_pdf_w * entry_disk_pdf_a(light);
    let weight = found_emission_weight(mis, segments, params.environment, direct_pdf_w, emission_pdf_w);
    return environment_radiance(light, dir) * weight;
}

// One light sample from the camera vertex `s` (`light_sample` of camera_pass.rs).
fn weighted_light_sample(
    rng: ptr<function, Sampler>,
    s: Surface,
    b: Bsdf,
    out: Outgoing,
    walk: Walk,
    mis: SubpathMis,
) -> Shadow {
    let sample = sample_light(rng, s, b, out, true);
    if !sample.valid {
        return no_shadow();
    }
    let seen = sample.seen;
    let direct_pdf_w = seen.direct_pdf_w * sample.pick_pmf;
    // No BSDF sample hits a delta light.
    let delta = is_delta_light(light_kind(sample.light));
    let bsdf_fwd_pdf_w = select(sample.eval.pdf_fwd, 0.0, delta);
    var weight = light_sample_weight(
        mis,
        direct_pdf_w,
        seen.emission_pdf_w * sample.pick_pmf,
        seen.cos_at_light,
        abs(dot3(s.n_g, seen.direction)),
        bsdf_fwd_pdf_w,
        sample.eval.pdf_rev,
    );
    if delta && only_delta_light_sample(walk.segments) {
        weight = 1.0;
    }
    let toward_light = transmittance(medium_toward(walk.medium, s, seen.direction), seen.distance);
    let contribution = walk.throughput * toward_light * seen.value * sample.eval.f_cos
        * (weight / direct_pdf_w);
    return shadow_to_light(s, sample.light, seen, contribution);
}

// The connection between the camera vertex `s` and the light vertex `vertex`, its
// contribution scaled by `scale` (`connect` of camera_pass.rs).
fn connect(
    s: Surface,
    b: Bsdf,
    out: Outgoing,
    walk: Walk,
    mis: SubpathMis,
    vertex: LightVertex,
    scale: f32,
) -> Shadow {
    let to_light = vertex.position - s.position;
    let distance_sq = dot3(to_light, to_light);
    if distance_sq == 0.0 {
        return no_shadow();
    }
    let distance = sqrt(distance_sq);
    let direction = to_light / distance;
    let camera_eval = bsdf_eval(b, out, direction, false, true);
    if all(camera_eval.f_cos == vec3(0.0)) {
        return no_shadow();
    }
    let ls = surface_at(vertex.triangle, vertex.u, vertex.v);
    let light_b = bsdf_new(material_at(ls), ls.n_g, ls.n_s);
    let light_out = outgoing(light_b, vertex.wo);
    if !light_out.valid {
        return no_shadow();
    }
    let light_eval = bsdf_eval(light_b, light_out, -direction, true, true);
    if all(light_eval.f_cos == vec3(0.0)) {
        return no_shadow();
    }
    let light_mis = SubpathMis(vertex.mis.x, vertex.mis.y, vertex.mis.z);
    let weight = connection_weight(
        mis,
        light_mis,
        camera_eval.pdf_fwd * abs(dot3(ls.n_g, direction)) / distance_sq,
        camera_eval.pdf_rev,
        light_eval.pdf_fwd * abs(dot3(s.n_g, direction)) / distance_sq,
        light_eval.pdf_rev,
        vertex.path_length == 1u,
    );
    let toward_light = transmittance(medium_toward(walk.medium, s, direction), distance);
    let contribution = walk.throughput * toward_light * vertex.throughput * camera_eval.f_cos
        * light_eval.f_cos * (weight * scale / distance_sq);
    let origin = offset_ray_origin(s.position, s.error, s.n_g, direction);
    let target_point = offset_ray_origin(ls.position, ls.error, ls.n_g, -direction);
    return Shadow(true, origin, target_point - origin, 1.0 - GAMMA_16, contribution);
}

// The buckets a query at `query` reads (`HashGrid::cells`): its cell's and, per axis, the
// neighbour on the side of the cell it lies in, where the sphere of the radius reaches; each
// once, NO_BUCKET for the others.
fn grid_cells(it: Iteration, query: vec3<f32>) -> array<u32, 8> {
    var buckets = array<u32, 8>(
        NO_BUCKET, NO_BUCKET, NO_BUCKET, NO_BUCKET, NO_BUCKET, NO_BUCKET, NO_BUCKET, NO_BUCKET,
    );
    let r = sqrt(it.radius_sq);
    if it.entry_count == 0u || any(query < it.grid_min - r) || any(query > it.grid_max + r) {
        return buckets;
    }
    let scaled = (query - it.grid_min) * it.inv_cell_size;
    let cell = floor(scaled);
    let side = (scaled - cell) > vec3(0.5);
    // Shortened by a bound of its rounding error, as `HashGrid::cells`.
    let rounding = (abs(scaled) + 1.0) * GRID_SCALED_ERROR;
    let to_face = max(select(scaled - cell, cell + 1.0 - scaled, side) - rounding, vec3(0.0));
    let to_face_sq = to_face * to_face;
    let base = vec3<i32>(cell);
    let step = select(vec3(-1), vec3(1), side);
    for (var corner = 0u; corner < 8u; corner++) {
        let across = vec3((corner & 1u) != 0u, (corner & 2u) != 0u, (corner & 4u) != 0u);
        var distance_sq = 0.0;
        for (var axis = 0u; axis < 3u; axis++) {
            if across[axis] {
                distance_sq += to_face_sq[axis];
            }
        }
        if distance_sq > GRID_REACH_SQ {
            continue;
        }
        let bucket = grid_bucket(it, base + select(vec3(0), step, across));
        var seen = false;
        for (var k = 0u; k < 8u; k++) {
            seen = seen || buckets[k] == bucket;
        }
        if !seen {
            buckets[corner] = bucket;
        }
    }
    return buckets;
}

// Density estimation with the light vertices of iteration `it` within its radius of the
// camera vertex `s` (vertex merging, `merge` of camera_pass.rs): the MIS-weighted reflected
// radiance there, per unit throughput.
fn merge(s: Surface, b: Bsdf, out: Outgoing, mis: SubpathMis, it: Iteration, segments: u32) -> vec3<f32> {
    var sum = vec3(0.0);
    let buckets = grid_cells(it, s.position);
    for (var slot = 0u; slot < 8u; slot++) {
        let bucket = buckets[slot];
        if bucket == NO_BUCKET {
            continue;
        }
        let first = grid_starts[it.grid_starts + bucket];
        let end = grid_starts[it.grid_starts + bucket + 1u];
        for (var e = first; e < end; e++) {
            let entry = grid_entries[it.grid_entries + e];
            let d = entry.position - s.position;
            if !(dot3(d, d) <= it.radius_sq) {
                continue;
            }
            // The grid holds only the vertices that merge (grid.wgsl).
            let vertex = cache[it.cache_start + entry.index];
            if segments + vertex.path_length > params.max_segments {
                continue;
            }
            let eval = bsdf_eval(b, out, vertex.wo, false, true);
            let cos_light = abs(dot3(geometric_normal(vertex.triangle), vertex.wo));
            if all(eval.f_cos == vec3(0.0)) || cos_light == 0.0 {
                continue;
            }
            var weight = 1.0;
            if !plan_has(PPM) {
                let light = SubpathMis(vertex.mis.x, vertex.mis.y, vertex.mis.z);
                weight = merge_weight(mis, light, eval.pdf_fwd, eval.pdf_rev);
            }
            // The light vertices' density is over the area of the surfaces they lie on: the
            // photon's flux weighs f·|ωi·n_s| / |ωi·n_g|, n_g its own triangle's.
            sum += vertex.throughput * eval.f_cos * (weight / cos_light);
        }
    }
    return sum / (PI * it.radius * it.radius * params.light_paths);
}

@compute @workgroup_size(WORKGROUP)
fn connect_camera_paths(@builtin(global_invocation_id) id: vec3<u32>) {
    let path = frame_path(id);
    if path == NO_PATH {
        return;
    }
    let pixel = path / params.samples;
    let sample = path % params.samples;
    let iteration = params.first_sample + sample;
    // The iteration's light vertices, MIS factors and grid.
    let it = iterations[sample];
    factors = it.factors;
    let cache_start = it.cache_start;
    let cache_count = it.cache_count;
    // The camera path (`start` of camera_pass.rs).
    let key = hash_key3(params.seed, vec2(pixel, 0u), vec2(0u));
    var rng = sequence_sampler(key, iteration, params.independent != 0u);
    let direction = pixel_direction(&rng, pixel);
    let cos_camera = dot3(params.camera_forward, direction);
    var mis = mis_camera(1.0 / (params.pixel_area * (cos_camera * cos_camera * cos_camera)));
    // The quantities without the merge at the latest vertex, for the emission the next
    // segment finds (`CameraMis`).
    var beside = mis;
    var walk = Walk(params.camera_position, direction, vec3(1.0), vec3(0.0), 1u, 1.0);
    var radiance = vec3(0.0);
    var closest_rays = 0u;
    var shadow_rays = 0u;
    // c = (1 / N_c) · (N_v / N_p): each pick stands for N_v / N_c vertices of N_p paths.
    let scale = f32(cache_count) / (f32(params.connections) * params.light_paths);
    loop {
        let hit = trace(Ray(walk.origin, 0.0, walk.direction, MISSED), false);
        closest_rays += 1u;
        let segments = walk.segments;
        if segments > params.max_segments {
            break;
        }
        if hit.prim == NO_HIT {
            radiance += walk.throughput * transmittance(walk.medium, infinity())
                * found_escape(walk.direction, beside, segments);
            break;
        }
        // The vertex (`shade` of camera_pass.rs).
        start_step(&rng, segments, CAMERA_PAIRS);
        var picks_rng = next_stream(rng);
        walk.throughput *= transmittance(walk.medium, hit.t);
        let s = surface_at(hit.prim, hit.u, hit.v);
        let wo = -walk.direction;
        mis_arrive(&mis, hit.t * hit.t, abs(dot3(s.n_g, wo)));
        mis_arrive(&beside, hit.t * hit.t, abs(dot3(s.n_g, wo)));
        radiance += walk.throughput * found_emission(s, hit, walk.direction, beside, segments);
        if segments >= params.max_segments {
            break;
        }
        let b = bsdf_new(material_at(s), s.n_g, s.n_s);
        let out = outgoing(b, wo);
        if !out.valid {
            break;
        }
        if has_non_delta(b.m) && plan_has(CONNECTS) {
            rng.pair += CAMERA_LIGHT_PICK;
            let shadow = weighted_light_sample(&rng, s, b, out, walk, mis);
            if shadow.valid && unblocked(shadow, &shadow_rays) {
                radiance += shadow.contribution;
            }
            // The light vertices picked (`CachePicks`), none from an empty cache.
            let connections = select(params.connections, 0u, cache_count == 0u);
            for (var k = 0u; k < connections; k++) {
                let pick = mul_wide(pcg_next(&picks_rng), cache_count).y;
                let vertex = cache[cache_start + pick];
                if segments + vertex.path_length + 1u > params.max_segments {
                    continue;
                }
                let connection = connect(s, b, out, walk, mis, vertex, scale);
                if connection.valid && unblocked(connection, &shadow_rays) {
                    radiance += connection.contribution;
                }
            }
        }
        if has_non_delta(b.m) && plan_has(MERGES) {
            radiance += walk.throughput * merge(s, b, out, mis, it, segments);
            // Photon mapping proper stops at the first diffuse or glossy vertex.
            if plan_has(PPM) {
                break;
            }
        }
        // The continuation in radiance transport, with the MIS update.
        let sample = scatter(&rng, b, out, false, true);
        if !sample.valid {
            break;
        }
        let cos_out = abs(dot3(s.n_g, sample.wi));
        let specular = sample.kind == KIND_SPECULAR;
        let d_vc_beside = mis_scatter(&mis, cos_out, sample.pdf_fwd, sample.pdf_rev, specular, false);
        beside = SubpathMis(mis.d_vcm, d_vc_beside, mis.d_vm);
        if !walk_on(&walk, &rng, s, sample, false) {
            break;
        }
    }
    film_add(pixel, radiance);
    atomicAdd(&ray_counts[0], closest_rays);
    atomicAdd(&ray_counts[2], shadow_rays);
}
