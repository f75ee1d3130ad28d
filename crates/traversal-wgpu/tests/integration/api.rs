//! The GPU backend against the backend-independent traversal contract, and its own API:
//! submit/wait with several batches in flight, outputs resized and overwritten, build errors.

use std::sync::Arc;

use glam::Vec3;
use vcm_scene::sampling::Rng;
use vcm_traversal::contract::{self, uv_sphere};
use vcm_traversal::{BuildError, HitBatch, NO_HIT, RayBatch, Traversal, TraversalJob};
use vcm_traversal_wgpu::{GpuBvh, GpuBvhOptions, GpuDevice, GpuError, NodeLayout};

use crate::common::{gpu, random_rays};

fn backend(device: &Arc<GpuDevice>, triangles: &[[Vec3; 3]]) -> GpuBvh {
    GpuBvh::new(device.clone(), triangles, GpuBvhOptions::default()).unwrap()
}

/// The whole contract on every layout. On a software adapter the coincident-triangle check
/// stacks 5,000 triangles instead of 50,000: lavapipe ends a kernel invocation's loops after
/// 65,535 iterations in all (see `GpuDevice::is_software`), and a ray through 50,000
/// coincident triangles must test every one of them to find the smallest id.
#[test]
fn gpu_backend_meets_the_traversal_contract_with_every_layout() {
    let Some(device) = gpu().map(Arc::new) else {
        return;
    };
    let coincident = if device.is_software() {
        5_000
    } else {
        contract::COINCIDENT_TRIANGLES
    };
    for layout in [NodeLayout::Binary, NodeLayout::Wide] {
        let options = GpuBvhOptions {
            layout,
            ..GpuBvhOptions::default()
        };
        contract::check_contract_with(
            &|triangles| Box::new(GpuBvh::new(device.clone(), triangles, options).unwrap()),
            coincident,
        );
    }
}

#[test]
fn batches_in_flight_together_match_synchronous_queries() {
    let Some(device) = gpu().map(Arc::new) else {
        return;
    };
    let triangles = uv_sphere(Vec3::ZERO, 1.0, 32, 64);
    let bvh = backend(&device, &triangles);
    let mut rng = Rng::new(3, 0);
    let batches: Vec<RayBatch> = [1, 1000, 70_000, 5]
        .iter()
        .map(|&n| random_rays(&mut rng, Vec3::splat(-2.0), Vec3::splat(2.0), n))
        .collect();
    let pending: Vec<_> = batches
        .iter()
        .enumerate()
        .map(|(i, rays)| {
            let job = if i % 2 == 0 {
                // Stale output from an earlier, larger batch must be overwritten.
                let mut hits = HitBatch::default();
                hits.resize(rays.len() + 17);
                TraversalJob::Intersect {
                    rays: rays.clone(),
                    hits,
                }
            } else {
                TraversalJob::Occluded {
                    rays: rays.clone(),
                    occluded: vec![true; 3],
                }
            };
            bvh.submit(job)
        })
        .collect();
    for (i, pending) in pending.into_iter().enumerate() {
        match pending.wait() {
            TraversalJob::Intersect { rays, hits } => {
                let mut expected = HitBatch::default();
                bvh.intersect(&rays, &mut expected);
                assert_eq!(hits, expected, "batch {i}");
                assert!(rays.len() < 1000 || hits.prim.iter().any(|&p| p != NO_HIT));
            }
            TraversalJob::Occluded { rays, occluded } => {
                let mut expected = Vec::new();
                bvh.occluded(&rays, &mut expected);
                assert_eq!(occluded, expected, "batch {i}");
            }
        }
    }
    // Slots are reused: the largest batch determines the memory held.
    assert!(bvh.memory_bytes() >= 70_000 * 32);
}

#[test]
fn invalid_triangles_are_reported_before_touching_the_device() {
    let Some(device) = gpu().map(Arc::new) else {
        return;
    };
    let bad = [Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Y];
    let error = GpuBvh::new(
        device,
        &[[Vec3::ZERO, Vec3::X, Vec3::Y], bad],
        GpuBvhOptions::default(),
    )
    .err()
    .unwrap();
    assert!(matches!(
        error,
        GpuError::Build(BuildError::NonFiniteVertex { triangle: 1 })
    ));
}

/// Kernel timing for the benchmarks: a positive GPU time wherever the adapter has timestamp
/// queries (lavapipe has), none for an empty batch, and the backend's answers unchanged by
/// the timed dispatches.
#[test]
fn kernels_are_timed_where_the_adapter_has_timestamps() {
    let Some(device) = gpu().map(Arc::new) else {
        return;
    };
    let bvh = backend(&device, &uv_sphere(Vec3::ZERO, 1.0, 16, 32));
    let rays = random_rays(
        &mut Rng::new(5, 0),
        Vec3::splat(-2.0),
        Vec3::splat(2.0),
        5000,
    );
    let (mut before, mut after) = (HitBatch::default(), HitBatch::default());
    bvh.intersect(&rays, &mut before);
    assert_eq!(bvh.kernel_time(&RayBatch::default(), false, 3), None);
    for occlusion in [false, true] {
        let time = bvh.kernel_time(&rays, occlusion, 3);
        assert_eq!(time.is_some(), device.has_timestamps(), "{occlusion}");
        assert!(time.is_none_or(|t| !t.is_zero()), "{time:?}");
    }
    bvh.intersect(&rays, &mut after);
    assert_eq!(before, after);
}

/// A device lost mid-render fails the backend instead of panicking: the batch in flight and
/// every later one report misses and no occlusion, and the backend says why.
#[test]
fn a_lost_device_fails_the_backend_instead_of_panicking() {
    let Some(device) = gpu().map(Arc::new) else {
        return;
    };
    let bvh = backend(&device, &uv_sphere(Vec3::ZERO, 1.0, 16, 32));
    let mut rng = Rng::new(5, 0);
    let rays = random_rays(&mut rng, Vec3::splat(-2.0), Vec3::splat(2.0), 2000);
    let (mut hits, mut occluded) = (HitBatch::default(), Vec::new());
    bvh.intersect(&rays, &mut hits);
    bvh.occluded(&rays, &mut occluded);
    assert!(hits.prim.iter().any(|&p| p != NO_HIT));
    assert!(occluded.iter().any(|&o| o));
    assert_eq!(bvh.failure(), None);
    let in_flight = bvh.submit(TraversalJob::Intersect {
        rays: rays.clone(),
        hits: HitBatch::default(),
    });
    device.device.destroy();
    let TraversalJob::Intersect { hits: lost, .. } = in_flight.wait() else {
        unreachable!("the job submitted")
    };
    assert!(
        lost.prim.iter().all(|&p| p == NO_HIT),
        "the batch in flight missed"
    );
    assert_eq!(lost.len(), rays.len());
    let failure = bvh.failure().expect("the failure is kept");
    assert!(failure.contains("lost"), "{failure}");
    bvh.intersect(&rays, &mut hits);
    bvh.occluded(&rays, &mut occluded);
    assert!(hits.prim.iter().all(|&p| p == NO_HIT) && hits.len() == rays.len());
    assert!(occluded.iter().all(|&o| !o) && occluded.len() == rays.len());
}
