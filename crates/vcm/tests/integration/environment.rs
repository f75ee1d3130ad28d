//! The environment light. Constant radiance L from every direction: every algorithm finds
//! L where the camera sees the sky, and ρ L on a Lambertian floor of albedo ρ that sees the
//! whole upper hemisphere (irradiance π L), which paths reach by light samples, by BSDF
//! samples that escape, and by light paths entering the scene from the sky. Constant or
//! painted (an equirectangular map with a sun), the algorithms agree where it is occluded.

use std::sync::Arc;

use glam::Vec3;
use vcm::{Algorithm, Integrator, MergeRadius, PtSettings, VcmSettings};
use vcm_scene::light::EnvironmentMap;
use vcm_scene::{Camera, Material, Scene};

use crate::common;

const SKY: Vec3 = Vec3::new(1.0, 0.5, 0.25);
const ALBEDO: f32 = 0.5;
const SIZE: u32 = 16;
const FRAMES: u32 = 100;

/// A floor of half side 1 in z = 0 facing +Z under the sky, seen by `camera`.
fn floor_under_the_sky(camera: Camera) -> Scene {
    floor_with_normals_under_the_sky(camera, Vec3::ZERO)
}

/// The floor of [`floor_under_the_sky`] with `normal` as every vertex's normal (zero: none).
fn floor_with_normals_under_the_sky(camera: Camera, normal: Vec3) -> Scene {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    common::push_floor(&mut positions, &mut triangles, 1.0);
    let mut mesh = common::mesh(positions, triangles, vec![0, 0]);
    mesh.normals.fill(normal);
    let sky = common::sky(SKY, None, &mesh);
    let floor = Material::diffuse("floor", Vec3::splat(ALBEDO));
    common::scene(mesh, vec![floor], vec![sky], camera)
}

/// Renders `scene` with `algorithm` and asserts that every pixel converges to `expected`.
fn assert_every_algorithm_sees(scene: &Scene, expected: f64, view: &str) {
    for algorithm in common::EVERY_ALGORITHM {
        // A radius at which the 256 light paths of a frame meet camera vertices often enough
        // for 100 frames to measure the spread; the floor is flat and evenly lit, so merging
        // within it adds no bias (the disks stay inside the floor).
        let mut integrator = common::integrator(scene, algorithm, SIZE, 3, 0.1);
        let series = common::render_series(integrator.as_mut(), FRAMES);
        let pixels = vec![expected; (SIZE * SIZE) as usize];
        common::assert_pixels_match(&series, &pixels, &format!("{view}, {algorithm:?}"));
    }
}

fn channel_mean(v: Vec3) -> f64 {
    f64::from(v.element_sum()) / 3.0
}

#[test]
fn a_floor_under_the_sky_reflects_albedo_times_sky() {
    // From 2 above the floor, a field of view of 0.8 rad sees only floor (|x|, |y| < 0.85).
    let scene = floor_under_the_sky(common::camera(Vec3::new(0.0, 0.0, 2.0), 0.8));
    assert_every_algorithm_sees(&scene, f64::from(ALBEDO) * channel_mean(SKY), "floor");
}

/// Shading normals tilted by θ from the geometric one (as a normal map or vertex normals
/// give): a Lambertian floor lit by the constant sky over its geometric hemisphere reflects
/// ρ L (1 + cos θ) / 2, the cosine taken about the shading normal and light from below the
/// floor's plane refused. Light paths reach the camera through the adjoint BSDF, with
/// Veach's correction for shading normals, and merges weigh each light vertex by
/// f·|ωi·n_s| / |ωi·n_g|, as the vertices' density is over the floor's area: all converge to
/// the same value. (Merges that weighed by f alone made BPM 8.4% too bright here, z = 11.8;
/// PPM, which sums merges without weights, hid it: under a uniform sky both weightings
/// integrate to the same.) Image means only: a pixel's light-tracing estimate is heavy-tailed
/// where Veach's factor |ωi·n_s| / |ωi·n_g| is large (light grazing the floor), so 100
/// frames underestimate its spread.
#[test]
fn a_floor_with_tilted_shading_normals_reflects_the_clipped_cosine() {
    let tilt = 40f32.to_radians();
    // Every view direction is within 0.4 rad of the geometric normal, so in front of the
    // tilted one too (40° + 23° < 90°).
    let camera = common::camera(Vec3::new(0.0, 0.0, 2.0), 0.8);
    let normal = Vec3::new(tilt.sin(), 0.0, tilt.cos());
    let scene = floor_with_normals_under_the_sky(camera, normal);
    let expected = f64::from(ALBEDO) * channel_mean(SKY) * (1.0 + f64::from(tilt.cos())) / 2.0;
    let every_part_of_vcm = VcmSettings {
        seed: 3,
        radius: MergeRadius::SceneFraction(0.1),
        // Nothing here is specular: pruned, VCM would run as BPT and never merge.
        prune: false,
        ..common::vcm_settings(Algorithm::Vcm, SIZE, SIZE)
    };
    let mut integrators: Vec<(String, Box<dyn Integrator>)> = common::EVERY_ALGORITHM
        .into_iter()
        .map(|a| {
            (
                format!("{a:?}"),
                common::integrator(&scene, a, SIZE, 3, 0.1),
            )
        })
        .collect();
    let unpruned = Box::new(common::vcm(scene.clone(), every_part_of_vcm));
    integrators.push(("VCM with merging".into(), unpruned));
    for (label, mut integrator) in integrators {
        let series = common::render_series(integrator.as_mut(), FRAMES);
        let (mean, se) = (series.image_mean, series.image_std_err);
        assert!(
            (mean - expected).abs() <= 4.0 * se,
            "{label}: image mean {mean} vs {expected} ± 4·{se}"
        );
    }
}

