//! Every integrator shades vertices on plain Lambertian surfaces in SIMD lanes where it can (the path tracer's vertices, the VCM family's light vertices, and its
//! camera vertices where nothing merges); every other vertex goes through the general BSDF.
//! The lanes perform the general vertex's operations in the same order, so a render gives
//! the same film with them and without them (`lambert_lanes` off in the settings), bit for
//! bit: on the Cornell scenes, with leaning shading normals, with path length limits,
//! several samples per frame and several connections per camera vertex, and on a scene of
//! one-sided and double-sided surfaces seen from both sides under two lights of different
//! power, beside glossy and emitting ones, and under every kind of light.

use glam::{Vec3, Vec4};
use vcm::{Algorithm, Film, Integrator, MergeRadius, PtSettings, Schedule, VcmSettings};
use vcm_scene::light::{DirectionalLight, Light, PointLight, SpotLight};
use vcm_scene::{Material, Scene};

use crate::common::{self, EVERY_ALGORITHM};

const SIZE: u32 = 40;
const FRAMES: u32 = 3;
const LANES_PART: &str = "plain Lambert vertices in SIMD lanes";

/// How an integrator renders besides its algorithm.
#[derive(Clone, Copy)]
struct Options {
    max_depth: Option<u32>,
    samples_per_frame: u32,
    connections: u32,
    /// Shade in lanes where the scene allows it (the settings' `lambert_lanes`).
    lanes: bool,
}

const DEFAULT: Options = Options {
    max_depth: None,
    samples_per_frame: 1,
    connections: 1,
    lanes: true,
};

/// The path tracer (`None`) or `algorithm` over `scene`, merging within 5% of the scene's
/// radius.
fn integrator(scene: Scene, algorithm: Option<Algorithm>, options: Options) -> Box<dyn Integrator> {
    let Options {
        max_depth,
        samples_per_frame,
        connections,
        lanes,
    } = options;
    let mut integrator: Box<dyn Integrator> = match algorithm {
        None => Box::new(common::path_tracer(
            scene,
            PtSettings {
                seed: 3,
                max_depth,
                lambert_lanes: lanes,
                ..common::pt_settings(SIZE, SIZE)
            },
        )),
        Some(algorithm) => Box::new(common::vcm(
            scene,
            VcmSettings {
                seed: 3,
                max_depth,
                connections,
                radius: MergeRadius::SceneFraction(0.05),
                lambert_lanes: lanes,
                ..common::vcm_settings(algorithm, SIZE, SIZE)
            },
        )),
    };
    let schedule = Schedule {
        samples_per_frame,
        ..Schedule::default()
    };
    integrator.set_schedule(schedule).unwrap();
    integrator
}

/// The mean film of `FRAMES` frames, and whether the integrator shaded in lanes.
fn render(mut integrator: Box<dyn Integrator>) -> (Vec<Vec3>, bool) {
    let decisions = integrator.decisions();
    let lanes = decisions.iter().find(|d| d.part == LANES_PART);
    let in_lanes = lanes.expect("the integrator decides on lanes").runs;
    let mut film = Film::new(SIZE, SIZE);
    let samples = integrator.samples_per_frame();
    for frame in 0..FRAMES {
        integrator.render_frame(&mut film, frame * samples);
    }
    (film.mean(), in_lanes)
}

/// Renders `scene` with every algorithm, with and without lanes, and asserts the films are
/// the same, bit for bit.
fn assert_lanes_change_nothing(
    name: &str,
    scene: &Scene,
    algorithms: &[Option<Algorithm>],
    options: Options,
) {
    let without = Options {
        lanes: false,
        ..options
    };
    for &algorithm in algorithms {
        let (with_lanes, ran) = render(integrator(scene.clone(), algorithm, options));
        let (general, ran_without) = render(integrator(scene.clone(), algorithm, without));
        let label = format!("{name}, {algorithm:?}");
        assert!(
            ran && !ran_without,
            "{label}: lanes ran {ran}, {ran_without}"
        );
        assert!(
            with_lanes.iter().any(|p| p.max_element() > 0.0),
            "{label}: black"
        );
        let bits = |film: &[Vec3]| -> Vec<[u32; 3]> {
            film.iter()
                .map(|p| p.to_array().map(f32::to_bits))
                .collect()
        };
        let differing = bits(&with_lanes)
            .iter()
            .zip(bits(&general))
            .filter(|(a, b)| **a != *b)
            .count();
        assert_eq!(differing, 0, "{label}: pixels differ");
    }
}

