//! A Lambertian plane lit by point, spot and directional lights: the radiance toward the
//! camera is L = ρ/π · I · cos θ / d² (times the spot's falloff), or ρ/π · E · cos θ outside
//! an occluder's shadow for a directional light of irradiance E. Only direct light: the plane
//! cannot see itself. The point light scene is also rendered at tiny and huge scales: lengths
//! × s and intensity × s² give the same image. Every scene is rendered by the path tracer,
//! BPT and VCM: with delta lights, a light sample and a light path splatted through the camera
//! both find the direct light, so the check covers their MIS weights too.

use glam::{DVec3, Vec3, Vec4};
use vcm::{Algorithm, Integrator, PtSettings, VcmSettings};
use vcm_scene::light::{DirectionalLight, Light, PointLight, SpotLight};
use vcm_scene::{Material, Scene};

use crate::common;

const ALBEDO: f32 = 0.5;
/// Radiant intensity at scale 1 (W/sr).
const INTENSITY: Vec3 = Vec3::new(4.0, 8.0, 12.0);
/// Light position at scale 1.
const LIGHT: Vec3 = Vec3::new(0.5, -0.3, 1.5);
const SIZE: u32 = 8;

/// Channel mean of an RGB value.
fn mean(rgb: Vec3) -> f64 {
    f64::from(rgb.element_sum()) / 3.0
}

/// Analytic radiance (channel mean) leaving the plane z = 0 at `p`, lit by a light of radiant
/// intensity `intensity` (W/sr toward `p`) at `position`.
fn radiance(position: Vec3, intensity: f64, p: DVec3) -> f64 {
    let to_light = position.as_dvec3() - p;
    let d2 = to_light.length_squared();
    let cos_theta = to_light.z / d2.sqrt();
    f64::from(ALBEDO) / std::f64::consts::PI * intensity * cos_theta / d2
}

/// The integrators every scene is rendered with (`None`: the path tracer).
const ALGORITHMS: [Option<Algorithm>; 3] = [None, Some(Algorithm::Bpt), Some(Algorithm::Vcm)];

/// The floor (of material `floor` and half side `half`, its vertex normals `normal`, zero for
/// none; plus `extra` quads of material 1, black) under `light`, seen by `camera`.
fn floor_scene(
    light: Light,
    camera: vcm_scene::Camera,
    floor: Material,
    half: f32,
    extra: &[[Vec3; 4]],
    normal: Vec3,
) -> Scene {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    common::push_floor(&mut positions, &mut triangles, half);
    for quad in extra {
        common::push_quad(&mut positions, &mut triangles, *quad);
    }
    let mut material_ids = vec![1; triangles.len()];
    material_ids[..2].fill(0);
    let mut mesh = common::mesh(positions, triangles, material_ids);
    mesh.normals[..4].fill(normal);
    common::scene(
        mesh,
        vec![floor, Material::diffuse("black", Vec3::ZERO)],
        vec![light],
        camera,
    )
}

/// The Lambertian floor of albedo `ALBEDO`.
fn lambertian_floor() -> Material {
    Material::diffuse("floor", Vec3::splat(ALBEDO))
}

/// An integrator (`None`: the path tracer) for the flat-shaded [`floor_scene`].
fn floor_under(
    light: Light,
    camera: vcm_scene::Camera,
    half: f32,
    extra: &[[Vec3; 4]],
    algorithm: Option<Algorithm>,
) -> Box<dyn Integrator> {
    let scene = floor_scene(light, camera, lambertian_floor(), half, extra, Vec3::ZERO);
    integrator_for(scene, algorithm, true)
}

/// An integrator (`None`: the path tracer) for `scene`, seed 9; `prune: false` runs every
/// part of the VCM family's algorithm even where the scene does not need it.
fn integrator_for(scene: Scene, algorithm: Option<Algorithm>, prune: bool) -> Box<dyn Integrator> {
    match algorithm {
        None => {
            let settings = PtSettings {
                seed: 9,
                ..common::pt_settings(SIZE, SIZE)
            };
            Box::new(common::path_tracer(scene, settings))
        }
        Some(algorithm) => {
            let settings = VcmSettings {
                seed: 9,
                prune,
                ..common::vcm_settings(algorithm, SIZE, SIZE)
            };
            Box::new(common::vcm(scene, settings))
        }
    }
}

