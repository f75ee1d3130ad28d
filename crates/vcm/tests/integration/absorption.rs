//! Absorption inside solids (`KHR_materials_volume` attenuation). A diffuse floor lies inside
//! a wide, flat, absorbing slab of index 1 (its surfaces bend nothing and reflect nothing).
//!
//! Under a constant sky, light crossing height h of the slab at cos θ to the vertical keeps
//! e^(−σh/cos θ), so the floor's irradiance is E = 2π L ∫₀¹ e^(−σh/μ) μ dμ, its radiance
//! ρE/π, and a pixel whose ray meets the floor at cos θ sees that radiance times
//! e^(−σh/cos θ) once more. Camera paths are absorbed on their way down and up, light paths
//! on their way in to the floor, where merges meet them.
//!
//! Under a roof inside the slab, lit by a point light above it, the shade is lit only by
//! light bounced within the slab, which bidirectional connections and merges through it
//! carry: BPT and VCM agree with bidirectional photon mapping. (Light tracing cannot see
//! inside: the slab's surface is in the way of its camera connections.)

use glam::{DVec3, Vec3, Vec3Swizzles};
use vcm::{Algorithm, Integrator};
use vcm_scene::light::{Light, PointLight};
use vcm_scene::{Camera, Material, Scene};

use crate::common;

const SKY: Vec3 = Vec3::new(1.0, 0.5, 0.25);
const ALBEDO: f32 = 0.5;
/// Absorption coefficient σ of the slab under the sky, per unit length.
const SIGMA: f32 = 2.5;
/// Height of that slab's top above the floor.
const DEPTH: f32 = 0.2;
const SIZE: u32 = 16;
const FRAMES: u32 = 100;
/// A merge radius of 1 (the scene's radius is 7.07), at which the ~100 light vertices a frame
/// leaves on the floor meet camera vertices often enough: the floor is evenly lit within 3 of
/// its center, and the viewed part's disks (shrinking from 1) stay there.
const EVEN_RADIUS: f32 = 0.141_421_35;

/// The two triangles of the face of the box `±half` whose outward normal is `n` (an axis,
/// ±), counter-clockwise seen from outside.
fn push_face(positions: &mut Vec<Vec3>, triangles: &mut Vec<[u32; 3]>, half: Vec3, n: Vec3) {
    // u × v = n.
    let (u, v) = (n.zxy().abs(), n.yzx().abs());
    let (u, v) = if n.element_sum() > 0.0 {
        (u, v)
    } else {
        (v, u)
    };
    let (c, u, v) = (n * half, u * half, v * half);
    common::push_quad(
        positions,
        triangles,
        [c - u - v, c + u - v, c + u + v, c - u + v],
    );
}

/// Appends the slab (half side 5, from z = −0.1 up to `depth`) made of material 1 to the
/// floor of material 0 in `positions` / `triangles`, and returns the mesh.
fn with_slab(
    mut positions: Vec<Vec3>,
    mut triangles: Vec<[u32; 3]>,
    depth: f32,
) -> vcm_scene::Mesh {
    let floor_triangles = triangles.len();
    let first_slab_vertex = positions.len();
    let bottom = -0.1;
    let half = Vec3::new(5.0, 5.0, (depth - bottom) / 2.0);
    for n in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
        push_face(&mut positions, &mut triangles, half, n);
    }
    let center = Vec3::new(0.0, 0.0, (depth + bottom) / 2.0);
    positions[first_slab_vertex..]
        .iter_mut()
        .for_each(|p| *p += center);
    let material_ids = (0..triangles.len())
        .map(|t| u32::from(t >= floor_triangles))
        .collect();
    common::mesh(positions, triangles, material_ids)
}

/// The diffuse floor (material 0) and the slab's clear solid of index 1 absorbing `sigma`
/// per unit length (material 1).
fn materials(sigma: f32) -> Vec<Material> {
    let slab = Material {
        name: "slab".into(),
        metallic: 0.0,
        roughness: 0.0,
        transmission: 1.0,
        ior: 1.0,
        thin_walled: false,
        absorption: Vec3::splat(sigma),
        double_sided: true,
        ..Material::default()
    };
    vec![Material::diffuse("floor", Vec3::splat(ALBEDO)), slab]
}

/// The floor (half side 4, z = 0) inside a slab of height [`DEPTH`] absorbing `sigma` under
/// the sky, seen from 3 above the floor with a field of view of 0.5 rad: the camera sees only
/// floor with |x|, |y| < 0.8, where light leaving through the slab's sides (lateral runs of
/// 4 within height 0.2, at cos θ < 0.05) is weighed by e^(−10) or less.
fn floor_in_a_slab(sigma: f32) -> Scene {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    common::push_floor(&mut positions, &mut triangles, 4.0);
    let mesh = with_slab(positions, triangles, DEPTH);
    let sky = common::sky(SKY, None, &mesh);
    let camera = common::camera(Vec3::new(0.0, 0.0, 3.0), 0.5);
    common::scene(mesh, materials(sigma), vec![sky], camera)
}

