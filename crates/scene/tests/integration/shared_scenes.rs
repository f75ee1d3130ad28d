//! Loads every third-party model under `../shared/scenes/` and checks what the loader found
//! against counts read from the files themselves (accessor counts, material and texture lists),
//! then checks that truncated and corrupted copies give errors, not panics.
//!
//! Expected triangle counts are the index accessor counts / 3 of every mesh instance reachable
//! from the default scene (for the OBJ: the number of `f` lines, all triangles); texture counts
//! are the distinct textures the materials use (occlusion maps are not loaded).

use std::path::{Path, PathBuf};

use vcm_scene::{Scene, SceneError};

fn shared_scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes")
}

struct Expected {
    file: &'static str,
    triangles: usize,
    materials: usize,
    textures: usize,
    area_lights: usize,
}

const MODELS: &[Expected] = &[
    Expected {
        file: "khronos-samples/AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf",
        triangles: 61,
        materials: 6,
        textures: 4,
        area_lights: 0,
    },
    Expected {
        file: "khronos-samples/Avocado/glTF/Avocado.gltf",
        triangles: 682,
        materials: 1,
        textures: 3,
        area_lights: 0,
    },
    Expected {
        file: "khronos-samples/MetalRoughSpheresNoTextures/glTF/MetalRoughSpheresNoTextures.gltf",
        triangles: 1_040_409,
        materials: 98,
        textures: 0,
        area_lights: 0,
    },
    Expected {
        file: "khronos-samples/NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf",
        triangles: 5240,
        materials: 1,
        textures: 3,
        area_lights: 0,
    },
    Expected {
        file: "khronos-samples/WaterBottle/glTF/WaterBottle.gltf",
        triangles: 4510,
        materials: 1,
        textures: 4,
        // Every triangle uses the one emissive material.
        area_lights: 4510,
    },
    Expected {
        file: "stanford-bunny/bunny.obj",
        triangles: 3674,
        materials: 0,
        textures: 0,
        area_lights: 0,
    },
];

fn load(file: &str) -> Scene {
    let path = shared_scenes().join(file);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn every_shared_model_loads_with_the_counts_in_its_file() {
    for expected in MODELS {
        let scene = load(expected.file);
        let name = expected.file;
        // Zero-area triangles are dropped and counted, never silently.
        assert_eq!(
            scene.mesh.triangle_count() + scene.dropped_triangles,
            expected.triangles,
            "{name}: triangles"
        );
        assert!(
            scene.dropped_triangles * 100 <= expected.triangles,
            "{name}: dropped"
        );
        // Loaders append one default material for primitives without one.
        assert_eq!(
            scene.materials.len(),
            expected.materials + 1,
            "{name}: materials"
        );
        assert_eq!(scene.textures.len(), expected.textures, "{name}: textures");
        let area_lights = scene.features.lights.area;
        assert_eq!(
            area_lights + scene.dropped_triangles.min(expected.area_lights),
            expected.area_lights,
            "{name}: area lights"
        );
        assert_eq!(scene.features.triangles, scene.mesh.triangle_count());
        assert!(!scene.features.bounds.is_empty(), "{name}: bounds");
    }
}

#[test]
fn features_describe_the_models() {
    let alpha = load(MODELS[0].file);
    assert!(alpha.features.alpha_masks && alpha.features.textures && alpha.features.normal_maps);
    assert!(
        alpha.warnings.iter().any(|w| w.contains("BLEND")),
        "{:?}",
        alpha.warnings
    );
    let spheres = load(MODELS[2].file);
    let f = spheres.features;
    assert!(!f.textures && !f.alpha_masks && !f.normal_maps);
    assert!(f.materials.glossy && f.materials.diffuse && f.materials.specular);
    let bunny = load(MODELS[5].file);
    assert!(bunny.features.materials.diffuse && !bunny.features.materials.glossy);
    assert_eq!(bunny.lights.len(), 0);
    let bottle = load(MODELS[4].file);
    assert!(bottle.light_sampler.sample(0.5).is_some());
}

/// Tangents generated where a file has none agree with the ones the Khronos mirror test was
/// authored with (MikkTSpace, glTF's convention): the same handedness w on every vertex of
/// its mirrored halves, and about the same direction.
#[test]
fn generated_tangents_match_the_authored_ones() {
    let scene = load(MODELS[3].file);
    let mut generated = scene.mesh.clone();
    generated.generate_tangents(0..generated.triangles.len());
    let used = generated.triangles.iter().flatten().map(|&i| i as usize);
    let (mut vertices, mut same_w, mut close) = (0, 0, 0);
    for i in used {
        let (authored, ours) = (scene.mesh.tangents[i], generated.tangents[i]);
        vertices += 1;
        same_w += usize::from(authored.w == ours.w);
        close += usize::from(authored.truncate().normalize().dot(ours.truncate()) > 0.9);
    }
    assert_eq!(same_w, vertices, "handedness");
    // Per-vertex averaging differs from MikkTSpace's at seams; most agree closely.
    assert!(
        close * 10 >= vertices * 9,
        "{close} of {vertices} within 26°"
    );
}

/// Copies a model's folder into a temporary directory so it can be damaged.
fn damaged_copy(file: &str) -> (tempfile::TempDir, PathBuf) {
    let source = shared_scenes().join(file);
    let dir = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(source.parent().unwrap()).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), dir.path().join(entry.file_name())).unwrap();
    }
    let copy = dir.path().join(source.file_name().unwrap());
    (dir, copy)
}