/// Renders `light`'s scene with every integrator and compares the pixels with `expected`.
fn assert_all_match(
    light: Light,
    camera: vcm_scene::Camera,
    half: f32,
    extra: &[[Vec3; 4]],
    expected: &[f64],
    label: &str,
) {
    for algorithm in ALGORITHMS {
        let mut integrator = floor_under(light.clone(), camera, half, extra, algorithm);
        // Light paths splatted through the camera land in a given pixel rarely (64 light
        // paths a frame): enough frames that each pixel's standard error sees them.
        let series = common::render_series(integrator.as_mut(), 512);
        common::assert_pixels_match(&series, expected, &format!("{label}, {algorithm:?}"));
    }
}

/// Renders the point light scene at scale `scale` and compares every pixel with the closed
/// form.
fn assert_matches_closed_form(scale: f32) {
    let camera = common::camera(Vec3::new(0.2, 0.1, 3.0) * scale, 0.6);
    let light = PointLight {
        position: LIGHT * scale,
        intensity: INTENSITY * scale * scale,
    };
    let expected = common::plane_pixel_values(&camera, SIZE, |p| {
        radiance(light.position, mean(light.intensity), p)
    });
    let label = format!("scale {scale}");
    assert_all_match(
        Light::Point(light),
        camera,
        20.0 * scale,
        &[],
        &expected,
        &label,
    );
}

#[test]
fn lambertian_plane_under_a_point_light_matches_the_closed_form() {
    assert_matches_closed_form(1.0);
}

#[test]
fn the_closed_form_holds_at_tiny_and_huge_scales() {
    for scale in [1e-4, 1e5] {
        assert_matches_closed_form(scale);
    }
}

/// Vertex normals leaning 40° from the floor's: the light's cosine is taken about them
/// (L = ρ/π · I · max(0, cos θ_s) / d²), by light samples and by light paths through the
/// adjoint BSDF with Veach's correction (and VCM with every technique on: nothing here is
/// specular, so pruned it would run as BPT). A uniform sky cannot tell every weighting of
/// the shading cosines apart (`environment.rs`); a point light to one side can. (BPM is left
/// out: on this wide floor its merges find a light vertex too rarely for 512 frames.)
#[test]
fn leaning_shading_normals_take_the_light_cosine_about_themselves() {
    let camera = common::camera(Vec3::new(0.2, 0.1, 3.0), 0.6);
    let tilt = 40f32.to_radians();
    let normal = DVec3::new(tilt.sin().into(), 0.0, tilt.cos().into());
    let light = PointLight {
        position: LIGHT,
        intensity: INTENSITY,
    };
    let expected = common::plane_pixel_values(&camera, SIZE, |p| {
        let to_light = light.position.as_dvec3() - p;
        let d2 = to_light.length_squared();
        let cos_s = (to_light.dot(normal) / d2.sqrt()).max(0.0);
        f64::from(ALBEDO) / std::f64::consts::PI * mean(light.intensity) * cos_s / d2
    });
    let floor = lambertian_floor();
    let scene = floor_scene(
        Light::Point(light),
        camera,
        floor,
        20.0,
        &[],
        normal.as_vec3(),
    );
    let algorithms = [
        None,
        Some(Algorithm::LightTracing),
        Some(Algorithm::Bpt),
        Some(Algorithm::Vcm),
    ];
    for algorithm in algorithms {
        let mut integrator = integrator_for(scene.clone(), algorithm, false);
        let series = common::render_series(integrator.as_mut(), 512);
        let label = format!("leaning normals, {algorithm:?}");
        common::assert_pixels_match(&series, &expected, &label);
    }
}

/// GGX (Trowbridge-Reitz) D(h) and the height-correlated Smith G2 of width `alpha`, for the
/// unit half vector `h` and the unit directions `wo`, `wi` (z: the surface normal).
fn ggx_d_g2(alpha: f64, h: DVec3, wo: DVec3, wi: DVec3) -> (f64, f64) {
    let a2 = alpha * alpha;
    let t = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z;
    let d = 1.0 / (std::f64::consts::PI * a2 * t * t);
    let lambda = |w: DVec3| {
        let tan2 = (w.x * w.x + w.y * w.y) / (w.z * w.z);
        0.5 * ((1.0 + a2 * tan2).sqrt() - 1.0)
    };
    (d, 1.0 / (1.0 + lambda(wo) + lambda(wi)))
}

