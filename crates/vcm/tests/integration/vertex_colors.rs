//! Vertex colors (glTF `COLOR_0`) multiply the base color: the Cornell box with its colors
//! moved from the materials onto the vertices renders the same image, bit for bit, with the
//! path tracer and with VCM (whose light paths rebuild BSDFs at cached vertices).

use glam::Vec3;
use vcm::{Algorithm, Film, Integrator, PtSettings, VcmSettings};
use vcm_scene::light::Light;
use vcm_scene::{Material, Scene};

use crate::common;

const SIZE: u32 = 32;
const FRAMES: u32 = 4;

/// `scene` with every material's base color replaced by white and `vertex_color(material)`
/// given to the vertices of its triangles instead.
fn recolored(scene: &Scene, vertex_color: impl Fn(&Material) -> Vec3) -> Scene {
    let mut mesh = scene.mesh.clone();
    let mut colors = vec![None; mesh.positions.len()];
    for (triangle, &material) in mesh.triangles.iter().zip(&mesh.material_ids) {
        let color = vertex_color(&scene.materials[material as usize]);
        for &vertex in triangle {
            let slot = &mut colors[vertex as usize];
            assert!(
                slot.is_none_or(|c| c == color),
                "vertex {vertex} has two colors"
            );
            *slot = Some(color);
        }
    }
    mesh.colors = colors.into_iter().map(|c| c.unwrap_or(Vec3::ONE)).collect();
    let materials = scene
        .materials
        .iter()
        .map(|m| Material {
            base_color: Vec3::ONE.extend(m.base_color.w),
            ..m.clone()
        })
        .collect();
    let punctual = scene
        .lights
        .iter()
        .filter(|light| !matches!(light, Light::Area(_)))
        .cloned()
        .collect();
    Scene::new(
        scene.path.clone(),
        mesh,
        materials,
        scene.textures.clone(),
        punctual,
        scene.camera,
        Vec::new(),
    )
}

/// The mean film of `FRAMES` frames of the path tracer (`None`) or `algorithm`.
fn render(scene: Scene, algorithm: Option<Algorithm>) -> Vec<Vec3> {
    let mut integrator: Box<dyn Integrator> = match algorithm {
        None => Box::new(common::path_tracer(
            scene,
            PtSettings {
                seed: 9,
                ..common::pt_settings(SIZE, SIZE)
            },
        )),
        Some(algorithm) => Box::new(common::vcm(
            scene,
            VcmSettings {
                seed: 9,
                ..common::vcm_settings(algorithm, SIZE, SIZE)
            },
        )),
    };
    let mut film = Film::new(SIZE, SIZE);
    for iteration in 0..FRAMES {
        integrator.render_frame(&mut film, iteration);
    }
    film.mean()
}

#[test]
fn colors_on_vertices_render_like_colors_on_materials() {
    let scene = common::scene_file("cornell-box.gltf");
    let tinted = recolored(&scene, |m| m.base_color.truncate());
    assert!(tinted.features.vertex_colors);
    assert!(tinted.material_lobes.iter().any(Option::is_none));
    // Without the colors the walls are white: the image must differ (else the test could
    // not see vertex colors being ignored).
    let white = recolored(&scene, |_| Vec3::ONE);
    assert!(!white.features.vertex_colors);
    for algorithm in [None, Some(Algorithm::Vcm)] {
        let expected = render(scene.clone(), algorithm);
        assert!(
            render(tinted.clone(), algorithm) == expected,
            "{algorithm:?}: vertex colors render differently from material colors"
        );
        assert!(
            render(white.clone(), algorithm) != expected,
            "{algorithm:?}: white walls render like coloured ones"
        );
    }
}