/// ∫₀¹ e^(−τ/μ) μ dμ by Simpson's rule.
fn slab_irradiance_integral(tau: f64) -> f64 {
    let n = 10_000;
    let f = |mu: f64| {
        if mu > 0.0 {
            (-tau / mu).exp() * mu
        } else {
            0.0
        }
    };
    let h = 1.0 / f64::from(n);
    let inner: f64 = (1..n)
        .map(|i| f(f64::from(i) * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
        .sum();
    (f(0.0) + inner + f(1.0)) * h / 3.0
}

/// The path tracer (`None`) or `algorithm` rendering `scene` at `size`² (seed 5), merging
/// (where it merges) within `radius_fraction` of the scene's radius.
fn integrator(
    scene: &Scene,
    algorithm: Option<Algorithm>,
    size: u32,
    radius_fraction: f32,
) -> Box<dyn Integrator> {
    common::integrator(scene, algorithm, size, 5, radius_fraction)
}

#[test]
fn light_through_an_absorbing_slab_follows_beer_lambert() {
    let scene = floor_in_a_slab(SIGMA);
    assert!(scene.features.absorbing_volumes);
    let tau = f64::from(SIGMA * DEPTH);
    let sky = f64::from(SKY.element_sum()) / 3.0;
    let floor_radiance = f64::from(ALBEDO) * 2.0 * sky * slab_irradiance_integral(tau);
    let camera = scene.camera;
    let eye = camera.position.as_dvec3();
    let expected = common::plane_pixel_values(&camera, SIZE, |point: DVec3| {
        let cos = eye.z / (eye - point).length();
        floor_radiance * (-tau / cos).exp()
    });
    let algorithms = [
        None,
        Some(Algorithm::Bpt),
        Some(Algorithm::Ppm),
        Some(Algorithm::Bpm),
        Some(Algorithm::Vcm),
    ];
    for algorithm in algorithms {
        let mut integrator = integrator(&scene, algorithm, SIZE, EVEN_RADIUS);
        let series = common::render_series(integrator.as_mut(), FRAMES);
        common::assert_pixels_match(&series, &expected, &format!("{algorithm:?}"));
    }
}

/// Without absorption the same slab passes everything: the floor is albedo × sky.
#[test]
fn a_clear_slab_absorbs_nothing() {
    let scene = floor_in_a_slab(0.0);
    assert!(!scene.features.absorbing_volumes);
    let sky = f64::from(SKY.element_sum()) / 3.0;
    let expected = vec![f64::from(ALBEDO) * sky; (SIZE * SIZE) as usize];
    let series = common::render_series(integrator(&scene, None, SIZE, 0.0).as_mut(), FRAMES);
    common::assert_pixels_match(&series, &expected, "clear slab");
}

/// The floor inside a slab of height 1 absorbing 0.5 per unit length, under a diffuse roof
/// at height 0.5 that leaves a gap over x > 2.5, where a point light above the slab shines
/// in. The camera, outside the slab's side at floor level and looking up a little, sees only
/// the roof's underside in the shade, which light reaches by bouncing off the floor under
/// the gap: every path the camera sees runs through the slab and has two diffuse vertices in
/// it, so bidirectional connections and merges, through the absorbing solid, carry all the
/// light.
fn shade_under_a_roof() -> Scene {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    common::push_floor(&mut positions, &mut triangles, 4.0);
    // Counter-clockwise seen from below.
    let corners = [(-4.0, -4.0), (-4.0, 4.0), (2.5, 4.0), (2.5, -4.0)];
    let roof = corners.map(|(x, y)| Vec3::new(x, y, 0.5));
    common::push_quad(&mut positions, &mut triangles, roof);
    let mesh = with_slab(positions, triangles, 1.0);
    let light = Light::Point(PointLight {
        position: Vec3::new(3.25, 0.0, 2.0),
        intensity: Vec3::splat(20.0),
    });
    let elevation = 0.086_f32;
    let camera = Camera {
        forward: Vec3::new(-elevation.cos(), 0.0, elevation.sin()),
        right: Vec3::Y,
        up: Vec3::new(elevation.sin(), 0.0, elevation.cos()),
        ..common::camera(Vec3::new(6.0, 0.0, 0.1), 0.05)
    };
    common::scene(mesh, materials(0.5), vec![light], camera)
}

/// BPT and VCM agree with bidirectional photon mapping (merging only, within 0.1: the shade
/// is lit smoothly, so the blur stays within the noise) region by region in the shade (z-scores
/// of 4 × 4 blocks and the image; |z| < 4.6 keeps the family-wise false alarm rate near 1e-3
/// over 2 × 17 comparisons).
#[test]
fn connections_and_merges_through_an_absorbing_slab_agree() {
    let scene = shade_under_a_roof();
    let (size, frames, radius) = (64, 400, 0.1 / 50f32.sqrt());
    let mut bpm = integrator(&scene, Some(Algorithm::Bpm), size, radius);
    let reference = common::region_means(bpm.as_mut(), frames, 4);
    for algorithm in [Algorithm::Bpt, Algorithm::Vcm] {
        let mut integrator = integrator(&scene, Some(algorithm), size, radius);
        let z = common::region_means(integrator.as_mut(), frames, 4).z_scores(&reference);
        for (r, z) in z.iter().enumerate() {
            assert!(z.abs() < 4.6, "{algorithm:?}, region {r}: z = {z:.2}");
        }
    }
}
