//! The [`Traversal`] contract as executable checks, for every backend's tests (a new
//! backend's included): each check builds its scenes through the caller's constructor and
//! panics with a message on the first violation.

use glam::{Vec3, vec3};

use crate::{HitBatch, NO_HIT, RayBatch, Traversal};

/// Builds a backend over triangles (triangle `i` is primitive `i`).
pub type Build<'a> = &'a dyn Fn(&[[Vec3; 3]]) -> Box<dyn Traversal>;

/// A triangle in the plane z = 1 around the +z axis (a ray from the origin along +z hits it
/// at t = 1).
pub const TRIANGLE_AT_Z1: [Vec3; 3] = [
    Vec3::new(-1.0, -1.0, 1.0),
    Vec3::new(1.0, -1.0, 1.0),
    Vec3::new(0.0, 1.0, 1.0),
];

/// How many identical triangles [`check_contract`] stacks up in
/// [`many_coincident_triangles`].
pub const COINCIDENT_TRIANGLES: usize = 50_000;

/// Runs every check of this module.
pub fn check_contract(build: Build) {
    check_contract_with(build, COINCIDENT_TRIANGLES);
}

/// Runs every check of this module, stacking `coincident` identical triangles in
/// [`many_coincident_triangles`] (backends on a device that bounds the work of one ray, such
/// as lavapipe, pass fewer).
pub fn check_contract_with(build: Build, coincident: usize) {
    empty_scene_misses_everything(build);
    single_triangle_is_double_sided_and_edge_on_misses(build);
    ties_resolve_to_the_smallest_id(build);
    closed_meshes_hit_from_inside_never_leak(build);
    tmin_skips_the_surface_a_ray_starts_on(build);
    tmin_is_inclusive_and_tmax_exclusive(build);
    invalid_rays_miss(build);
    many_coincident_triangles(build, coincident);
}

/// Traces `rays` with both queries and checks that occlusion agrees with the closest hits.
pub fn trace(bvh: &dyn Traversal, rays: &RayBatch) -> (HitBatch, Vec<bool>) {
    let mut hits = HitBatch::default();
    let mut occluded = Vec::new();
    bvh.intersect(rays, &mut hits);
    bvh.occluded(rays, &mut occluded);
    assert_eq!(hits.len(), rays.len());
    assert_occlusion_matches_hits(&hits, &occluded);
    (hits, occluded)
}

/// Occlusion must report exactly the rays that have a closest hit.
pub fn assert_occlusion_matches_hits(hits: &HitBatch, occluded: &[bool]) {
    assert_eq!(hits.len(), occluded.len());
    for (i, &occluded) in occluded.iter().enumerate() {
        assert_eq!(
            occluded,
            hits.is_hit(i),
            "ray {i}: occlusion disagrees with closest hit"
        );
    }
}

/// Rays `(origin, direction)` over `[0, ∞)`.
pub fn unbounded_rays(rays: &[(Vec3, Vec3)]) -> RayBatch {
    let mut batch = RayBatch::default();
    for &(origin, direction) in rays {
        batch.push(origin, direction, 0.0, f32::INFINITY);
    }
    batch
}

/// A deterministic low-discrepancy point in [0, 1)³ (the R3 sequence), for test rays.
fn r3(i: usize) -> Vec3 {
    let g = 1.220_744_1_f64;
    let f = |k: i32| ((0.5 + i as f64 / g.powi(k)).fract()) as f32;
    vec3(f(1), f(2), f(3))
}

/// A unit direction from a point of [0, 1)³.
fn direction(u: Vec3) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u.y;
    vec3(r * phi.cos(), r * phi.sin(), z)
}

/// An empty backend misses every ray, and empty batches give empty outputs.
pub fn empty_scene_misses_everything(build: Build) {
    let bvh = build(&[]);
    let rays = RayBatch::default();
    let (hits, occluded) = trace(bvh.as_ref(), &rays);
    assert!(hits.is_empty() && occluded.is_empty());
    let rays: Vec<_> = (0..100)
        .map(|i| (r3(i) * 2.0 - 1.0, direction(r3(i + 100))))
        .collect();
    let (hits, occluded) = trace(bvh.as_ref(), &unbounded_rays(&rays));
    assert!(hits.prim.iter().all(|&p| p == NO_HIT));
    assert!(hits.t.iter().all(|&t| t == f32::INFINITY));
    assert!(!occluded.iter().any(|&o| o));
}