#[test]
fn the_cornell_scenes_render_the_same_in_lanes() {
    for name in [
        "cornell-box.gltf",
        "cornell-indirect.gltf",
        "cornell-specular.gltf",
        "cornell-water.gltf",
    ] {
        let scene = common::scene_file(name);
        assert_lanes_change_nothing(name, &scene, &EVERY_ALGORITHM, DEFAULT);
    }
}

#[test]
fn leaning_shading_normals_and_length_limits_render_the_same_in_lanes() {
    let leaning = common::with_leaning_normals("cornell-box.gltf");
    assert_lanes_change_nothing("leaning normals", &leaning, &EVERY_ALGORITHM, DEFAULT);
    let connecting = [None, Some(Algorithm::Bpt), Some(Algorithm::Vcm)];
    let scene = common::scene_file("cornell-box.gltf");
    for max_depth in [1, 2, 3, 4] {
        let limited = Options {
            max_depth: Some(max_depth),
            ..DEFAULT
        };
        let name = format!("max depth {max_depth}");
        assert_lanes_change_nothing(&name, &scene, &connecting, limited);
    }
}

/// Paths of several iterations share lane groups (each its own cache), and camera vertices
/// connect to several light vertices each.
#[test]
fn several_samples_per_frame_and_connections_render_the_same_in_lanes() {
    let scene = common::scene_file("cornell-box.gltf");
    let connecting = [Some(Algorithm::Bpt), Some(Algorithm::Vcm)];
    for (samples_per_frame, connections) in [(3, 1), (1, 3), (2, 2)] {
        let options = Options {
            samples_per_frame,
            connections,
            ..DEFAULT
        };
        let name = format!("{samples_per_frame} samples per frame, {connections} connections");
        assert_lanes_change_nothing(&name, &scene, &connecting, options);
    }
}

/// An open room: a one-sided floor, a one-sided back wall facing away from the camera, a
/// double-sided left wall seen from its back, a one-sided panel facing the floor, a glossy
/// right wall (general BSDF), and two emitters of different power (a white diffuse one
/// included, which the lanes leave to the general vertex).
fn sides() -> Scene {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    let v = Vec3::new;
    let quads = [
        [
            v(-1., 0., 1.),
            v(1., 0., 1.),
            v(1., 0., -1.),
            v(-1., 0., -1.),
        ],
        [
            v(1., 0., -1.),
            v(-1., 0., -1.),
            v(-1., 1.5, -1.),
            v(1., 1.5, -1.),
        ],
        [
            v(-1., 0., 1.),
            v(-1., 1.5, 1.),
            v(-1., 1.5, -1.),
            v(-1., 0., -1.),
        ],
        [
            v(-0.4, 0.8, 0.2),
            v(0.4, 0.8, 0.2),
            v(0.4, 0.8, -0.4),
            v(-0.4, 0.8, -0.4),
        ],
        [
            v(1., 0., 1.),
            v(1., 0., -1.),
            v(1., 1.5, -1.),
            v(1., 1.5, 1.),
        ],
        [
            v(-0.3, 1.5, -0.3),
            v(0.3, 1.5, -0.3),
            v(0.3, 1.5, 0.3),
            v(-0.3, 1.5, 0.3),
        ],
        [
            v(-0.2, 0.2, -0.99),
            v(0.2, 0.2, -0.99),
            v(0.2, 0.5, -0.99),
            v(-0.2, 0.5, -0.99),
        ],
    ];
    for corners in quads {
        common::push_quad(&mut positions, &mut triangles, corners);
    }
    let one_sided = |name, albedo| Material {
        double_sided: false,
        ..Material::diffuse(name, albedo)
    };
    let glossy = Material {
        roughness: 0.4,
        ..Material::diffuse("glossy", Vec3::new(0.3, 0.5, 0.2))
    };
    let emitter = |name, albedo, emission| Material {
        emission,
        base_color: Vec4::from((albedo, 1.0)),
        ..Material::diffuse(name, albedo)
    };
    let materials = vec![
        one_sided("floor", Vec3::new(0.7, 0.6, 0.5)),
        one_sided("back", Vec3::splat(0.8)),
        Material::diffuse("left", Vec3::new(0.2, 0.6, 0.8)),
        one_sided("panel", Vec3::splat(0.9)),
        glossy,
        emitter("ceiling light", Vec3::ZERO, Vec3::splat(5.0)),
        emitter("white lamp", Vec3::ONE, Vec3::new(20.0, 15.0, 10.0)),
    ];
    let material_ids = (0..quads.len() as u32).flat_map(|q| [q, q]).collect();
    common::scene(
        common::mesh(positions, triangles, material_ids),
        materials,
        Vec::new(),
        common::camera(Vec3::new(0.0, 0.7, 2.5), 1.0),
    )
}

