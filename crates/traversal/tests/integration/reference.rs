//! Random rays against random meshes agree with a brute-force f64 reference.

use glam::Vec3;
use vcm_traversal::contract::uv_sphere;
use vcm_traversal::{
    BuildPreset, CpuBvh, CpuBvhOptions, CpuKernel, HitBatch, Interleave, RayBatch, Traversal,
};

use crate::common::{self, Rng, RngExt, assert_matches_reference, height_field, triangle_soup};

/// Random rays: origins in the meshes' bounding box, random directions and lengths, a
/// quarter with a bounded `[tmin, tmax)`.
fn random_rays(rng: &mut Rng, count: usize) -> RayBatch {
    let mut rays = RayBatch::with_capacity(count);
    for _ in 0..count {
        let origin = rng.point_in_box(0.0, 1.0);
        let direction = rng.unit_vector() * rng.range(0.5, 2.0);
        if rng.below(4) == 0 {
            let tmin = rng.range(0.0, 0.5);
            rays.push(origin, direction, tmin, tmin + rng.range(0.0, 1.0));
        } else {
            rays.push(origin, direction, 0.0, f32::INFINITY);
        }
    }
    rays
}

/// A soup, a closed sphere and a height field with shared edges, in one mesh.
fn random_mesh(rng: &mut Rng) -> Vec<[Vec3; 3]> {
    let mut tris = triangle_soup(rng, 1500, 1.0);
    tris.extend(uv_sphere(Vec3::splat(0.5), 0.3, 24, 48));
    tris.extend(height_field(rng, 24));
    tris
}

fn check_preset(preset: BuildPreset, kernel: CpuKernel, interleave: Interleave, seed: u64) {
    let mut rng = Rng::new(seed, 0);
    let tris = random_mesh(&mut rng);
    let rays = random_rays(&mut rng, 3000);
    let options = CpuBvhOptions {
        preset,
        chunk_size: 64,
        kernel,
        interleave,
    };
    let bvh = CpuBvh::new(&tris, options).unwrap();
    let mut hits = HitBatch::default();
    bvh.intersect(&rays, &mut hits);
    let ties = assert_matches_reference(&tris, &rays, &hits);
    let hit_count = hits
        .prim
        .iter()
        .filter(|&&p| p != vcm_traversal::NO_HIT)
        .count();
    println!(
        "{preset:?}: {hit_count} hits of {}, {ties} ties",
        rays.len()
    );
    assert!(
        hit_count > rays.len() / 3,
        "too few hits to be a useful test"
    );
    assert!(ties * 100 < rays.len(), "{ties} ties is suspiciously many");

    // Occlusion must agree with closest hit on the same rays.
    let mut occluded = Vec::new();
    bvh.occluded(&rays, &mut occluded);
    vcm_traversal::contract::assert_occlusion_matches_hits(&hits, &occluded);
}

/// One test per build preset, kernel and interleaving, each on its own seed.
macro_rules! preset_tests {
    ($($name:ident: $preset:ident, $kernel:ident, $interleave:ident, $seed:literal;)*) => {$(
        #[test]
        fn $name() {
            check_preset(
                BuildPreset::$preset,
                CpuKernel::$kernel,
                Interleave::$interleave,
                $seed,
            );
        }
    )*};
}

preset_tests! {
    fastest_preset_matches_reference: Fastest, Auto, Auto, 1;
    medium_preset_matches_reference: Medium, Auto, Auto, 2;
    spatial_split_preset_matches_reference: Slow, Auto, Auto, 3;
    portable_kernel_matches_reference: Medium, Portable, Auto, 5;
    rays_in_turn_match_reference: Medium, Auto, On, 6;
    portable_rays_in_turn_match_reference: Slow, Portable, On, 7;
    full_reinsertion_preset_matches_reference: VerySlow, Auto, Auto, 8;
}

#[test]
fn barycentrics_reconstruct_hit_point() {
    let mut rng = Rng::new(4, 0);
    let tris = random_mesh(&mut rng);
    let rays = random_rays(&mut rng, 2000);
    let bvh = CpuBvh::new(&tris, CpuBvhOptions::default()).unwrap();
    let mut hits = HitBatch::default();
    bvh.intersect(&rays, &mut hits);
    for i in (0..rays.len()).filter(|&i| hits.is_hit(i)) {
        let tri = &tris[hits.prim[i] as usize];
        let on_triangle = common::point_at(tri, hits.u[i], hits.v[i]);
        let on_ray = (rays.origin(i) + rays.direction(i) * hits.t[i]).as_dvec3();
        let scale = tri.iter().map(|p| p.length()).fold(1.0, f32::max) as f64;
        assert!(
            on_triangle.distance(on_ray) < 1e-5 * scale,
            "ray {i}: barycentric point {on_triangle} vs ray point {on_ray}"
        );
        assert!(hits.u[i] >= 0.0 && hits.v[i] >= 0.0 && hits.u[i] + hits.v[i] <= 1.0 + 1e-6);
    }
}

#[test]
fn measured_interleaving_reports_the_hits_of_one_ray_at_a_time() {
    // Large enough that `Interleave::Auto` measures both ways, chunk by chunk.
    let mut rng = Rng::new(9, 0);
    let mut tris = random_mesh(&mut rng);
    tris.extend(height_field(&mut rng, 100));
    let options = |interleave| CpuBvhOptions {
        chunk_size: 16,
        interleave,
        ..CpuBvhOptions::default()
    };
    let measured = CpuBvh::new(&tris, options(Interleave::Auto)).unwrap();
    let single = CpuBvh::new(&tris, options(Interleave::Off)).unwrap();
    assert!(measured.memory_bytes() > vcm_traversal::INTERLEAVE_ABOVE_BYTES);
    let (mut expected, mut hits) = (HitBatch::default(), HitBatch::default());
    let (mut expected_occluded, mut occluded) = (Vec::new(), Vec::new());
    // 30 batches of 64 chunks: one chunk in 16 runs the way not preferred, so every batch
    // runs both ways, and the estimate is updated several times.
    for _ in 0..30 {
        let rays = random_rays(&mut rng, 1024);
        single.intersect(&rays, &mut expected);
        measured.intersect(&rays, &mut hits);
        assert_eq!(hits.prim, expected.prim);
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&hits.t), bits(&expected.t));
        assert_eq!(bits(&hits.u), bits(&expected.u));
        single.occluded(&rays, &mut expected_occluded);
        measured.occluded(&rays, &mut occluded);
        assert_eq!(occluded, expected_occluded);
    }
}