/// Front and back faces are hit at the same t with the right barycentrics; a ray in the
/// triangle's plane misses it.
pub fn single_triangle_is_double_sided_and_edge_on_misses(build: Build) {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let bvh = build(&[tri]);
    let rays = unbounded_rays(&[
        (vec3(0.25, 0.25, 1.0), vec3(0.0, 0.0, -1.0)), // front
        (vec3(0.25, 0.25, -2.0), vec3(0.0, 0.0, 2.0)), // back, direction not normalised
        (vec3(0.75, 0.75, 1.0), vec3(0.0, 0.0, -1.0)), // outside
        (vec3(-1.0, 0.25, 0.0), vec3(1.0, 0.0, 0.0)),  // in plane
    ]);
    let (hits, _) = trace(bvh.as_ref(), &rays);
    assert_eq!(hits.prim, [0, 0, NO_HIT, NO_HIT]);
    assert_eq!(&hits.t[..2], [1.0, 1.0]);
    for i in 0..2 {
        assert!((hits.u[i] - 0.25).abs() < 1e-6 && (hits.v[i] - 0.25).abs() < 1e-6);
    }
    assert_eq!(&hits.u[2..], [0.0, 0.0]);
}

/// Coplanar overlapping triangles: at equal t the smallest id is reported, from either side,
/// and a closer triangle still wins.
pub fn ties_resolve_to_the_smallest_id(build: Build) {
    let small = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let big = [
        vec3(-1.0, -1.0, 0.0),
        vec3(2.0, -1.0, 0.0),
        vec3(-1.0, 2.0, 0.0),
    ];
    let in_front = [
        vec3(0.0, 0.0, 0.5),
        vec3(0.5, 0.0, 0.5),
        vec3(0.0, 0.5, 0.5),
    ];
    let rays = unbounded_rays(&[
        (vec3(0.3, 0.3, 1.0), vec3(0.0, 0.0, -1.0)), // small + big tie
        (vec3(0.3, 0.3, -1.0), vec3(0.0, 0.0, 1.0)), // the same tie from behind
        (vec3(0.1, 0.1, 1.0), vec3(0.0, 0.0, -1.0)), // in front wins
        (vec3(1.5, -0.5, 1.0), vec3(0.0, 0.0, -1.0)), // big only
    ]);
    // The same scene in both id orders: the answer follows the ids, not the layout.
    for order in [[small, big, in_front], [big, small, in_front]] {
        let bvh = build(&order);
        let (hits, _) = trace(bvh.as_ref(), &rays);
        let big_id = if order[0] == big { 0 } else { 1 };
        assert_eq!(hits.prim, [0, 0, 2, big_id]);
        assert_eq!(hits.t, [1.0, 1.0, 0.5, 1.0]);
    }
}

/// The 12 triangles of an axis-aligned box.
pub fn cuboid(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let corner =
        |i: usize| Vec3::select(glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), hi, lo);
    let faces = [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ];
    faces
        .iter()
        .flat_map(|&[a, b, c, d]| {
            [
                [corner(a), corner(b), corner(c)],
                [corner(a), corner(c), corner(d)],
            ]
        })
        .collect()
}

/// A closed UV sphere (poles are fans), `rings × segments` quads, shared vertices exact.
pub fn uv_sphere(center: Vec3, radius: f32, rings: usize, segments: usize) -> Vec<[Vec3; 3]> {
    let vertex = |ring: usize, segment: usize| {
        if ring == 0 || ring == rings {
            // Exact, shared poles.
            return center + vec3(0.0, 0.0, if ring == 0 { radius } else { -radius });
        }
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        let phi = std::f32::consts::TAU * (segment % segments) as f32 / segments as f32;
        center
            + radius
                * vec3(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                )
    };
    let mut tris = Vec::new();
    for ring in 0..rings {
        for segment in 0..segments {
            let (a, b) = (vertex(ring, segment), vertex(ring, segment + 1));
            let (c, d) = (vertex(ring + 1, segment), vertex(ring + 1, segment + 1));
            if ring != 0 {
                tris.push([a, c, b]);
            }
            if ring != rings - 1 {
                tris.push([b, c, d]);
            }
        }
    }
    tris
}

