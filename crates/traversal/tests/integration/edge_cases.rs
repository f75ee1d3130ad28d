//! Hand-made scenes for the cases random testing rarely reaches: the backend-independent
//! contract (`vcm_traversal::contract`) for every build preset and kernel, plus what is
//! specific to the CPU backend.

use glam::{Vec3, vec3};
use vcm_traversal::contract::{self, TRIANGLE_AT_Z1, assert_no_leaks, cuboid, uv_sphere};
use vcm_traversal::{
    BuildError, BuildPreset, CpuBvh, CpuBvhOptions, CpuKernel, Interleave, RayBatch, Traversal,
};

use crate::common::{self, Rng, RngExt};

fn build(tris: &[[Vec3; 3]]) -> Box<dyn Traversal> {
    Box::new(CpuBvh::new(tris, CpuBvhOptions::default()).unwrap())
}

#[test]
fn cpu_backend_meets_the_traversal_contract() {
    contract::check_contract(&build);
}

#[test]
fn cpu_backend_meets_the_traversal_contract_with_rays_in_turn() {
    let options = CpuBvhOptions {
        interleave: Interleave::On,
        ..CpuBvhOptions::default()
    };
    let build = |tris: &[[Vec3; 3]]| -> Box<dyn Traversal> {
        Box::new(CpuBvh::new(tris, options).unwrap())
    };
    contract::check_contract(&build);
}

#[test]
fn empty_scene_uses_no_memory() {
    assert_eq!(
        CpuBvh::new(&[], CpuBvhOptions::default())
            .unwrap()
            .memory_bytes(),
        0
    );
}

#[test]
fn closed_cube_never_leaks_with_any_preset_or_kernel() {
    for (lo, hi) in [
        (Vec3::splat(-1.0), Vec3::splat(1.0)),
        (Vec3::splat(1000.0), Vec3::splat(1000.5)),
    ] {
        let tris = cuboid(lo, hi);
        let size = hi - lo;
        let origins = [lo + size * 0.5, lo + size * vec3(0.9, 0.5, 0.01)];
        for preset in [BuildPreset::Fastest, BuildPreset::Medium, BuildPreset::Slow] {
            for kernel in [CpuKernel::Auto, CpuKernel::Portable] {
                let options = CpuBvhOptions {
                    preset,
                    kernel,
                    ..CpuBvhOptions::default()
                };
                assert_no_leaks(&CpuBvh::new(&tris, options).unwrap(), &tris, &origins);
            }
        }
    }
}

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
fn many_coincident_triangles_build_fast_and_match_the_reference() {
    // Identical boxes once made obvhs's PLOC degenerate into a chain (quadratic build time,
    // then a stack overflow); the build must stay fast and traversal correct.
    let mut tris = vec![TRIANGLE_AT_Z1; 50_000];
    tris.push(TRIANGLE_AT_Z1.map(|p| p * 0.5));
    let bvh = CpuBvh::new(&tris, CpuBvhOptions::default()).unwrap();
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
    let (hits, _) = contract::trace(&bvh, &rays);
    common::assert_matches_reference(&tris, &rays, &hits);
}
