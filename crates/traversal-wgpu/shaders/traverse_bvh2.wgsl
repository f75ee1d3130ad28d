// Closest-hit and any-hit traversal of a binary BVH whose nodes hold both children's boxes.
// One invocation traces one ray; the stack holds far children with their entry distances so
// that subtrees behind the closest hit so far are skipped when popped.
// STACK_SIZE (the hierarchy's depth) is defined by the host when it composes the module, and
// is_opaque comes from alpha_none.wgsl or alpha_masks.wgsl.

struct Node {
    left_min: vec3<f32>,
    left_index: u32,
    left_max: vec3<f32>,
    right_index: u32,
    right_min: vec3<f32>,
    left_count: u32,
    right_max: vec3<f32>,
    right_count: u32,
}

@group(1) @binding(0) var<storage, read> nodes: array<Node>;

// Traces `ray`; with `any_hit` it returns the first hit found instead of the closest.
fn trace(ray_in: Ray, any_hit: bool) -> Hit {
    var best = Hit(ray_in.tmax, NO_HIT, 0.0, 0.0);
    if !(ray_in.tmin < ray_in.tmax) || arrayLength(&nodes) == 0u {
        return best;
    }
    let ray = prepare_ray(ray_in);
    var stack_node: array<u32, STACK_SIZE>;
    var stack_t: array<f32, STACK_SIZE>;
    var depth = 0u;
    var node = 0u;
    loop {
        let n = nodes[node];
        var t_left = box_entry(n.left_min, n.left_max, ray, best.t);
        var t_right = box_entry(n.right_min, n.right_max, ray, best.t);
        if n.left_count > 0u && t_left < MISSED {
            for (var i = n.left_index; i < n.left_index + n.left_count; i++) {
                best = closer_hit(i, ray, best);
            }
            t_left = MISSED;
        }
        if n.right_count > 0u && t_right < MISSED {
            for (var i = n.right_index; i < n.right_index + n.right_count; i++) {
                best = closer_hit(i, ray, best);
            }
            t_right = MISSED;
        }
        if any_hit && best.prim != NO_HIT {
            break;
        }
        if t_left < MISSED && t_right < MISSED {
            let right_first = t_right < t_left;
            stack_node[depth] = select(n.right_index, n.left_index, right_first);
            stack_t[depth] = select(t_right, t_left, right_first);
            depth += 1u;
            node = select(n.left_index, n.right_index, right_first);
            continue;
        }
        if t_left < MISSED {
            node = n.left_index;
            continue;
        }
        if t_right < MISSED {
            node = n.right_index;
            continue;
        }
        // Pop the nearest pending subtree that can still hold a closer hit.
        var found = false;
        while depth > 0u {
            depth -= 1u;
            if stack_t[depth] <= best.t {
                node = stack_node[depth];
                found = true;
                break;
            }
        }
        if !found {
            break;
        }
    }
    if best.prim != NO_HIT {
        best.prim = ids[best.prim];
    }
    return best;
}