/// Rays from inside a closed convex mesh towards points along every edge and at every
/// centroid: none may escape and all reach the surface at t = 1. Returns the ray count.
pub fn assert_no_leaks(bvh: &dyn Traversal, tris: &[[Vec3; 3]], origins: &[Vec3]) -> usize {
    let mut rays = RayBatch::default();
    for &origin in origins {
        for tri in tris {
            for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                for k in 0..=16 {
                    let target = tri[a].lerp(tri[b], k as f32 / 16.0);
                    rays.push(origin, target - origin, 0.0, f32::INFINITY);
                }
            }
            let centroid = (tri[0] + tri[1] + tri[2]) / 3.0;
            rays.push(origin, centroid - origin, 0.0, f32::INFINITY);
        }
    }
    let (hits, _) = trace(bvh, &rays);
    let leaks = hits.prim.iter().filter(|&&p| p == NO_HIT).count();
    assert_eq!(
        leaks,
        0,
        "{leaks} of {} rays escaped the closed mesh",
        rays.len()
    );
    for (i, t) in hits.t.iter().enumerate() {
        assert!((t - 1.0).abs() < 1e-4, "ray {i}: t = {t}");
    }
    rays.len()
}

/// Boxes at several scales and positions, and a sphere, shot from inside.
pub fn closed_meshes_hit_from_inside_never_leak(build: Build) {
    for (lo, hi) in [
        (Vec3::splat(-1.0), Vec3::splat(1.0)),
        (Vec3::ZERO, vec3(1.0, 2.0, 3.0)),
        (Vec3::splat(1000.0), Vec3::splat(1000.5)),
        (Vec3::splat(-1e-3), vec3(1e-3, 2e-3, 1e-3)),
    ] {
        let tris = cuboid(lo, hi);
        let size = hi - lo;
        let origins = [
            lo + size * 0.5,
            lo + size * vec3(0.1, 0.2, 0.3),
            lo + size * vec3(0.9, 0.5, 0.01),
        ];
        assert_no_leaks(build(&tris).as_ref(), &tris, &origins);
    }
    let center = vec3(0.3, -0.2, 5.0);
    let tris = uv_sphere(center, 2.0, 16, 32);
    let origins = [
        center,
        center + vec3(0.5, 0.5, -0.3),
        center + vec3(-1.2, 0.1, 0.2),
    ];
    assert!(assert_no_leaks(build(&tris).as_ref(), &tris, &origins) > 40_000);
}

/// Rays that start on a surface with a small tmin never hit it again.
pub fn tmin_skips_the_surface_a_ray_starts_on(build: Build) {
    let lower = [
        vec3(-5.0, 0.0, -5.0),
        vec3(5.0, 0.0, -5.0),
        vec3(0.0, 0.0, 5.0),
    ];
    let upper = lower.map(|p| p + Vec3::Y);
    let bvh = build(&[lower, upper]);
    let (mut up, mut down) = (RayBatch::default(), RayBatch::default());
    for i in 0..500 {
        let u = r3(i);
        let (a, b) = (0.1 + 0.3 * u.x, 0.1 + 0.3 * u.y);
        let origin = lower[0] * (1.0 - a - b) + lower[1] * a + lower[2] * b;
        let dir = (direction(r3(i + 1000)) * 0.3 + Vec3::Y).normalize();
        up.push(origin, dir, 1e-4, f32::INFINITY);
        down.push(origin, -dir, 1e-4, f32::INFINITY);
    }
    let (hits, _) = trace(bvh.as_ref(), &up);
    assert!(
        hits.prim.iter().all(|&p| p == 1),
        "a ray leaving the surface hit itself"
    );
    let (hits, _) = trace(bvh.as_ref(), &down);
    assert!(
        hits.prim.iter().all(|&p| p == NO_HIT),
        "a ray leaving the surface hit itself"
    );
}

/// `[tmin, tmax)`: a hit exactly at tmin counts, one exactly at tmax does not.
pub fn tmin_is_inclusive_and_tmax_exclusive(build: Build) {
    let tris: Vec<_> = (1..=8)
        .map(|z| {
            let z = z as f32;
            [
                vec3(-10.0, -10.0, z),
                vec3(10.0, -10.0, z),
                vec3(0.0, 10.0, z),
            ]
        })
        .collect();
    let bvh = build(&tris);
    let cases = [
        (0.0, f32::INFINITY, Some(0)),
        (1.0, f32::INFINITY, Some(0)),
        (1.5, f32::INFINITY, Some(1)),
        (3.0, 3.5, Some(2)),
        (0.0, 1.0, None),
        (3.25, 3.75, None),
        (8.5, f32::INFINITY, None),
        (5.0, 5.0, None),
        (6.0, 5.0, None),
        (-1.0, 0.5, None),
    ];
    let mut rays = RayBatch::default();
    for (tmin, tmax, _) in cases {
        rays.push(Vec3::ZERO, Vec3::Z, tmin, tmax);
    }
    let (hits, _) = trace(bvh.as_ref(), &rays);
    for (i, (tmin, tmax, expected)) in cases.into_iter().enumerate() {
        assert_eq!(hits.prim[i], expected.unwrap_or(NO_HIT), "[{tmin}, {tmax})");
    }
}