#[test]
fn one_and_two_sided_surfaces_under_two_lights_render_the_same_in_lanes() {
    assert_lanes_change_nothing("sides", &sides(), &EVERY_ALGORITHM, DEFAULT);
}

/// The Cornell box lit by `lights`, with its area light (`area`) or without (its emitter
/// black).
fn cornell_box_lit_by(lights: Vec<Light>, area: bool) -> Scene {
    let mut scene = common::scene_file("cornell-box.gltf");
    if !area {
        for material in &mut scene.materials {
            material.emission = Vec3::ZERO;
        }
    }
    let mesh = scene.mesh.clone();
    common::rebuilt(scene, mesh, lights)
}

/// Lanes sample point, spot, directional and constant area lights themselves, lights of
/// different kinds in one group, and the environment by its own code, going on in the lanes
/// from its sample.
#[test]
fn every_kind_of_light_renders_the_same_in_lanes() {
    let mesh = common::scene_file("cornell-box.gltf").mesh;
    let bounds = mesh.bounds();
    let point = Light::Point(PointLight {
        position: Vec3::new(-0.3, 0.7, 0.2),
        intensity: Vec3::new(1.0, 0.8, 0.6),
    });
    let spot = Light::Spot(SpotLight {
        position: Vec3::new(0.4, 0.8, 0.5),
        direction: Vec3::new(-0.3, -1.0, -0.4).normalize(),
        intensity: Vec3::new(2.0, 2.0, 3.0),
        cos_inner: 0.9,
        cos_outer: 0.7,
    });
    // Into the box's open front, lighting the floor and the back wall.
    let sun = Light::Directional(DirectionalLight {
        direction: Vec3::new(0.2, -0.5, -1.0).normalize(),
        irradiance: Vec3::new(1.5, 1.4, 1.2),
        scene_center: bounds.center(),
        scene_radius: bounds.radius(),
    });
    let sky = common::sky(Vec3::new(0.2, 0.3, 0.5), None, &mesh);
    let every = vec![point.clone(), spot.clone(), sun.clone(), sky.clone()];
    for (name, lights, area) in [
        ("point light alone", vec![point.clone()], false),
        ("spot light and area light", vec![spot], true),
        ("sun alone", vec![sun], false),
        ("sky and area light", vec![sky], true),
        ("every kind", every, true),
    ] {
        let scene = cornell_box_lit_by(lights, area);
        assert_lanes_change_nothing(name, &scene, &EVERY_ALGORITHM, DEFAULT);
    }
    let limited = Options {
        max_depth: Some(3),
        connections: 2,
        ..DEFAULT
    };
    let connecting = [None, Some(Algorithm::Bpt), Some(Algorithm::Vcm)];
    let scene = cornell_box_lit_by(vec![point], true);
    assert_lanes_change_nothing("point light, limited", &scene, &connecting, limited);
}