/// A polished white metal floor (roughness 0.02: GGX α = r² = 4·10⁻⁴, F = 1) under a point
/// light, seen from straight above through a field of view of 1.6 mrad that the light's
/// highlight fills: L = D(h) G2 / (4 cos θo) · I / d² per pixel. The highlight exists only
/// for a rough lobe (a perfect mirror cannot reflect a point light toward a pinhole), so
/// this fails if any roughness above 0 renders as a mirror, or with α = r.
#[test]
fn a_polished_floor_shows_the_point_lights_ggx_highlight() {
    let roughness = 0.02;
    let alpha = f64::from(roughness).powi(2);
    let camera = common::camera(Vec3::new(0.0, 0.0, 3.0), 1.6e-3);
    let light = PointLight {
        position: Vec3::new(0.0, 0.0, 1.5),
        intensity: INTENSITY,
    };
    let expected = common::plane_pixel_values(&camera, SIZE, |p| {
        let to_light = light.position.as_dvec3() - p;
        let (wi, wo) = (
            to_light.normalize(),
            (camera.position.as_dvec3() - p).normalize(),
        );
        let (d, g2) = ggx_d_g2(alpha, (wi + wo).normalize(), wo, wi);
        d * g2 / (4.0 * wo.z) * mean(light.intensity) / to_light.length_squared()
    });
    let floor = Material {
        base_color: Vec4::ONE,
        metallic: 1.0,
        roughness,
        ..Material::diffuse("polished", Vec3::ONE)
    };
    let scene = floor_scene(Light::Point(light), camera, floor, 20.0, &[], Vec3::ZERO);
    for algorithm in ALGORITHMS {
        let mut integrator = integrator_for(scene.clone(), algorithm, true);
        let series = common::render_series(integrator.as_mut(), 512);
        let label = format!("polished floor, {algorithm:?}");
        common::assert_pixels_match(&series, &expected, &label);
    }
}

#[test]
fn spot_light_falloff_matches_the_closed_form() {
    // The whole view lies inside the outer cone (tan 0.85 · 1.5 ≈ 1.7 > the view's corners at
    // ≤ 1.5 from the axis) and mostly outside the inner one, so every pixel sees the falloff
    // ramp and no pixel a cut-off sliver that its few samples could miss.
    let camera = common::camera(Vec3::new(0.0, 0.0, 3.0), 0.6);
    let spot = SpotLight {
        position: Vec3::new(0.1, -0.1, 1.5),
        direction: Vec3::new(-0.05, 0.05, -1.0).normalize(),
        intensity: INTENSITY,
        cos_inner: 0.2f32.cos(),
        cos_outer: 0.85f32.cos(),
    };
    let expected = common::plane_pixel_values(&camera, SIZE, |p| {
        let to_p = (p - spot.position.as_dvec3()).normalize().as_vec3();
        let falloff = f64::from(spot.falloff(spot.direction.dot(to_p)));
        radiance(spot.position, mean(spot.intensity) * falloff, p)
    });
    assert_all_match(Light::Spot(spot), camera, 20.0, &[], &expected, "spot");
}

#[test]
fn directional_light_and_its_shadow_match_the_closed_form() {
    // Light travels along (-1, 0, -1)/√2; a black square at z = 1 beside the camera's view
    // shadows the floor where x + 1 ∈ [0.8, 1.6] and |y| ≤ 0.3.
    let camera = common::camera(Vec3::new(0.0, 0.0, 3.0), 0.6);
    let irradiance = Vec3::new(2.0, 3.0, 4.0);
    // A small floor in a tight bounding disk: light paths, which start on the disk, then
    // land in the view often enough for their share of BPT's and VCM's weights to be seen.
    let light = DirectionalLight {
        direction: Vec3::new(-1.0, 0.0, -1.0).normalize(),
        irradiance,
        scene_center: Vec3::ZERO,
        scene_radius: 4.5,
    };
    let occluder =
        [(0.8, -0.3), (1.6, -0.3), (1.6, 0.3), (0.8, 0.3)].map(|(x, y)| Vec3::new(x, y, 1.0));
    let lit = f64::from(ALBEDO) / std::f64::consts::PI * mean(irradiance) * 0.5f64.sqrt();
    let expected = common::plane_pixel_values(&camera, SIZE, |p| {
        let shadowed = (0.8..=1.6).contains(&(p.x + 1.0)) && p.y.abs() <= 0.3;
        if shadowed { 0.0 } else { lit }
    });
    // Some pixels lie fully in the shadow, some fully in the light.
    assert!(expected.contains(&0.0));
    assert!(expected.iter().any(|&l| (l - lit).abs() < 1e-9 * lit));
    let light = Light::Directional(light);
    assert_all_match(light, camera, 3.0, &[occluder], &expected, "directional");
}
