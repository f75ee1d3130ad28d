//! Leaving out what a scene does not need changes the cost, never the expectation: renders
//! with pruning equal renders without it, bit for bit where the parts left out contribute
//! nothing (shading work, light paths on a scene without diffuse or glossy surfaces), and
//! within the standard errors where the estimator changes (VCM without merging on a scene
//! without specular surfaces, which is then BPT, bit for bit).

use glam::Vec3;
use vcm::{Algorithm, Film, FrameStats, Integrator, MergeRadius, PtSettings, Vcm, VcmSettings};
use vcm_scene::light::{Light, PointLight};
use vcm_scene::{Material, Scene, ShadingPlan};

use crate::common;

const SIZE: u32 = 32;
/// A merge radius at which merging carries a large share of VCM's weights on a 32² image
/// (η = π r² N ≈ 4), but blurs less than the noise of the statistical test (as in
/// `algorithms_agree`): a pruned VCM that lost merging's share would be seen.
const RADIUS_FRACTION: f32 = 0.02;

/// The integrator of `algorithm` (`None`: the path tracer) over `scene`.
fn integrator(scene: Scene, algorithm: Option<Algorithm>, prune: bool) -> Box<dyn Integrator> {
    match algorithm {
        None => {
            let settings = PtSettings {
                seed: 5,
                ..common::pt_settings(SIZE, SIZE)
            };
            Box::new(common::path_tracer(scene, settings))
        }
        Some(algorithm) => Box::new(vcm_family(scene, algorithm, prune)),
    }
}

fn vcm_family(scene: Scene, algorithm: Algorithm, prune: bool) -> Vcm {
    let settings = VcmSettings {
        seed: 5,
        prune,
        radius: MergeRadius::SceneFraction(RADIUS_FRACTION),
        ..common::vcm_settings(algorithm, SIZE, SIZE)
    };
    common::vcm(scene, settings)
}

/// The film of `frames` frames and their summed statistics.
fn render(integrator: &mut dyn Integrator, frames: u32) -> (Vec<Vec3>, FrameStats) {
    let mut film = Film::new(SIZE, SIZE);
    let mut stats = FrameStats::default();
    for iteration in 0..frames {
        stats.accumulate(&integrator.render_frame(&mut film, iteration));
    }
    (film.mean(), stats)
}

/// A floor under a point light: no emissive triangle, no texture, no normal map.
fn floor_under_a_point_light() -> Scene {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    common::push_floor(&mut positions, &mut triangles, 1.0);
    let light = Light::Point(PointLight {
        position: Vec3::new(0.3, 0.2, 1.0),
        intensity: Vec3::splat(2.0),
    });
    common::scene(
        common::mesh(positions, triangles, vec![0, 0]),
        vec![Material::diffuse("floor", Vec3::splat(0.5))],
        vec![light],
        common::camera(Vec3::new(0.0, 0.0, 2.0), 1.0),
    )
}

#[test]
fn shading_without_the_parts_a_scene_lacks_gives_the_same_image_bit_for_bit() {
    let scenes = [
        ("cornell-box", common::scene_file("cornell-box.gltf")),
        ("point light", floor_under_a_point_light()),
    ];
    for (name, scene) in scenes {
        assert_ne!(
            scene.shading,
            ShadingPlan::FULL,
            "{name}: nothing is left out"
        );
        let full = Scene {
            shading: ShadingPlan::FULL,
            ..scene.clone()
        };
        for algorithm in [None, Some(Algorithm::Vcm)] {
            let (pruned, _) = render(integrator(scene.clone(), algorithm, true).as_mut(), 2);
            let (unpruned, _) = render(integrator(full.clone(), algorithm, true).as_mut(), 2);
            assert!(
                pruned.iter().any(|p| p.max_element() > 0.0),
                "{name}: black"
            );
            assert!(pruned == unpruned, "{name}, {algorithm:?}: images differ");
        }
    }
}

/// A closed mirror sphere with a mirror-like emitting cap in view, seen from inside: no
/// surface that a light vertex could be stored on.
fn mirror_sphere() -> Scene {
    let (positions, triangles) = common::inward_icosphere(2);
    let in_cap = |t: &[u32; 3]| t.iter().all(|&i| positions[i as usize].z < -0.8);
    let material_ids = triangles.iter().map(|t| u32::from(in_cap(t))).collect();
    let mirror = Material {
        metallic: 1.0,
        roughness: 0.0,
        base_color: glam::Vec4::new(0.9, 0.8, 0.7, 1.0),
        ..Material::default()
    };
    let emitter = Material {
        emission: Vec3::splat(3.0),
        ..mirror.clone()
    };
    common::scene(
        common::mesh(positions, triangles, material_ids),
        vec![mirror, emitter],
        Vec::new(),
        common::camera(Vec3::new(0.1, 0.2, 0.3), 1.2),
    )
}