fn truncate(path: &Path, fraction: f64) {
    let bytes = std::fs::read(path).unwrap();
    let keep = (bytes.len() as f64 * fraction) as usize;
    std::fs::write(path, &bytes[..keep]).unwrap();
}

fn expect_error(path: &Path) -> SceneError {
    match Scene::load(path) {
        Ok(_) => panic!("{} loaded despite the damage", path.display()),
        Err(e) => {
            let message = e.to_string();
            assert!(message.contains(&path.display().to_string()), "{message}");
            e
        }
    }
}

#[test]
fn truncated_gltf_json_buffers_and_textures_are_errors() {
    for expected in MODELS.iter().filter(|m| m.file.ends_with(".gltf")) {
        let (_dir, copy) = damaged_copy(expected.file);
        truncate(&copy, 0.5);
        assert!(matches!(expect_error(&copy), SceneError::Gltf { .. }));

        let (dir, copy) = damaged_copy(expected.file);
        let bin = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| p.extension().is_some_and(|e| e == "bin"))
            .unwrap();
        truncate(&bin, 0.9);
        assert!(matches!(expect_error(&copy), SceneError::Gltf { .. }));

        if expected.textures > 0 {
            let (dir, copy) = damaged_copy(expected.file);
            for image in std::fs::read_dir(dir.path())
                .unwrap()
                .map(|e| e.unwrap().path())
            {
                if image.extension().is_some_and(|e| e == "png" || e == "jpg") {
                    truncate(&image, 0.3);
                }
            }
            let error = expect_error(&copy);
            assert!(matches!(error, SceneError::Texture { .. }), "{error}");
        }
    }
}

#[test]
fn missing_files_are_errors_naming_them() {
    let (dir, copy) = damaged_copy(MODELS[1].file);
    std::fs::remove_file(dir.path().join("Avocado_normal.png")).unwrap();
    let message = expect_error(&copy).to_string();
    assert!(message.contains("Avocado_normal.png"), "{message}");
    let missing = dir.path().join("nothing-here.gltf");
    assert!(matches!(expect_error(&missing), SceneError::Io { .. }));
    let unknown = dir.path().join("Avocado.bin");
    assert!(matches!(
        expect_error(&unknown),
        SceneError::UnknownFormat { .. }
    ));
}

#[test]
fn corrupted_obj_files_are_errors_or_load_what_is_there() {
    let (_dir, copy) = damaged_copy(MODELS[5].file);
    let text = std::fs::read_to_string(&copy).unwrap();
    let nan = text.replacen("v 1.301895 0.122622", "v NaN 0.122622", 1);
    std::fs::write(&copy, nan).unwrap();
    let message = expect_error(&copy).to_string();
    assert!(message.contains("non-finite"), "{message}");

    let out_of_range = format!("{text}\nf 1 2 99999\n");
    std::fs::write(&copy, out_of_range).unwrap();
    expect_error(&copy);

    // A cut in the middle of the file: either an error or a smaller mesh, never a panic.
    for fraction in [0.1, 0.37, 0.5, 0.93] {
        let keep = (text.len() as f64 * fraction) as usize;
        std::fs::write(&copy, &text.as_bytes()[..keep]).unwrap();
        if let Ok(scene) = Scene::load(&copy) {
            assert!(scene.mesh.triangle_count() < MODELS[5].triangles);
        }
    }
}
