//! A specular–diffuse–specular scene: a tiny area light shines through a glass sphere onto a
//! diffuse floor, and the camera sees the floor only in a mirror. The caustic's paths are
//! E S D S S L: path tracing finds them only when a diffuse bounce happens to hit the tiny
//! light through the sphere, BPT cannot connect (both ends of every connection are specular
//! or on the same plane), and VCM merges at the floor. With the same number of frames, VCM's
//! expected error against a long VCM reference is far below both.
//!
//! The error of one short path-traced render is heavy-tailed: most of it comes from the rare
//! paths that hit the light, so a render without one has a small relMSE (the caustic is
//! simply missing, about 0.3 here) and one with a few has a huge one (10² to 10³). One render
//! per algorithm would compare a single draw of that (3 of 10 seeds gave PT below 10× VCM);
//! the test compares the mean relMSE of several independent renders, which estimates the
//! expected relMSE, the quantity "far below" is about.

use glam::Vec3;
use vcm::metrics::compare;
use vcm::{Algorithm, Film, Integrator, MergeRadius, PtSettings, VcmSettings};
use vcm_scene::{Camera, Material, Scene};

use crate::common;

const SIZE: u32 = 32;
const FRAMES: u32 = 64;

fn sds_scene() -> Scene {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    let mut material_ids = Vec::new();
    let mut push_quad = |positions: &mut Vec<Vec3>, corners: [Vec3; 4], material: u32| {
        let before = triangles.len();
        common::push_quad(positions, &mut triangles, corners);
        material_ids.extend(std::iter::repeat_n(material, triangles.len() - before));
    };
    // Floor z = 0 (facing up), mirror x = 2 (facing −x), tiny light at z = 2.5 (facing down).
    let floor = [(-2.0, -2.0), (2.0, -2.0), (2.0, 2.0), (-2.0, 2.0)];
    push_quad(&mut positions, floor.map(|(x, y)| Vec3::new(x, y, 0.0)), 0);
    let mirror = [(-2.0, 0.0), (-2.0, 3.0), (2.0, 3.0), (2.0, 0.0)];
    push_quad(&mut positions, mirror.map(|(y, z)| Vec3::new(2.0, y, z)), 1);
    let light = [(-0.03, -0.03), (-0.03, 0.03), (0.03, 0.03), (0.03, -0.03)];
    push_quad(&mut positions, light.map(|(x, y)| Vec3::new(x, y, 2.5)), 2);
    // The glass sphere: radius 0.5 around (0, 0, 1).
    let (sphere, sphere_triangles) = vcm_scene::shapes::icosphere(3);
    let base = positions.len() as u32;
    positions.extend(sphere.iter().map(|&p| p * 0.5 + Vec3::Z));
    for [a, b, c] in sphere_triangles {
        triangles.push([a + base, b + base, c + base]);
        material_ids.push(3);
    }
    let materials = vec![
        Material::diffuse("floor", Vec3::splat(0.8)),
        Material {
            metallic: 1.0,
            roughness: 0.0,
            ..Material::diffuse("mirror", Vec3::splat(0.95))
        },
        Material {
            emission: Vec3::splat(3000.0),
            ..Material::diffuse("light", Vec3::ZERO)
        },
        Material {
            transmission: 1.0,
            roughness: 0.0,
            ior: 1.5,
            thin_walled: false,
            ..Material::diffuse("glass", Vec3::ONE)
        },
    ];
    // Looking at the mirror image of the floor under the sphere.
    let position = Vec3::new(0.3, 0.0, 2.6);
    let forward = (Vec3::new(4.0, 0.0, 0.0) - position).normalize();
    let right = forward.cross(Vec3::Z).normalize();
    let camera = Camera {
        position,
        right,
        up: right.cross(forward),
        forward,
        yfov: 0.3,
        aspect_ratio: None,
    };
    common::scene(
        common::mesh(positions, triangles, material_ids),
        materials,
        Vec::new(),
        camera,
    )
}

/// Independent renders averaged for each algorithm's expected relMSE.
const RUNS: u64 = 8;

fn render(integrator: &mut dyn Integrator, frames: u32) -> Vec<Vec3> {
    let mut film = Film::new(SIZE, SIZE);
    for sample in 0..frames {
        integrator.render_frame(&mut film, sample);
    }
    assert_eq!(film.dropped(), 0);
    film.mean()
}

fn vcm_family(algorithm: Algorithm, seed: u64) -> vcm::Vcm {
    let settings = VcmSettings {
        seed,
        // 1024 light paths a frame: merge within 2% of the scene radius.
        radius: MergeRadius::SceneFraction(0.02),
        ..common::vcm_settings(algorithm, SIZE, SIZE)
    };
    common::vcm(sds_scene(), settings)
}

#[test]
fn vcm_renders_a_caustic_seen_in_a_mirror_far_better_than_pt_and_bpt() {
    let reference = render(&mut vcm_family(Algorithm::Vcm, 1), 16 * FRAMES);
    let caustic = reference
        .iter()
        .map(|p| p.max_element())
        .fold(0.0, f32::max);
    assert!(caustic > 0.0, "the reference is black");
    let relmse = |image: &[Vec3]| compare(image, &reference).unwrap().relmse;
    // Mean relMSE over RUNS renders with seeds first, first + 1, …
    let mean_relmse = |first: u64, new: &dyn Fn(u64) -> Box<dyn Integrator>| {
        let runs = (first..first + RUNS).map(|seed| relmse(&render(new(seed).as_mut(), FRAMES)));
        runs.sum::<f64>() / RUNS as f64
    };
    let pt = mean_relmse(2, &|seed| {
        let settings = PtSettings {
            seed,
            ..common::pt_settings(SIZE, SIZE)
        };
        Box::new(common::path_tracer(sds_scene(), settings))
    });
    let bpt = mean_relmse(100, &|seed| Box::new(vcm_family(Algorithm::Bpt, seed)));
    let vcm = mean_relmse(200, &|seed| Box::new(vcm_family(Algorithm::Vcm, seed)));
    eprintln!(
        "mean relMSE of {RUNS} renders of {FRAMES} frames: PT {pt:.3e}, BPT {bpt:.3e}, VCM {vcm:.3e}"
    );
    // A VCM frame costs about twice a PT frame here; "far below" is ten times.
    assert!(vcm * 10.0 < pt, "VCM {vcm} vs PT {pt}");
    assert!(vcm * 10.0 < bpt, "VCM {vcm} vs BPT {bpt}");
}