#[test]
fn a_scene_without_diffuse_or_glossy_surfaces_traces_no_light_paths() {
    let algorithms = [
        Algorithm::LightTracing,
        Algorithm::Bpt,
        Algorithm::Ppm,
        Algorithm::Bpm,
        Algorithm::Vcm,
    ];
    for algorithm in algorithms {
        let mut pruned = vcm_family(mirror_sphere(), algorithm, true);
        let (image, stats) = render(&mut pruned, 2);
        let mut full = vcm_family(mirror_sphere(), algorithm, false);
        let (full_image, full_stats) = render(&mut full, 2);
        assert!(
            image.iter().any(|p| p.max_element() > 0.0),
            "{algorithm:?}: black"
        );
        assert!(image == full_image, "{algorithm:?}: images differ");
        assert_eq!(stats.light_rays, 0, "{algorithm:?}");
        assert!(
            full_stats.light_rays > 0,
            "{algorithm:?}: the full render traced none"
        );
        assert_eq!(cache_capacity(&pruned), 0, "{algorithm:?}");
        assert_eq!(grid_bytes(&pruned), 0, "{algorithm:?}");
    }
}

/// Vertices the integrator's light vertex caches can hold, over all samples of a frame.
fn cache_capacity(vcm: &Vcm) -> usize {
    vcm.caches().iter().map(|cache| cache.capacity()).sum()
}

/// Bytes of the integrator's hash grids, over all samples of a frame.
fn grid_bytes(vcm: &Vcm) -> usize {
    vcm.grids().iter().map(|grid| grid.memory_bytes()).sum()
}

#[test]
fn integrators_that_never_connect_or_merge_allocate_no_cache_and_build_no_grid() {
    let mut lt = vcm_family(
        common::scene_file("cornell-box.gltf"),
        Algorithm::LightTracing,
        true,
    );
    render(&mut lt, 1);
    assert_eq!((cache_capacity(&lt), grid_bytes(&lt)), (0, 0));
    let mut bpt = vcm_family(common::scene_file("cornell-box.gltf"), Algorithm::Bpt, true);
    render(&mut bpt, 1);
    assert!(cache_capacity(&bpt) > 0);
    assert_eq!(grid_bytes(&bpt), 0);
    let mut bpm = vcm_family(common::scene_file("cornell-box.gltf"), Algorithm::Bpm, true);
    render(&mut bpm, 1);
    assert!(cache_capacity(&bpm) > 0 && grid_bytes(&bpm) > 0);
}

#[test]
fn vcm_without_specular_surfaces_runs_as_bpt_without_a_grid() {
    let scene = common::scene_file("cornell-box.gltf");
    let mut vcm = vcm_family(scene.clone(), Algorithm::Vcm, true);
    let (vcm_image, vcm_stats) = render(&mut vcm, 3);
    let (bpt_image, _) = render(&mut vcm_family(scene, Algorithm::Bpt, true), 3);
    assert!(vcm_image == bpt_image, "pruned VCM differs from BPT");
    assert_eq!(grid_bytes(&vcm), 0);
    assert_eq!(vcm_stats.grid_build_time, std::time::Duration::ZERO);
    let decisions = vcm.decisions();
    let merging = decisions.iter().find(|d| d.part == "merging and hash grid");
    assert!(!merging.unwrap().runs);
}

/// Regions per image side of the statistical comparison.
const REGIONS: usize = 4;
/// 2 scenes × (16 regions + the image) = 34 comparisons: |z| < 4.5 keeps the family-wise
/// false alarm rate near 2e-4 (Šidák).
const Z_LIMIT: f64 = 4.5;

#[test]
fn vcm_without_merging_has_the_expectation_of_full_vcm() {
    const FRAMES: u32 = 600;
    for name in ["cornell-box.gltf", "cornell-indirect.gltf"] {
        let scene = common::scene_file(name);
        let [pruned, full] = [true, false].map(|prune| {
            let mut vcm = vcm_family(scene.clone(), Algorithm::Vcm, prune);
            common::region_means(&mut vcm, FRAMES, REGIONS)
        });
        for (r, z) in pruned.z_scores(&full).iter().enumerate() {
            assert!(z.abs() < Z_LIMIT, "{name}, region {r}: z = {z:.2}");
        }
    }
}
