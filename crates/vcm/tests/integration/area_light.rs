//! A Lambertian plane under a one-sided emitting rectangle: the radiance leaving the plane is
//! ρ/π · E with the irradiance E of a uniformly emitting polygon from Lambert's formula
//! E = L/2 · Σᵢ Θᵢ (n · γ̂ᵢ), where Θᵢ is the angle the edge (vᵢ, vᵢ₊₁) subtends at the
//! receiver and γ̂ᵢ the unit normal of the plane through the receiver and that edge (Arvo 1994,
//! "The irradiance Jacobian for partially occluded polyhedral sources", eq. 3). Light sampling
//! and BSDF sampling both find the light, so the test checks their MIS weights sum to one.

use glam::{DVec3, Vec3};
use vcm::{Algorithm, PtSettings, VcmSettings};
use vcm_scene::Material;

use crate::common;

const ALBEDO: f32 = 0.6;
/// Emitted radiance of the light (W·sr⁻¹·m⁻²).
const EMITTED: Vec3 = Vec3::new(3.0, 2.0, 1.0);
const SIZE: u32 = 8;

/// Irradiance at `p` on the plane z = 0 (normal +Z) from the polygon `corners` of radiance
/// `radiance`, the whole polygon above the receiver's horizon.
fn polygon_irradiance(corners: &[DVec3], radiance: f64, p: DVec3) -> f64 {
    let dirs: Vec<DVec3> = corners.iter().map(|c| (*c - p).normalize()).collect();
    let sum: f64 = (0..dirs.len())
        .map(|i| {
            let (a, b) = (dirs[i], dirs[(i + 1) % dirs.len()]);
            a.angle_between(b) * a.cross(b).normalize().z
        })
        .sum();
    0.5 * radiance * sum.abs()
}

#[test]
fn lambertian_plane_under_an_area_light_matches_lamberts_formula() {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    common::push_floor(&mut positions, &mut triangles, 20.0);
    // Beside the camera's view, facing down (counter-clockwise seen from below).
    let light =
        [(0.9, -1.0), (0.9, 1.0), (2.9, 1.0), (2.9, -1.0)].map(|(x, y)| Vec3::new(x, y, 0.5));
    common::push_quad(&mut positions, &mut triangles, light);
    let lamp = Material {
        emission: EMITTED,
        ..Material::diffuse("lamp", Vec3::ZERO)
    };
    let camera = common::camera(Vec3::new(0.0, 0.0, 3.0), 0.6);
    let scene = common::scene(
        common::mesh(positions, triangles, vec![0, 0, 1, 1]),
        vec![Material::diffuse("floor", Vec3::splat(ALBEDO)), lamp],
        Vec::new(),
        camera,
    );
    let corners = light.map(Vec3::as_dvec3);
    let radiance = f64::from(EMITTED.element_sum()) / 3.0;
    let expected = common::plane_pixel_values(&camera, SIZE, |p| {
        f64::from(ALBEDO) / std::f64::consts::PI * polygon_irradiance(&corners, radiance, p)
    });
    let settings = PtSettings {
        seed: 21,
        ..common::pt_settings(SIZE, SIZE)
    };
    let series = common::render_series(&mut common::path_tracer(scene.clone(), settings), 128);
    common::assert_pixels_match(&series, &expected, "area light, path tracing");
    // Emission hits, light samples and light paths splatted through the camera all find this
    // light: BPT and VCM weight the three.
    for algorithm in [Algorithm::Bpt, Algorithm::Vcm] {
        let settings = VcmSettings {
            seed: 21,
            ..common::vcm_settings(algorithm, SIZE, SIZE)
        };
        let series = common::render_series(&mut common::vcm(scene.clone(), settings), 128);
        common::assert_pixels_match(&series, &expected, &format!("area light, {algorithm:?}"));
    }
}
