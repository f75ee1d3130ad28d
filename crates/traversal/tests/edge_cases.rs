//! Hand-made scenes for the cases random testing rarely reaches.

mod common;

use common::{Rng, RngExt, TRIANGLE_AT_Z1, cuboid, uv_sphere};
use glam::{Vec3, vec3};
use vcm_traversal::{
    BuildError, BuildPreset, CpuBvh, CpuBvhOptions, CpuKernel, HitBatch, NO_HIT, RayBatch,
    Traversal,
};

fn build(tris: &[[Vec3; 3]]) -> CpuBvh {
    CpuBvh::new(tris, CpuBvhOptions::default()).unwrap()
}

fn trace(bvh: &CpuBvh, rays: &RayBatch) -> (HitBatch, Vec<bool>) {
    let mut hits = HitBatch::default();
    let mut occluded = Vec::new();
    bvh.intersect(rays, &mut hits);
    bvh.occluded(rays, &mut occluded);
    common::assert_occlusion_matches_hits(&hits, &occluded);
    (hits, occluded)
}

/// Rays `(origin, direction)` over `[0, ∞)`.
fn unbounded_rays(rays: &[(Vec3, Vec3)]) -> RayBatch {
    let mut batch = RayBatch::default();
    for &(origin, direction) in rays {
        batch.push(origin, direction, 0.0, f32::INFINITY);
    }
    batch
}

#[test]
fn empty_scene_misses_everything() {
    let bvh = build(&[]);
    let mut rng = Rng::new(10, 0);
    let mut rays = RayBatch::default();
    for _ in 0..100 {
        rays.push(
            rng.point_in_box(-1.0, 1.0),
            rng.unit_vector(),
            0.0,
            f32::INFINITY,
        );
    }
    let (hits, occluded) = trace(&bvh, &rays);
    assert!(hits.prim.iter().all(|&p| p == NO_HIT));
    assert!(hits.t.iter().all(|&t| t == f32::INFINITY));
    assert!(!occluded.iter().any(|&o| o));
    assert_eq!(bvh.memory_bytes(), 0);

    let (hits, occluded) = trace(&bvh, &RayBatch::default());
    assert!(hits.is_empty() && occluded.is_empty());
}

#[test]
fn single_triangle_is_double_sided_and_edge_on_misses() {
    let tri = [
        vec3(0.0, 0.0, 0.0),
        vec3(1.0, 0.0, 0.0),
        vec3(0.0, 1.0, 0.0),
    ];
    let bvh = build(&[tri]);
    let rays = unbounded_rays(&[
        (vec3(0.25, 0.25, 1.0), vec3(0.0, 0.0, -1.0)), // front
        (vec3(0.25, 0.25, -2.0), vec3(0.0, 0.0, 2.0)), // back
        (vec3(0.75, 0.75, 1.0), vec3(0.0, 0.0, -1.0)), // outside
        (vec3(-1.0, 0.25, 0.0), vec3(1.0, 0.0, 0.0)),  // in plane
    ]);
    let (hits, _) = trace(&bvh, &rays);
    assert_eq!(hits.prim, [0, 0, NO_HIT, NO_HIT]);
    assert_eq!(hits.t[0], 1.0);
    assert_eq!(hits.t[1], 1.0);
    assert!((hits.u[0] - 0.25).abs() < 1e-6 && (hits.v[0] - 0.25).abs() < 1e-6);
    assert!((hits.u[1] - 0.25).abs() < 1e-6 && (hits.v[1] - 0.25).abs() < 1e-6);
}

#[test]
fn coplanar_and_overlapping_triangles() {
    let big = [
        vec3(-1.0, -1.0, 0.0),
        vec3(2.0, -1.0, 0.0),
        vec3(-1.0, 2.0, 0.0),
    ];
    let small = [
        vec3(0.0, 0.0, 0.0),
        vec3(1.0, 0.0, 0.0),
        vec3(0.0, 1.0, 0.0),
    ];
    let in_front = [
        vec3(0.0, 0.0, 0.5),
        vec3(0.5, 0.0, 0.5),
        vec3(0.0, 0.5, 0.5),
    ];
    let bvh = build(&[big, small, in_front]);
    let rays = unbounded_rays(&[
        (vec3(0.3, 0.3, 1.0), vec3(0.0, 0.0, -1.0)), // big + small tie
        (vec3(0.1, 0.1, 1.0), vec3(0.0, 0.0, -1.0)), // in front wins
        (vec3(0.1, 0.1, -1.0), vec3(0.0, 0.0, 1.0)), // from behind
        (vec3(1.5, -0.5, 1.0), vec3(0.0, 0.0, -1.0)), // big only
    ]);
    let (hits, _) = trace(&bvh, &rays);
    assert!(hits.prim[0] == 0 || hits.prim[0] == 1);
    assert_eq!(hits.t[0], 1.0);
    assert_eq!((hits.prim[1], hits.t[1]), (2, 0.5));
    assert!(hits.prim[2] == 0 || hits.prim[2] == 1);
    assert_eq!(hits.t[2], 1.0);
    assert_eq!((hits.prim[3], hits.t[3]), (0, 1.0));
}

