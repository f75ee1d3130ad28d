//! The path tracer shades vertices on plain Lambertian surfaces under area lights in SIMD
//! lanes; every other vertex goes through the general BSDF. The lanes perform the general
//! vertex's operations in the same order, so a render gives the same film with them and
//! without them ([`ShadingPlan::lambert_lanes`] off), bit for bit: on the Cornell scenes,
//! with leaning shading normals, with a path length limit, and on a scene of one-sided and
//! double-sided surfaces seen from both sides under two lights of different power, beside
//! glossy and emitting ones.

mod common;

use glam::{Vec3, Vec4};
use vcm::{Film, Integrator, PtSettings};
use vcm_scene::{Material, Scene};

const SIZE: u32 = 40;
const FRAMES: u32 = 3;
const LANES_PART: &str = "plain Lambert vertices in SIMD lanes";

/// The mean film of `FRAMES` frames of the path tracer, and whether it shaded in lanes.
fn render(scene: Scene, settings: PtSettings) -> (Vec<Vec3>, bool) {
    let mut tracer = common::path_tracer(scene, settings);
    let decisions = tracer.decisions();
    let lanes = decisions.iter().find(|d| d.part == LANES_PART);
    let in_lanes = lanes.expect("the path tracer decides on lanes").runs;
    let mut film = Film::new(SIZE, SIZE);
    for frame in 0..FRAMES {
        tracer.render_frame(&mut film, frame);
    }
    (film.mean(), in_lanes)
}

/// Renders `scene` with and without lanes and asserts the films are the same, bit for bit.
fn assert_lanes_change_nothing(name: &str, scene: Scene, settings: PtSettings) {
    let without = Scene {
        shading: vcm_scene::ShadingPlan {
            lambert_lanes: false,
            ..scene.shading
        },
        ..scene.clone()
    };
    let (with_lanes, ran) = render(scene, settings);
    let (general, ran_without) = render(without, settings);
    assert!(
        ran && !ran_without,
        "{name}: lanes ran {ran}, {ran_without}"
    );
    assert!(
        with_lanes.iter().any(|p| p.max_element() > 0.0),
        "{name}: black"
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
    assert_eq!(differing, 0, "{name}: pixels differ");
}

fn settings() -> PtSettings {
    PtSettings {
        seed: 3,
        ..common::pt_settings(SIZE, SIZE)
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
        assert_lanes_change_nothing(name, common::scene_file(name), settings());
    }
}

#[test]
fn leaning_shading_normals_and_a_length_limit_render_the_same_in_lanes() {
    let leaning = common::with_leaning_normals("cornell-box.gltf");
    assert_lanes_change_nothing("leaning normals", leaning, settings());
    for max_depth in [1, 2, 4] {
        let limited = PtSettings {
            max_depth: Some(max_depth),
            ..settings()
        };
        let scene = common::scene_file("cornell-box.gltf");
        assert_lanes_change_nothing(&format!("max depth {max_depth}"), scene, limited);
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
    assert_lanes_change_nothing("sides", sides(), settings());
}

/// A light other than a constant area light keeps every vertex on the general BSDF.
#[test]
fn a_point_light_leaves_the_lanes_out() {
    let mut scene = common::scene_file("cornell-box.gltf");
    let bulb = vcm_scene::light::Light::Point(vcm_scene::light::PointLight {
        position: Vec3::new(0.0, 1.0, 0.0),
        intensity: Vec3::ONE,
    });
    scene = common::rebuilt(scene.clone(), scene.mesh.clone(), vec![bulb]);
    let tracer = common::path_tracer(scene, settings());
    let decisions = tracer.decisions();
    let lanes = decisions.iter().find(|d| d.part == LANES_PART).unwrap();
    assert!(!lanes.runs);
    assert!(
        lanes.reason.contains("constant, uncut area light"),
        "{}",
        lanes.reason
    );
}
