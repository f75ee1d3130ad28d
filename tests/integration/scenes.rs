//! The committed scenes in `scenes/` load and are what `examples/make_scenes.rs` promises.

use std::path::Path;

use glam::Vec3;
use vcm_rs::scene::light::Light;
use vcm_rs::scene::{Material, Scene};

fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn cornell_box_is_a_closed_room_lit_from_the_ceiling() {
    let scene = load("cornell-box.gltf");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.mesh.triangle_count(), 5 * 2 + 2 + 2 * 12);
    let f = scene.features;
    assert!(f.materials.diffuse && !f.materials.glossy && !f.materials.specular);
    assert!(!f.textures && !f.alpha_masks && !f.normal_maps);
    assert_eq!(f.lights.area, 2);
    // Every surface faces the inside of the room: from the center of the room (inside the
    // tall block's neighbourhood excluded) each wall and the light face toward the center.
    for t in 0..12 {
        let [a, b, c] = scene.mesh.corners(t);
        let centroid = (a + b + c) / 3.0;
        let n = scene.mesh.geometric_normal(t);
        assert!(
            n.dot(Vec3::ZERO - centroid) > 0.0,
            "triangle {t} faces away"
        );
    }
    for light in &scene.lights {
        let Light::Area(area) = light else {
            panic!("only area lights")
        };
        assert!(area.normal.y < -0.99, "the light shines downward");
        let center = area.corners.iter().sum::<Vec3>() / 3.0;
        assert!(scene.camera.raster_of(512, 512, center).is_some());
    }
    // The camera looks into the open side of the room.
    assert!(scene.camera.position.z > 1.0);
    assert!(scene.camera.forward.dot(-Vec3::Z) > 0.999);
}

#[test]
fn every_scene_loads_cleanly_with_the_features_its_name_promises() {
    let expect = [
        ("cornell-box.gltf", false, false),
        ("cornell-indirect.gltf", false, false),
        ("cornell-specular.gltf", true, true),
        ("cornell-specular-close.gltf", true, true),
        ("cornell-water.gltf", true, true),
        ("large.gltf", true, true),
    ];
    for (name, specular, transmission) in expect {
        let scene = load(name);
        assert!(scene.warnings.is_empty(), "{name}: {:?}", scene.warnings);
        assert_eq!(scene.dropped_triangles, 0, "{name}");
        let m = scene.features.materials;
        assert!(m.diffuse, "{name}");
        assert_eq!(
            (m.specular, m.transmission),
            (specular, transmission),
            "{name}"
        );
        assert_eq!(scene.features.lights.area, 2, "{name}");
    }
    assert!(load("large.gltf").mesh.triangle_count() >= 1_000_000);
}

#[test]
fn the_indirect_light_faces_the_ceiling_and_the_water_surface_faces_up() {
    for light in &load("cornell-indirect.gltf").lights {
        let Light::Area(area) = light else {
            panic!("only area lights")
        };
        assert!(area.normal.y > 0.99);
    }
    let water = load("cornell-water.gltf");
    let (water_material, surface) = triangles_of(&water, "water");
    assert!(!surface.is_empty());
    assert!(
        surface
            .iter()
            .all(|&t| water.mesh.geometric_normal(t).y > 0.5)
    );
    assert_eq!(water_material.ior, 1.33);
}

/// The material named `name` of `scene` and the triangles that have it.
fn triangles_of<'a>(scene: &'a Scene, name: &str) -> (&'a Material, Vec<usize>) {
    let index = scene.materials.iter().position(|m| m.name == name);
    let index = index.unwrap_or_else(|| panic!("no material {name}"));
    let triangles = (0..scene.mesh.triangle_count())
        .filter(|&t| scene.mesh.material_ids[t] as usize == index)
        .collect();
    (&scene.materials[index], triangles)
}

#[test]
fn the_point_light_scene_has_no_area_light_and_a_mirror_facing_down() {
    let scene = load("cornell-point.gltf");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let f = scene.features;
    assert!(f.materials.diffuse && f.materials.specular && f.materials.transmission);
    assert_eq!((f.lights.area, f.lights.point), (0, 1));
    let Light::Point(bulb) = &scene.lights[0] else {
        panic!("a point light")
    };
    // Above the glass sphere, below the mirror, inside the room and in view.
    assert!(bulb.position.y > 0.0 && bulb.position.y < 0.99);
    assert!(bulb.position.abs().max_element() < 1.0);
    assert!(scene.camera.raster_of(512, 512, bulb.position).is_some());
    let (_, faces) = triangles_of(&scene, "mirror");
    assert_eq!(faces.len(), 2);
    assert!(
        faces
            .iter()
            .all(|&t| scene.mesh.geometric_normal(t).y < -0.99)
    );
}