/// Rays from inside a closed mesh towards every vertex, along every edge and across faces:
/// none may escape, whatever the mesh's scale and position.
fn assert_no_leaks(tris: &[[Vec3; 3]], origins: &[Vec3], options: CpuBvhOptions) -> usize {
    let bvh = CpuBvh::new(tris, options).unwrap();
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
    let (hits, _) = trace(&bvh, &rays);
    let leaks = hits.prim.iter().filter(|&&p| p == NO_HIT).count();
    assert_eq!(
        leaks,
        0,
        "{leaks} of {} rays escaped the closed mesh",
        rays.len()
    );
    for i in 0..rays.len() {
        // Every target lies on the surface at t = 1 (and it is convex).
        assert!((hits.t[i] - 1.0).abs() < 1e-4, "ray {i}: t = {}", hits.t[i]);
    }
    rays.len()
}

#[test]
fn closed_cube_hit_from_inside_never_leaks() {
    for (lo, hi) in [
        (Vec3::splat(-1.0), Vec3::splat(1.0)),
        (vec3(0.0, 0.0, 0.0), vec3(1.0, 2.0, 3.0)),
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
        for preset in [BuildPreset::Fastest, BuildPreset::Medium, BuildPreset::Slow] {
            for kernel in [CpuKernel::Auto, CpuKernel::Portable] {
                let options = CpuBvhOptions {
                    preset,
                    kernel,
                    ..CpuBvhOptions::default()
                };
                assert_no_leaks(&tris, &origins, options);
            }
        }
    }
}

#[test]
fn closed_sphere_hit_from_inside_never_leaks() {
    let center = vec3(0.3, -0.2, 5.0);
    let tris = uv_sphere(center, 2.0, 16, 32);
    let origins = [
        center,
        center + vec3(0.5, 0.5, -0.3),
        center + vec3(-1.2, 0.1, 0.2),
    ];
    let rays = assert_no_leaks(&tris, &origins, CpuBvhOptions::default());
    assert!(rays > 40_000);
}

/// The leak tests above have teeth: obvhs's Möller–Trumbore test lets a good share of the
/// same rays through, which is why the backend uses the watertight test.
#[test]
fn moller_trumbore_would_leak() {
    use obvhs::{ray::Ray, triangle::Triangle};
    let tris = uv_sphere(vec3(0.3, -0.2, 5.0), 2.0, 16, 32);
    let moller: Vec<_> = tris
        .iter()
        .map(|&[v0, v1, v2]| Triangle {
            v0: v0.into(),
            v1: v1.into(),
            v2: v2.into(),
        })
        .collect();
    let origin = vec3(0.3, -0.2, 5.0);
    let mut rays = 0;
    let mut leaks = 0;
    for tri in &tris {
        for (a, b) in [(0, 1), (1, 2), (2, 0)] {
            for k in 0..=16 {
                let target = tri[a].lerp(tri[b], k as f32 / 16.0);
                let ray = Ray::new_inf(origin.into(), (target - origin).into());
                rays += 1;
                leaks += usize::from(moller.iter().all(|t| t.intersect(&ray) == f32::INFINITY));
            }
        }
    }
    println!("Möller–Trumbore: {leaks} of {rays} rays escaped");
    assert!(leaks * 100 > rays, "only {leaks} of {rays} rays escaped");
}

#[test]
fn tmin_skips_the_surface_a_ray_starts_on() {
    // Two parallel planes; rays start exactly on the lower one (at barycentric points).
    let lower = [
        vec3(-5.0, 0.0, -5.0),
        vec3(5.0, 0.0, -5.0),
        vec3(0.0, 0.0, 5.0),
    ];
    let upper = lower.map(|p| p + Vec3::Y);
    let bvh = build(&[lower, upper]);
    let mut rng = Rng::new(11, 0);
    let mut up = RayBatch::default();
    let mut down = RayBatch::default();
    for _ in 0..500 {
        let (u, v) = (rng.range(0.1, 0.4), rng.range(0.1, 0.4));
        let origin = lower[0] * (1.0 - u - v) + lower[1] * u + lower[2] * v;
        let direction = (rng.unit_vector() * 0.3 + Vec3::Y).normalize();
        up.push(origin, direction, 1e-4, f32::INFINITY);
        down.push(origin, -direction, 1e-4, f32::INFINITY);
    }
    let (hits, _) = trace(&bvh, &up);
    assert!(
        hits.prim.iter().all(|&p| p == 1),
        "a ray leaving the surface hit itself"
    );
    let (hits, _) = trace(&bvh, &down);
    assert!(
        hits.prim.iter().all(|&p| p == NO_HIT),
        "a ray leaving the surface hit itself"
    );
}

