//! The first merge radius r₀: a fraction of the scene's radius, or pixel footprints that
//! camera rays measure at the surfaces they hit.

use glam::Vec3;
use vcm::{Algorithm, DEFAULT_RADIUS_FRACTION, Integrator, MergeRadius, VcmSettings};
use vcm_scene::{Camera, Scene};

use crate::common;

/// A diffuse square of half-size 50 at z = 0 under a point light, seen by `camera`.
fn wall(camera: Camera) -> Scene {
    common::lit_floor(50.0, camera)
}

/// The wall seen square-on from `distance` with vertical field of view `yfov`.
fn facing_wall(distance: f32, yfov: f32) -> Scene {
    wall(common::camera(Vec3::new(0.0, 0.0, distance), yfov))
}

/// Photon mapping over `scene` at `size`² with `radius`: its r₀ and its decisions.
fn first_radius(scene: &Scene, radius: MergeRadius, size: u32) -> (f32, Vec<String>) {
    let settings = VcmSettings {
        radius,
        ..common::vcm_settings(Algorithm::Ppm, size, size)
    };
    let vcm = common::vcm(scene.clone(), settings);
    let decisions = vcm.decisions().iter().map(|d| d.reason.clone()).collect();
    (vcm.radius(0), decisions)
}

#[test]
fn a_scene_fraction_scales_the_bounding_sphere() {
    let scene = facing_wall(4.0, 0.5);
    let (r0, _) = first_radius(&scene, MergeRadius::SceneFraction(0.01), 32);
    assert_eq!(r0, 0.01 * scene.features.bounds.radius());
}

#[test]
fn pixel_footprints_on_a_facing_wall_follow_distance_and_pixel_size() {
    // A pixel of area A on the image plane at unit distance, θ off the axis, covers a disk
    // of radius D / cos θ · √(A cos³θ / π) = D √(A cos θ / π) of the wall at distance D.
    let (distance, yfov, size, pixels) = (4.0f32, 0.1f32, 64, 3.0);
    let half = (yfov / 2.0).tan();
    let pixel_area = (2.0 * half / size as f32).powi(2);
    let cos_corner = 1.0 / (1.0 + 2.0 * half * half).sqrt();
    let centre = pixels * distance * (pixel_area / std::f32::consts::PI).sqrt();
    let (r0, decisions) = first_radius(
        &facing_wall(distance, yfov),
        MergeRadius::Pixels(pixels),
        size,
    );
    let slack = 1e-5 * centre;
    assert!(
        r0 >= centre * cos_corner.sqrt() - slack && r0 <= centre + slack,
        "r₀ {r0} outside [{}, {centre}]",
        centre * cos_corner.sqrt()
    );
    assert!(
        decisions.iter().any(|d| d.contains("pixel's footprint")),
        "{decisions:?}"
    );
}

#[test]
fn a_footprint_radius_halves_with_twice_the_pixels_and_doubles_with_twice_the_distance() {
    let pixels = MergeRadius::Pixels(2.0);
    let (near, _) = first_radius(&facing_wall(4.0, 0.5), pixels, 64);
    let (sharper, _) = first_radius(&facing_wall(4.0, 0.5), pixels, 128);
    let (farther, _) = first_radius(&facing_wall(8.0, 0.5), pixels, 64);
    assert!((sharper / near - 0.5).abs() < 2e-3, "{sharper} vs {near}");
    assert!((farther / near - 2.0).abs() < 1e-4, "{farther} vs {near}");
}

#[test]
fn a_camera_that_sees_nothing_falls_back_to_the_scene_fraction() {
    let away = Camera {
        forward: Vec3::Z,
        up: Vec3::Y,
        right: -Vec3::X,
        ..common::camera(Vec3::new(0.0, 0.0, 4.0), 0.5)
    };
    let scene = wall(away);
    let (r0, decisions) = first_radius(&scene, MergeRadius::Pixels(2.0), 32);
    assert_eq!(r0, DEFAULT_RADIUS_FRACTION * scene.features.bounds.radius());
    assert!(
        decisions.iter().any(|d| d.contains("no camera ray hits")),
        "{decisions:?}"
    );
}

#[test]
fn radii_that_are_not_positive_are_refused() {
    let scene = facing_wall(4.0, 0.5);
    for radius in [
        MergeRadius::Pixels(0.0),
        MergeRadius::SceneFraction(f32::NAN),
    ] {
        let settings = VcmSettings {
            radius,
            ..common::vcm_settings(Algorithm::Vcm, 16, 16)
        };
        let traversal = common::cpu_traversal(&scene);
        let error = vcm::Vcm::new(std::sync::Arc::new(scene.clone()), traversal, settings)
            .err()
            .expect("refused");
        assert!(error.to_string().contains("merge radius"), "{error}");
    }
}