/// Non-finite or zero directions, non-finite origins and NaN bounds miss; zero and
/// negative-zero direction components do not make a valid ray miss.
pub fn invalid_rays_miss(build: Build) {
    let bvh = build(&[TRIANGLE_AT_Z1]);
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    let mut rays = RayBatch::default();
    rays.push(vec3(nan, 0.0, 0.0), Vec3::Z, 0.0, inf);
    rays.push(Vec3::ZERO, vec3(0.0, nan, 1.0), 0.0, inf);
    rays.push(Vec3::ZERO, Vec3::splat(nan), 0.0, inf);
    rays.push(vec3(0.0, 0.0, -inf), Vec3::Z, 0.0, inf);
    rays.push(Vec3::ZERO, vec3(0.0, 0.0, inf), 0.0, inf);
    rays.push(Vec3::ZERO, Vec3::ZERO, 0.0, inf);
    rays.push(Vec3::ZERO, Vec3::Z, nan, inf);
    rays.push(Vec3::ZERO, Vec3::Z, 0.0, nan);
    let (hits, occluded) = trace(bvh.as_ref(), &rays);
    assert!(hits.prim.iter().all(|&p| p == NO_HIT));
    assert!(!occluded.iter().any(|&o| o));

    let mut rays = RayBatch::default();
    rays.push(Vec3::ZERO, vec3(0.0, 0.0, 1.0), 0.0, inf);
    rays.push(Vec3::ZERO, vec3(-0.0, -0.0, 1.0), 0.0, inf);
    rays.push(Vec3::ZERO, vec3(1e-30, -1e-30, 1.0), 0.0, inf);
    let (hits, _) = trace(bvh.as_ref(), &rays);
    assert_eq!(hits.prim, [0, 0, 0]);
}

/// `count` identical triangles and a smaller one in front: rays through the small one hit
/// it, the others hit the identical stack at its smallest id.
pub fn many_coincident_triangles(build: Build, count: usize) {
    let mut tris = vec![TRIANGLE_AT_Z1; count];
    let small = [
        vec3(-0.2, -0.2, 0.5),
        vec3(0.2, -0.2, 0.5),
        vec3(0.0, 0.2, 0.5),
    ];
    tris.push(small);
    let bvh = build(&tris);
    let mut rays = RayBatch::default();
    let mut expected = Vec::new();
    for i in 0..200 {
        let u = r3(i);
        let target = vec3(u.x * 1.6 - 0.8, u.y * 1.6 - 0.8, 1.0);
        // Whether the ray towards `p` (on z = 1) passes inside `tri` by more than `margin`
        // (its projection from the origin onto z = 1); negative margins test "outside".
        let inside = |tri: &[Vec3; 3], p: Vec3, margin: f32| {
            let [a, b, c] = tri.map(|v| v.truncate() / v.z);
            let p = p.truncate();
            let edge = |a: glam::Vec2, b: glam::Vec2| (b - a).perp_dot(p - a) / (b - a).length();
            edge(a, b) > margin && edge(b, c) > margin && edge(c, a) > margin
        };
        let (in_small, in_big) = (
            inside(&small, target, 0.01),
            inside(&TRIANGLE_AT_Z1, target, 0.01),
        );
        let out_small = !inside(&small, target, -0.01);
        let out_big = !inside(&TRIANGLE_AT_Z1, target, -0.01);
        let answer = if in_small {
            (count as u32, 0.5)
        } else if out_small && in_big {
            (0, 1.0)
        } else if out_small && out_big {
            (NO_HIT, f32::INFINITY)
        } else {
            continue; // grazes an edge
        };
        rays.push(Vec3::ZERO, target, 0.0, f32::INFINITY);
        expected.push(answer);
    }
    assert!(expected.len() > 150);
    let (hits, _) = trace(bvh.as_ref(), &rays);
    for (i, &(prim, t)) in expected.iter().enumerate() {
        assert_eq!(hits.prim[i], prim, "ray {i} towards {}", rays.direction(i));
        assert!(
            prim == NO_HIT || (hits.t[i] - t).abs() < 1e-6,
            "ray {i}: t = {}",
            hits.t[i]
        );
    }
}