#[test]
fn tmin_is_inclusive_and_tmax_exclusive() {
    // Planes at z = 1, 2, ..., 8, each a large triangle; a ray along +z from the origin.
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
    ];
    let mut rays = RayBatch::default();
    for (tmin, tmax, _) in cases {
        rays.push(Vec3::ZERO, Vec3::Z, tmin, tmax);
    }
    let (hits, _) = trace(&bvh, &rays);
    for (i, (tmin, tmax, expected)) in cases.into_iter().enumerate() {
        let expected = expected.unwrap_or(NO_HIT);
        assert_eq!(hits.prim[i], expected, "[{tmin}, {tmax})");
    }
}

#[test]
fn invalid_rays_miss_without_panicking() {
    let bvh = build(&[TRIANGLE_AT_Z1]);
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    let mut rays = RayBatch::default();
    rays.push(vec3(nan, 0.0, 0.0), Vec3::Z, 0.0, inf);
    rays.push(Vec3::ZERO, vec3(0.0, nan, 1.0), 0.0, inf);
    rays.push(Vec3::ZERO, Vec3::splat(nan), 0.0, inf);
    rays.push(vec3(0.0, 0.0, -inf), Vec3::Z, 0.0, inf);
    rays.push(Vec3::ZERO, vec3(0.0, 0.0, inf), 0.0, inf);
    rays.push(Vec3::ZERO, Vec3::ZERO, 0.0, inf);
    rays.push(Vec3::ZERO, Vec3::Z, nan, inf);
    rays.push(Vec3::ZERO, Vec3::Z, 0.0, nan);
    let (hits, occluded) = trace(&bvh, &rays);
    assert!(hits.prim.iter().all(|&p| p == NO_HIT));
    assert!(!occluded.iter().any(|&o| o));

    // Axis-aligned rays with zero and negative-zero components still hit.
    let mut rays = RayBatch::default();
    rays.push(Vec3::ZERO, vec3(0.0, 0.0, 1.0), 0.0, inf);
    rays.push(Vec3::ZERO, vec3(-0.0, -0.0, 1.0), 0.0, inf);
    rays.push(Vec3::ZERO, vec3(1e-30, -1e-30, 1.0), 0.0, inf);
    let (hits, _) = trace(&bvh, &rays);
    assert_eq!(hits.prim, [0, 0, 0]);
}

#[test]
fn non_finite_vertices_are_rejected_by_index() {
    let good = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let bad = [Vec3::ZERO, vec3(f32::NAN, 0.0, 0.0), Vec3::Y];
    let err = CpuBvh::new(&[good, good, bad], CpuBvhOptions::default()).err();
    assert_eq!(err, Some(BuildError::NonFiniteVertex { triangle: 2 }));
    let err = CpuBvh::new(&[[Vec3::INFINITY; 3]], CpuBvhOptions::default()).err();
    assert_eq!(err, Some(BuildError::NonFiniteVertex { triangle: 0 }));
    assert_eq!(
        err.unwrap().to_string(),
        "triangle 0 has a non-finite vertex coordinate"
    );
}

#[test]
fn many_coincident_triangles() {
    // Identical boxes once made obvhs's PLOC degenerate into a chain (quadratic build time,
    // then a stack overflow); the build must stay fast and traversal correct.
    let mut tris = vec![TRIANGLE_AT_Z1; 50_000];
    tris.push(TRIANGLE_AT_Z1.map(|p| p * 0.5));
    let bvh = build(&tris);
    assert!(
        bvh.build_time().as_secs_f32() < 10.0,
        "{:?}",
        bvh.build_time()
    );
    let mut rng = Rng::new(12, 0);
    let mut rays = RayBatch::default();
    for _ in 0..100 {
        let direction = vec3(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 1.0);
        rays.push(Vec3::ZERO, direction, 0.0, f32::INFINITY);
        rays.push(Vec3::ZERO, direction, 0.0, 0.75);
    }
    let (hits, _) = trace(&bvh, &rays);
    common::assert_matches_reference(&tris, &rays, &hits);
}
