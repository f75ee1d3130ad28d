//! Alpha-tested triangles are transparent where the test says so, for both query kinds.

use std::sync::Arc;

use glam::{Vec3, vec3};
use vcm_traversal::{
    AlphaTest, CpuBvh, CpuBvhOptions, HitBatch, Interleave, NO_HIT, RayBatch, Traversal,
};

use crate::common::{Rng, RngExt};

/// Triangles with even ids are masked and opaque only where `u < 0.5`.
struct HalfCutout;

impl AlphaTest for HalfCutout {
    fn is_masked(&self, prim: u32) -> bool {
        prim.is_multiple_of(2)
    }

    fn is_opaque_at(&self, prim: u32, u: f32, _v: f32) -> bool {
        assert!(self.is_masked(prim), "asked about unmasked prim {prim}");
        u < 0.5
    }
}

/// Large triangles parallel to the xy plane at z = 1, 2, 3, 4 (ids 0..4), covering the
/// rectangle [-2, 2] × [-2, -1] with `u` growing along +x.
fn layers() -> Vec<[Vec3; 3]> {
    (1..=4)
        .map(|z| {
            let z = z as f32;
            [vec3(-3.0, -3.0, z), vec3(5.0, -3.0, z), vec3(-3.0, 5.0, z)]
        })
        .collect()
}

/// `u` of the point (x, y) on any layer.
fn u_at(x: f32) -> f32 {
    (x + 3.0) / 8.0
}

#[test]
fn masked_triangles_let_rays_through_where_transparent() {
    for interleave in [Interleave::Off, Interleave::On] {
        let options = CpuBvhOptions {
            interleave,
            ..CpuBvhOptions::default()
        };
        let bvh = CpuBvh::with_alpha_test(&layers(), options, Arc::new(HalfCutout)).unwrap();
        check_half_cutout(&bvh);
    }
}

/// Layer 0 (masked) stops rays where u < 0.5, layer 1 (unmasked) the others.
fn check_half_cutout(bvh: &CpuBvh) {
    let mut rng = Rng::new(20, 0);
    let mut rays = RayBatch::default();
    for _ in 0..1000 {
        let origin = vec3(rng.range(-2.0, 2.0), rng.range(-2.0, -1.0), 0.0);
        rays.push(origin, Vec3::Z, 0.0, f32::INFINITY);
    }
    let mut hits = HitBatch::default();
    bvh.intersect(&rays, &mut hits);
    let mut occluded = Vec::new();
    bvh.occluded(&rays, &mut occluded);
    let mut transparent = 0;
    for (i, &occluded) in occluded.iter().enumerate() {
        // Layer 0 (masked) stops the ray where u < 0.5, else layer 1 (unmasked) does.
        let expected = if u_at(rays.origin_x[i]) < 0.5 { 0 } else { 1 };
        transparent += expected;
        assert_eq!(
            hits.prim[i], expected,
            "ray {i} at x = {}",
            rays.origin_x[i]
        );
        assert!(occluded);
    }
    assert!(
        (200..800).contains(&transparent),
        "{transparent} rays passed the cutout"
    );
}

#[test]
fn occlusion_ignores_transparent_hits() {
    // Layers 0 and 2 are cut out; id 1 is an unmasked copy of layer 0.
    let tris = layers();
    let with_backstop = vec![tris[0], tris[0], tris[2]];
    let bvh = CpuBvh::with_alpha_test(
        &with_backstop,
        CpuBvhOptions::default(),
        Arc::new(HalfCutout),
    )
    .unwrap();
    let mut rays = RayBatch::default();
    rays.push(vec3(-0.5, 0.0, 0.0), Vec3::Z, 0.0, f32::INFINITY); // u < 0.5: opaque
    rays.push(vec3(1.5, 0.0, 0.0), Vec3::Z, 0.0, f32::INFINITY); // u > 0.5: transparent
    rays.push(vec3(1.5, 0.0, 5.0), -Vec3::Z, 0.0, f32::INFINITY);
    let mut hits = HitBatch::default();
    bvh.intersect(&rays, &mut hits);
    let mut occluded = Vec::new();
    bvh.occluded(&rays, &mut occluded);
    assert!(hits.prim[0] == 0 || hits.prim[0] == 1, "tied opaque copies");
    assert_eq!(hits.t[0], 1.0);
    // The unmasked copy blocks where layers 0 and 2 are cut out.
    assert_eq!((hits.prim[1], hits.t[1]), (1, 1.0));
    assert_eq!((hits.prim[2], hits.t[2]), (1, 4.0));
    assert_eq!(occluded, [true, true, true]);

    // Id 1 (unmasked) is now a small triangle out of the way.
    let out_of_the_way = [
        Vec3::splat(100.0),
        vec3(101.0, 100.0, 100.0),
        Vec3::splat(101.0),
    ];
    let cutouts_only = vec![tris[0], out_of_the_way, tris[2]];
    let bvh = CpuBvh::with_alpha_test(
        &cutouts_only,
        CpuBvhOptions::default(),
        Arc::new(HalfCutout),
    )
    .unwrap();
    bvh.intersect(&rays, &mut hits);
    bvh.occluded(&rays, &mut occluded);
    assert_eq!(hits.prim, [0, NO_HIT, NO_HIT]);
    assert_eq!(occluded, [true, false, false]);
}
