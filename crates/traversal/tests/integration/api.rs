//! The batch types, the submit/wait pair and chunking behave as documented.

use glam::{Vec3, vec3};
use vcm_traversal::contract::TRIANGLE_AT_Z1;
use vcm_traversal::{
    BuildPreset, CpuBvh, CpuBvhOptions, CpuKernel, HitBatch, Interleave, NO_HIT, RayBatch,
    Traversal, TraversalJob,
};

use crate::common::{Rng, RngExt, triangle_soup};

fn random_rays(rng: &mut Rng, count: usize) -> RayBatch {
    let mut rays = RayBatch::with_capacity(count);
    for _ in 0..count {
        rays.push(
            rng.point_in_box(0.0, 1.0),
            rng.unit_vector(),
            0.0,
            f32::INFINITY,
        );
    }
    rays
}

#[test]
fn ray_batch_push_len_clear() {
    let mut rays = RayBatch::with_capacity(4);
    assert!(rays.is_empty());
    rays.push(vec3(1.0, 2.0, 3.0), vec3(4.0, 5.0, 6.0), 0.5, 7.0);
    rays.push(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY);
    assert_eq!(rays.len(), 2);
    assert_eq!(rays.origin(0), vec3(1.0, 2.0, 3.0));
    assert_eq!(rays.direction(0), vec3(4.0, 5.0, 6.0));
    assert_eq!((rays.tmin[0], rays.tmax[0]), (0.5, 7.0));
    let capacity = rays.origin_x.capacity();
    rays.clear();
    assert!(rays.is_empty() && rays.dir_z.is_empty());
    assert_eq!(rays.origin_x.capacity(), capacity);
}

#[test]
#[should_panic(expected = "RayBatch arrays differ in length")]
fn inconsistent_ray_arrays_are_reported() {
    let bvh = CpuBvh::new(&[], CpuBvhOptions::default()).unwrap();
    let mut rays = RayBatch::default();
    rays.push(Vec3::ZERO, Vec3::X, 0.0, 1.0);
    rays.dir_y.pop();
    bvh.intersect(&rays, &mut HitBatch::default());
}

#[test]
fn outputs_are_resized_and_overwritten() {
    let tris = [TRIANGLE_AT_Z1];
    let bvh = CpuBvh::new(&tris, CpuBvhOptions::default()).unwrap();
    let mut rays = RayBatch::default();
    rays.push(Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY);
    rays.push(Vec3::ZERO, -Vec3::Z, 0.0, f32::INFINITY);
    // Stale contents from a previous, larger batch.
    let mut hits = HitBatch::default();
    hits.resize(5);
    hits.prim.fill(7);
    hits.t.fill(-1.0);
    let mut occluded = vec![true; 5];
    bvh.intersect(&rays, &mut hits);
    bvh.occluded(&rays, &mut occluded);
    assert_eq!(hits.len(), 2);
    assert_eq!(hits.prim, [0, NO_HIT]);
    assert_eq!(hits.t, [1.0, f32::INFINITY]);
    assert_eq!((hits.u[1], hits.v[1]), (0.0, 0.0));
    assert_eq!(occluded, [true, false]);
}

#[test]
fn submit_returns_filled_jobs() {
    let mut rng = Rng::new(30, 0);
    let tris = triangle_soup(&mut rng, 500, 1.0);
    let bvh = CpuBvh::new(&tris, CpuBvhOptions::default()).unwrap();
    let backend: &dyn Traversal = &bvh;
    let rays = random_rays(&mut rng, 300);

    let mut expected_hits = HitBatch::default();
    backend.intersect(&rays, &mut expected_hits);
    let mut expected_occluded = Vec::new();
    backend.occluded(&rays, &mut expected_occluded);

    let pending_hits = backend.submit(TraversalJob::Intersect {
        rays: rays.clone(),
        hits: HitBatch::default(),
    });
    let pending_occluded = backend.submit(TraversalJob::Occluded {
        rays: rays.clone(),
        occluded: Vec::new(),
    });
    match pending_occluded.wait() {
        TraversalJob::Occluded { rays: r, occluded } => {
            assert_eq!(r, rays);
            assert_eq!(occluded, expected_occluded);
        }
        job => panic!("wrong job kind back: {job:?}"),
    }
    let job = pending_hits.wait();
    assert_eq!(job.rays(), &rays);
    match job {
        TraversalJob::Intersect { hits, .. } => assert_eq!(hits, expected_hits),
        job => panic!("wrong job kind back: {job:?}"),
    }
}

#[test]
fn results_do_not_depend_on_chunk_size_or_kernel() {
    let mut rng = Rng::new(31, 0);
    let tris = triangle_soup(&mut rng, 2000, 1.0);
    let rays = random_rays(&mut rng, 1001);
    let trace = |chunk_size, kernel, interleave| {
        let options = CpuBvhOptions {
            preset: BuildPreset::Fast,
            chunk_size,
            kernel,
            interleave,
        };
        let bvh = CpuBvh::new(&tris, options).unwrap();
        let mut hits = HitBatch::default();
        bvh.intersect(&rays, &mut hits);
        let mut occluded = Vec::new();
        bvh.occluded(&rays, &mut occluded);
        (hits, occluded)
    };
    let reference = trace(1, CpuKernel::Portable, Interleave::Off);
    assert!(reference.0.prim.iter().any(|&p| p != NO_HIT));
    for chunk_size in [0, 7, 256, 5000] {
        for kernel in [CpuKernel::Auto, CpuKernel::Portable] {
            for interleave in [Interleave::Off, Interleave::On] {
                let result = trace(chunk_size, kernel, interleave);
                let case = format!("chunk size {chunk_size}, {kernel:?}, {interleave:?}");
                assert_eq!(result, reference, "{case}");
            }
        }
    }
}

#[test]
fn reports_build_statistics() {
    let mut rng = Rng::new(32, 0);
    let tris = triangle_soup(&mut rng, 1000, 1.0);
    let bvh = CpuBvh::new(&tris, CpuBvhOptions::default()).unwrap();
    let bytes_per_triangle = bvh.memory_bytes() as f64 / tris.len() as f64;
    // 36 bytes of triangle and 4 of id, plus a share of 256-byte nodes: a node holds up to
    // eight children of up to three triangles, and far more than a node per four triangles
    // would mean mostly empty slots.
    assert!(
        (40.0..104.0).contains(&bytes_per_triangle),
        "{bytes_per_triangle}"
    );
    assert!(bvh.build_time().as_nanos() > 0);
}
