//! Stiff lights: a tiny light a million times brighter than a large dim one, a point light
//! almost touching a wall (which must cast a full shadow), and a point light so close to the
//! floor that its light grazes it (cosines of 10⁻⁵).

use glam::{DVec3, Vec3};
use vcm::Algorithm;
use vcm_scene::Material;
use vcm_scene::light::{Light, PointLight};

use super::harness::{self, REGIONS, Setup};
use super::scenes::{Placement, SceneParts, camera_looking, emitter};
use crate::common;
use crate::common::EVERY_ALGORITHM;

/// Radiance of the large light; the tiny one emits a million times more.
const DIM: f32 = 0.25;
const ALBEDO: f32 = 0.5;

/// A floor and a back wall under a dim 3 × 3 ceiling light and a 10⁻³ × 10⁻³ light of
/// 10⁶ times its radiance (a quarter of its power), both facing down; the camera looks down
/// at the floor from above the tiny light, which shows it only its black back.
fn two_lights() -> SceneParts {
    let position = Vec3::new(0.0, 1.2, 2.5);
    let forward = (Vec3::ZERO - position).normalize();
    let mut parts = SceneParts::new(camera_looking(position, forward, Vec3::Y, 0.7));
    let white = parts.material(Material::diffuse("white", Vec3::splat(0.7)));
    let grey = parts.material(Material::diffuse("grey", Vec3::splat(0.5)));
    let dim = parts.material(emitter(DIM));
    let bright = parts.material(emitter(DIM * 1e6));
    let v = Vec3::new;
    parts.quad(
        [
            v(-1.5, 0.0, 1.5),
            v(1.5, 0.0, 1.5),
            v(1.5, 0.0, -1.5),
            v(-1.5, 0.0, -1.5),
        ],
        white,
    );
    parts.quad(
        [
            v(-1.5, 0.0, -1.5),
            v(1.5, 0.0, -1.5),
            v(1.5, 1.6, -1.5),
            v(-1.5, 1.6, -1.5),
        ],
        grey,
    );
    parts.quad(
        [
            v(-1.5, 1.6, -1.5),
            v(1.5, 1.6, -1.5),
            v(1.5, 1.6, 1.5),
            v(-1.5, 1.6, 1.5),
        ],
        dim,
    );
    let (c, h) = (v(0.3, 0.4, 0.0), 0.5e-3);
    parts.quad(
        [
            c + v(-h, 0.0, -h),
            c + v(h, 0.0, -h),
            c + v(h, 0.0, h),
            c + v(-h, 0.0, h),
        ],
        bright,
    );
    parts
}

#[test]
fn a_tiny_bright_light_beside_a_large_dim_one_renders_as_path_tracing_sees_it() {
    let parts = two_lights();
    let render = |algorithm, seed| {
        // Merging within 2% of the scene blurs the tiny light's pool of light (0.4 below
        // it) by far less than 200 frames can see.
        let setup = Setup::new(seed, 0.02);
        let mut integrator =
            harness::integrator(parts.build(Placement::IDENTITY), algorithm, setup);
        common::region_means(integrator.as_mut(), 200, REGIONS)
    };
    let reference = render(None, 1);
    for algorithm in &EVERY_ALGORITHM[1..] {
        let series = render(*algorithm, 2);
        harness::assert_regions_agree(&series, &reference, &harness::name(*algorithm));
    }
}

/// The floor z = 0 (half side 4) seen from above, lit by `light`, with `wall` (a black
/// quad) if given.
fn lit_floor(camera: vcm_scene::Camera, light: PointLight, wall: Option<[Vec3; 4]>) -> SceneParts {
    let mut parts = SceneParts::new(camera);
    let floor = parts.material(Material::diffuse("floor", Vec3::splat(ALBEDO)));
    let black = parts.material(Material {
        double_sided: true,
        ..Material::diffuse("black", Vec3::ZERO)
    });
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    common::push_floor(&mut positions, &mut triangles, 4.0);
    parts.mesh(&positions, &triangles, floor);
    if let Some(wall) = wall {
        parts.quad(wall, black);
    }
    parts.light(Light::Point(light));
    parts
}

#[test]
fn a_point_light_almost_touching_a_wall_leaves_the_other_side_dark() {
    // The light is 10⁻⁵ from the wall x = 0; the camera sees only the floor behind it
    // (x from 0.1 to 1.1), which no light path can reach: the wall stands 1 high and the
    // floor cannot light itself.
    let camera = common::camera(Vec3::new(0.6, 0.0, 2.0), 2.0 * 0.25f32.atan());
    let light = PointLight {
        position: Vec3::new(-1e-5, 0.0, 0.5),
        intensity: Vec3::splat(10.0),
    };
    let v = Vec3::new;
    let wall = [
        v(0.0, -4.0, 0.0),
        v(0.0, 4.0, 0.0),
        v(0.0, 4.0, 1.0),
        v(0.0, -4.0, 1.0),
    ];
    // Merging within 0.3% of the scene (0.017) cannot reach across the wall into the view.
    // Without the wall the same view is lit.
    let open = lit_floor(camera, light.clone(), None).build(Placement::IDENTITY);
    let mut integrator =
        harness::integrator(open, None, Setup::new(3, vcm::DEFAULT_RADIUS_FRACTION));
    assert!(common::render_series(integrator.as_mut(), 4).image_mean > 0.1);
    let parts = lit_floor(camera, light, Some(wall));
    for algorithm in EVERY_ALGORITHM {
        let scene = parts.build(Placement::IDENTITY);
        let mut integrator = harness::integrator(
            scene,
            algorithm,
            Setup::new(3, vcm::DEFAULT_RADIUS_FRACTION),
        );
        let series = common::render_series(integrator.as_mut(), 50);
        let label = harness::name(algorithm);
        harness::assert_finite(&series, &label);
        let lit = series
            .film
            .mean()
            .iter()
            .filter(|rgb| rgb.max_element() > 0.0)
            .count();
        assert_eq!(
            lit, 0,
            "{label}: light leaks through the wall into {lit} pixels"
        );
    }
}

#[test]
fn light_grazing_the_floor_from_a_point_light_matches_the_closed_form() {
    // A light 10⁻⁵ above the floor lights the view (x from 0.5 to 1.5) at cosines of
    // 10⁻⁵ … 2·10⁻⁵: L = ρ/π · I · h / d³. Light paths almost never land there (the view
    // subtends 10⁻⁵ sr from the light), so only next event estimation can sample this light:
    // the path tracer, BPT and VCM, whose weights must then give it all.
    let height = 1e-5;
    let intensity = 1e5;
    let camera = common::camera(Vec3::new(1.0, 0.0, 2.0), 2.0 * 0.25f32.atan());
    let light = PointLight {
        position: Vec3::new(0.0, 0.0, height),
        intensity: Vec3::splat(intensity),
    };
    let expected = common::plane_pixel_values(&camera, harness::SIZE, |p| {
        let d = (DVec3::new(0.0, 0.0, f64::from(height)) - p).length();
        f64::from(ALBEDO) / std::f64::consts::PI * f64::from(intensity) * f64::from(height)
            / (d * d * d)
    });
    let parts = lit_floor(camera, light, None);
    for algorithm in [None, Some(Algorithm::Bpt), Some(Algorithm::Vcm)] {
        let scene = parts.build(Placement::IDENTITY);
        let mut integrator = harness::integrator(scene, algorithm, Setup::new(4, 0.05));
        let series = common::render_series(integrator.as_mut(), 100);
        common::assert_pixels_match(&series, &expected, &harness::name(algorithm));
    }
}