#[test]
fn the_sky_seen_directly_has_its_radiance() {
    let looking_up = Camera {
        forward: Vec3::Z,
        right: -Vec3::X,
        ..common::camera(Vec3::new(0.0, 0.0, 0.5), 0.8)
    };
    let scene = floor_under_the_sky(looking_up);
    assert_every_algorithm_sees(&scene, channel_mean(SKY), "sky");
}

/// A 32 × 16 sky: a gradient with a small sun 50 times brighter.
fn painted_sky() -> Arc<EnvironmentMap> {
    let (w, h) = (32, 16);
    let texels = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            if (5..7).contains(&x) && (4..6).contains(&y) {
                Vec3::new(50.0, 45.0, 40.0)
            } else {
                Vec3::new(0.2 + 0.8 * x as f32 / w as f32, 0.5, 0.3 + 0.02 * y as f32)
            }
        })
        .collect();
    Arc::new(EnvironmentMap::new(w, h, texels).unwrap())
}

/// Under a roof over half the floor, light reaches the shade only by bouncing off the
/// roof's underside and the lit floor: light tracing, BPT and VCM agree with the path
/// tracer region by region, under the constant sky and under a painted one with a sun
/// (z-scores of 4 × 4 blocks and the image; |z| < 4.6 keeps the family-wise false alarm
/// rate near 1e-3 over 2 × 3 × 17 comparisons).
#[test]
fn algorithms_agree_where_the_sky_is_partly_occluded() {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    common::push_floor(&mut positions, &mut triangles, 1.0);
    // The roof over x < 0, facing down (counter-clockwise seen from below).
    let roof =
        [(-1.0, -1.0), (-1.0, 1.0), (0.0, 1.0), (0.0, -1.0)].map(|(x, y)| Vec3::new(x, y, 0.4));
    common::push_quad(&mut positions, &mut triangles, roof);
    let mesh = common::mesh(positions, triangles, vec![0; 4]);
    let camera = Camera {
        forward: Vec3::new(0.0, 0.6, -0.8),
        up: Vec3::new(0.0, 0.8, 0.6),
        ..common::camera(Vec3::new(0.0, -1.6, 1.6), 0.9)
    };
    let material = Material::diffuse("grey", Vec3::splat(ALBEDO));
    for (name, map) in [("constant", None), ("painted", Some(painted_sky()))] {
        let sky = common::sky(SKY, map, &mesh);
        let scene = common::scene(mesh.clone(), vec![material.clone()], vec![sky], camera);
        let frames = 400;
        let mut tracer = common::path_tracer(
            scene.clone(),
            PtSettings {
                seed: 11,
                ..common::pt_settings(SIZE, SIZE)
            },
        );
        let reference = common::region_means(&mut tracer, frames, 4);
        for algorithm in [Algorithm::LightTracing, Algorithm::Bpt, Algorithm::Vcm] {
            let settings = VcmSettings {
                seed: 12,
                ..common::vcm_settings(algorithm, SIZE, SIZE)
            };
            let mut integrator = common::vcm(scene.clone(), settings);
            let z = common::region_means(&mut integrator, frames, 4).z_scores(&reference);
            for (r, z) in z.iter().enumerate() {
                assert!(
                    z.abs() < 4.6,
                    "{name} sky, {algorithm:?}, region {r}: z = {z:.2}"
                );
            }
        }
    }
}
