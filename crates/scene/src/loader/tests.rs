//! Hostile scene files (issue 56): each must be refused quickly, with an error naming the
//! file and the problem, or loaded with what the specification allows, and never exhaust
//! memory or the stack, block, or read what is not the scene's.

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use super::{LoadOptions, load_gltf_from_bytes, load_gltf_from_bytes_with, load_with};
use crate::error::SceneError;
use crate::scene::Scene;
use crate::testing::{data_uri, doubling_chain, triangle_positions};

/// A document whose buffer 0 is `buffer` (a URI of 36 bytes, one triangle's positions) and
/// mesh 0 that triangle; `nodes`, `roots` and `extra` (properties after a comma) complete it.
fn document_with(buffer: &str, roots: &str, nodes: &str, extra: &str) -> String {
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": {roots}}}],
        "nodes": {nodes},
        "buffers": [{{"byteLength": 36, "uri": "{buffer}"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                        "min": [0, 0, 0], "max": [1, 1, 0]}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}] {extra}}}"#
    )
}

/// [`document_with`] the triangle embedded, drawn by node 0.
fn document(nodes: &str, extra: &str) -> String {
    document_with(&data_uri(&triangle_positions()), "[0]", nodes, extra)
}

fn load(json: &str) -> Result<Scene, SceneError> {
    load_gltf_from_bytes(Path::new("memory.gltf"), json.as_bytes())
}

/// Runs `work` on another thread and returns its result, or `None` when it takes longer than
/// `seconds` (the thread is left behind: the caller unblocks it).
fn within<T: Send + 'static>(seconds: u64, work: impl FnOnce() -> T + Send + 'static) -> Option<T> {
    let (sender, receiver) = mpsc::channel();
    std::thread::spawn(move || sender.send(work()));
    receiver.recv_timeout(Duration::from_secs(seconds)).ok()
}

#[test]
fn exponential_instancing_is_refused_before_it_is_expanded() {
    // 30 levels: 2²⁹ copies of the triangle in 700 bytes (the process used to abort).
    let started = std::time::Instant::now();
    let error = load(&document(&doubling_chain(30), "")).unwrap_err();
    assert!(matches!(error, SceneError::TooLarge { .. }), "{error}");
    let message = error.to_string();
    assert!(
        message.starts_with("memory.gltf: ")
            && message.contains("expands to 536870912 triangles")
            && message.contains("max_triangles 20000000"),
        "{message}"
    );
    assert!(started.elapsed() < Duration::from_secs(1));
    // Instancing within the limit is kept: 2¹¹ copies under a limit of 4096.
    let json = document(&doubling_chain(12), "");
    let options = |max_triangles| LoadOptions {
        max_triangles,
        ..LoadOptions::default()
    };
    let path = Path::new("memory.gltf");
    let scene = load_gltf_from_bytes_with(path, json.as_bytes(), &options(4096)).unwrap();
    assert_eq!(scene.mesh.triangle_count(), 2048);
    let error = load_gltf_from_bytes_with(path, json.as_bytes(), &options(2047)).unwrap_err();
    assert!(error.to_string().contains("2048 triangles"), "{error}");
    // Nodes without meshes cost a visit each: 2⁶⁹ of them are refused too.
    let empty = doubling_chain(70).replace(r#"{"mesh": 0}"#, "{}");
    let message = load(&document(&empty, "")).unwrap_err().to_string();
    assert!(
        message.contains("more than 2^64 node instances"),
        "{message}"
    );
    // A scene listing its root several times instances it that often.
    let twice = document_with(
        &data_uri(&triangle_positions()),
        "[0, 0]",
        r#"[{"mesh": 0}]"#,
        "",
    );
    assert_eq!(load(&twice).unwrap().mesh.triangle_count(), 2);
}

#[test]
fn cycles_are_errors() {
    let cyclic = r#"[{"mesh": 0, "children": [1]}, {"children": [2]}, {"children": [1]}]"#;
    let message = load(&document(cyclic, "")).unwrap_err().to_string();
    assert!(message.contains("has a cycle"), "{message}");
}

#[test]
fn a_chain_deeper_than_the_stack_is_walked_without_recursion() {
    // 20000 nested nodes (recursion overflowed the 8 MiB main stack at 10300), loaded on a
    // thread with a 1 MiB stack; the mesh at the bottom is moved by every level.
    let levels = 20_000;
    let mut nodes: Vec<String> = (1..levels)
        .map(|next| format!(r#"{{"children": [{next}], "translation": [0, 0, 1]}}"#))
        .collect();
    nodes.push(r#"{"mesh": 0}"#.into());
    let json = document(&format!("[{}]", nodes.join(", ")), "");
    let scene = std::thread::Builder::new()
        .stack_size(1 << 20)
        .spawn(move || load(&json))
        .unwrap()
        .join()
        .unwrap()
        .unwrap();
    assert_eq!(scene.mesh.triangle_count(), 1);
    assert_eq!(scene.mesh.positions[0].z, (levels - 1) as f32);
}

/// Makes a FIFO at `path` (not a regular file, like `/dev/zero`, and one whose opening
/// blocks until a writer comes).
#[cfg(unix)]
fn make_fifo(path: &Path) {
    let made = std::process::Command::new("mkfifo").arg(path).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo {}", path.display());
}

/// Loads `scene` on another thread; if that blocks (opening `fifo` to read), opens the FIFO
/// for writing to let it go on, and fails.
#[cfg(unix)]
fn load_without_blocking(scene: PathBuf, fifo: &Path) -> Result<Scene, SceneError> {
    let result = within(5, move || Scene::load(&scene));
    result.unwrap_or_else(|| {
        let _writer = std::fs::OpenOptions::new().write(true).open(fifo);
        panic!("loading blocked on the FIFO {}", fifo.display())
    })
}

#[cfg(unix)]
#[test]
fn buffers_images_and_scene_files_that_are_not_regular_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("zero.bin");
    make_fifo(&fifo);
    let scene = dir.path().join("scene.gltf");
    std::fs::write(
        &scene,
        document_with("zero.bin", "[0]", r#"[{"mesh": 0}]"#, ""),
    )
    .unwrap();
    let message = load_without_blocking(scene.clone(), &fifo)
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("scene.gltf")
            && message.contains("zero.bin")
            && message.contains("not a regular file"),
        "{message}"
    );
    // An image, and an environment map.
    let textured = document(
        r#"[{"mesh": 0}]"#,
        r#", "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "images": [{"uri": "zero.bin"}], "textures": [{"source": 0}]"#,
    )
    .replace(r#""attributes""#, r#""material": 0, "attributes""#);
    let sky = document(
        r#"[{"mesh": 0}]"#,
        r#", "extensionsUsed": ["VCM_environment"],
        "extensions": {"VCM_environment": {"image": "zero.bin"}}"#,
    );
    for json in [textured, sky] {
        std::fs::write(&scene, json).unwrap();
        let message = load_without_blocking(scene.clone(), &fifo)
            .unwrap_err()
            .to_string();
        assert!(message.contains("not a regular file"), "{message}");
    }
    // The scene file itself.
    let fifo_scene = dir.path().join("fifo.gltf");
    make_fifo(&fifo_scene);
    let error = load_without_blocking(fifo_scene.clone(), &fifo_scene).unwrap_err();
    assert!(matches!(error, SceneError::Io { .. }), "{error}");
    assert!(error.to_string().contains("not a regular file"), "{error}");
}

/// A scene folder `scene/` inside a temporary folder that also holds `secret.bin` (a valid
/// triangle buffer, 36 bytes) and `secret.png`, which the scene must not read by default.
fn folder_with_a_secret_beside() -> (tempfile::TempDir, PathBuf) {
    let root = tempfile::tempdir().unwrap();
    let scene = root.path().join("scene");
    std::fs::create_dir(&scene).unwrap();
    std::fs::write(root.path().join("secret.bin"), triangle_positions()).unwrap();
    std::fs::write(
        root.path().join("secret.png"),
        crate::testing::png_claiming(2, 1),
    )
    .unwrap();
    (root, scene)
}

#[test]
fn uris_are_confined_to_the_scene_folder_unless_allowed() {
    let (root, folder) = folder_with_a_secret_beside();
    let scene = folder.join("scene.gltf");
    let secret = root.path().join("secret.bin");
    let confined = LoadOptions::default();
    let open = LoadOptions {
        allow_outside_files: true,
        ..LoadOptions::default()
    };
    let nodes = r#"[{"mesh": 0}]"#;
    for uri in [
        "../secret.bin".to_string(),
        "%2E%2E/secret.bin".to_string(),
        secret.display().to_string(),
    ] {
        std::fs::write(&scene, document_with(&uri, "[0]", nodes, "")).unwrap();
        let error = load_with(&scene, &confined).unwrap_err();
        assert!(matches!(error, SceneError::OutsideFolder { .. }), "{error}");
        let message = error.to_string();
        assert!(
            message.contains("scene.gltf")
                && message.contains(&uri)
                && message.contains("outside the scene's folder")
                && !message.contains("36 bytes"),
            "{message}"
        );
        let scene = load_with(&scene, &open).unwrap();
        assert_eq!(scene.mesh.triangle_count(), 1);
    }
    // A file outside that is shorter than declared: the message says nothing of its size.
    let longer = document_with("../secret.bin", "[0]", nodes, "")
        .replace(r#""byteLength": 36, "uri""#, r#""byteLength": 4096, "uri""#);
    std::fs::write(&scene, longer).unwrap();
    let message = load_with(&scene, &confined).unwrap_err().to_string();
    assert!(message.contains("outside the scene's folder"), "{message}");
    let message = load_with(&scene, &open).unwrap_err().to_string();
    assert!(
        message.contains("shorter than the 4096 bytes declared") && !message.contains("36 bytes"),
        "{message}"
    );
    // Images too.
    let textured = document(
        nodes,
        r#", "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "images": [{"uri": "../secret.png"}], "textures": [{"source": 0}]"#,
    );
    std::fs::write(&scene, textured).unwrap();
    let error = load_with(&scene, &confined).unwrap_err();
    assert!(matches!(error, SceneError::OutsideFolder { .. }), "{error}");
    assert_eq!(load_with(&scene, &open).unwrap().textures.len(), 1);
}

#[test]
fn obj_libraries_and_textures_are_confined_to_the_scene_folder() {
    let (root, folder) = folder_with_a_secret_beside();
    std::fs::write(root.path().join("secret.mtl"), "newmtl red\nKd 1 0 0\n").unwrap();
    let obj = folder.join("scene.obj");
    let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n";
    std::fs::write(&obj, format!("mtllib ../secret.mtl\n{triangle}")).unwrap();
    let scene = Scene::load(&obj).unwrap();
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("outside the scene's folder")),
        "{:?}",
        scene.warnings
    );
    assert_eq!(scene.materials[0].name, "default");
    let open = LoadOptions {
        allow_outside_files: true,
        ..LoadOptions::default()
    };
    assert_eq!(load_with(&obj, &open).unwrap().materials[0].name, "red");

    std::fs::write(
        folder.join("scene.mtl"),
        "newmtl red\nmap_Kd ../secret.png\n",
    )
    .unwrap();
    std::fs::write(&obj, format!("mtllib scene.mtl\n{triangle}")).unwrap();
    let error = Scene::load(&obj).unwrap_err();
    assert!(matches!(error, SceneError::OutsideFolder { .. }), "{error}");
    assert_eq!(load_with(&obj, &open).unwrap().textures.len(), 1);
}

#[test]
fn image_headers_claiming_more_than_their_bytes_are_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.gltf");
    // An OpenEXR environment map of a few hundred bytes claiming 16384² texels (3 GB as
    // linear RGB, within the 2^28-texel bound on any image).
    let exr = crate::testing::exr_claiming(16384, 16384);
    std::fs::write(dir.path().join("sky.exr"), &exr).unwrap();
    let sky = document(
        r#"[{"mesh": 0}]"#,
        r#", "extensionsUsed": ["VCM_environment"],
        "extensions": {"VCM_environment": {"image": "sky.exr"}}"#,
    );
    std::fs::write(&scene, sky).unwrap();
    let message = Scene::load(&scene).unwrap_err().to_string();
    let claim = format!("16384 × 16384 texels, more than a {}-byte file", exr.len());
    assert!(
        message.contains("scene.gltf") && message.contains("sky.exr") && message.contains(&claim),
        "{message}"
    );
    // A PNG texture claiming 10000² texels in a hundred bytes (100 MB decoded).
    let png = crate::testing::png_claiming(10000, 10000);
    let textured = document(
        r#"[{"mesh": 0}]"#,
        &format!(
            r#", "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}}}}}],
            "images": [{{"uri": "{}"}}], "textures": [{{"source": 0}}]"#,
            data_uri(&png)
        ),
    );
    let message = load(&textured).unwrap_err().to_string();
    assert!(
        message.contains("10000 × 10000 texels, more than a"),
        "{message}"
    );
}

#[test]
fn declared_counts_beyond_the_data_are_refused_before_reading() {
    // NORMAL: a sparse accessor without a buffer view, declaring 2^26 normals (800 MB read)
    // for a triangle of three vertices.
    let sparse = r#""accessors": [{"bufferView": 0, "componentType": 5126, "count": 3,
        "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
        {"componentType": 5126, "count": 67108864, "type": "VEC3",
         "min": [0, 0, 0], "max": [1, 1, 0],
         "sparse": {"count": 1, "indices": {"bufferView": 0, "componentType": 5125},
                    "values": {"bufferView": 0}}}],"#;
    let json = document(r#"[{"mesh": 0}]"#, "")
        .replace(
            r#""accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                        "min": [0, 0, 0], "max": [1, 1, 0]}],"#,
            sparse,
        )
        .replace(
            r#""attributes": {"POSITION": 0}"#,
            r#""attributes": {"POSITION": 0, "NORMAL": 1}"#,
        );
    assert!(json.contains("67108864") && json.contains(r#""NORMAL": 1"#));
    let started = std::time::Instant::now();
    let message = load(&json).unwrap_err().to_string();
    assert!(
        message.contains("accessor 1 has 67108864 elements for 3 positions"),
        "{message}"
    );
    assert!(started.elapsed() < Duration::from_secs(1));
    // POSITION itself: 2^31 vertices, a triangle list of 715827882, refused before reading.
    let json = json
        .replace("67108864", "2147483648")
        .replace(r#""POSITION": 0, "NORMAL": 1"#, r#""POSITION": 1"#);
    let error = load(&json).unwrap_err();
    assert!(matches!(error, SceneError::TooLarge { .. }), "{error}");
    assert!(error.to_string().contains("715827882 triangles"), "{error}");
}

#[test]
fn out_of_range_material_factors_are_clamped_with_one_warning_per_material() {
    let materials = r#", "materials": [
        {"name": "wild", "pbrMetallicRoughness": {"baseColorFactor": [100, 0.5, -1, 1],
            "metallicFactor": -5, "roughnessFactor": -1},
         "emissiveFactor": [2, 0, 0],
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 5},
                        "KHR_materials_ior": {"ior": 0.5},
                        "KHR_materials_specular": {"specularFactor": 3,
                                                   "specularColorFactor": [-1, 2, 1]}}},
        {"pbrMetallicRoughness": {"roughnessFactor": 7}},
        {"name": "tame", "pbrMetallicRoughness": {"roughnessFactor": 0.5}}],
        "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior",
                           "KHR_materials_specular"]"#;
    let scene = load(&document(r#"[{"mesh": 0}]"#, materials)).unwrap();
    let wild = &scene.materials[0];
    assert_eq!(wild.base_color, glam::Vec4::new(1.0, 0.5, 0.0, 1.0));
    assert_eq!((wild.metallic, wild.roughness), (0.0, 0.0));
    assert_eq!(
        (wild.transmission, wild.ior, wild.specular),
        (1.0, 1.0, 1.0)
    );
    assert_eq!(wild.emission, glam::Vec3::X);
    // specularColorFactor has no upper bound in KHR_materials_specular.
    assert_eq!(wild.specular_color, glam::Vec3::new(0.0, 2.0, 1.0));
    assert_eq!(scene.materials[1].roughness, 1.0);
    assert_eq!(scene.materials[2].roughness, 0.5);
    let about = |name: &str| {
        scene
            .warnings
            .iter()
            .filter(|w| w.starts_with(&format!("memory.gltf: {name} has ")))
            .count()
    };
    assert_eq!(about("material 'wild'"), 1, "{:?}", scene.warnings);
    assert_eq!(about("material 1"), 1, "{:?}", scene.warnings);
    assert_eq!(about("material 'tame'"), 0, "{:?}", scene.warnings);
    let wild_warning = scene
        .warnings
        .iter()
        .find(|w| w.contains("'wild'"))
        .unwrap();
    for property in [
        "baseColorFactor",
        "metallicFactor",
        "roughnessFactor",
        "emissiveFactor",
        "transmissionFactor",
        "ior",
        "specularFactor",
        "specularColorFactor",
    ] {
        assert!(
            wild_warning.contains(property),
            "{property}: {wild_warning}"
        );
    }
}

#[test]
fn impossible_camera_aspect_ratios_are_errors_and_extreme_ones_are_ignored() {
    let with_aspect = |aspect: &str| {
        let nodes = r#"[{"mesh": 0}, {"camera": 0, "translation": [0, 0, 3]}]"#;
        let cameras = format!(
            r#", "cameras": [{{"type": "perspective",
                "perspective": {{"yfov": 0.8, "znear": 0.1, "aspectRatio": {aspect}}}}}]"#
        );
        let json = document(nodes, &cameras).replace(r#""nodes": [0]"#, r#""nodes": [0, 1]"#);
        load(&json)
    };
    for aspect in ["0", "-1.5", "1e39"] {
        let message = with_aspect(aspect).unwrap_err().to_string();
        assert!(
            message.starts_with("memory.gltf: ")
                && message.contains("camera 0 has aspectRatio")
                && message.contains("must be a finite number > 0"),
            "{aspect}: {message}"
        );
    }
    let thin = with_aspect("1e-6").unwrap();
    assert_eq!(thin.camera.aspect_ratio, None);
    assert!(
        thin.warnings
            .iter()
            .any(|w| w.contains("aspectRatio 0.000001")),
        "{:?}",
        thin.warnings
    );
    let wide = with_aspect("1.5").unwrap();
    assert_eq!(wide.camera.aspect_ratio, Some(1.5));
    assert!(wide.warnings.is_empty(), "{:?}", wide.warnings);
}

#[test]
fn vertices_too_far_out_are_named_as_such_not_as_degenerate() {
    let mut positions = triangle_positions();
    positions[12..16].copy_from_slice(&1e38f32.to_le_bytes());
    let json = document_with(&data_uri(&positions), "[0]", r#"[{"mesh": 0}]"#, "");
    let error = load(&json).unwrap_err();
    assert!(matches!(error, SceneError::Geometry { .. }), "{error}");
    let message = error.to_string();
    assert!(
        message.contains("vertex 1 has position")
            && message.contains("beyond the ±1e18")
            && !message.contains("degenerate"),
        "{message}"
    );
    // A transform can carry finite positions out of range too.
    let scaled = document(r#"[{"mesh": 0, "scale": [1e30, 1e30, 1]}]"#, "");
    let message = load(&scaled).unwrap_err().to_string();
    assert!(message.contains("beyond the ±1e18"), "{message}");
}

#[test]
fn validation_errors_say_invalid_gltf_once() {
    let json = document(r#"[{"mesh": 0}]"#, "").replace(r#""bufferView": 0"#, r#""bufferView": 9"#);
    let message = load(&json).unwrap_err().to_string();
    assert_eq!(message.matches("invalid glTF").count(), 1, "{message}");
    assert!(
        message.starts_with("memory.gltf: invalid glTF: "),
        "{message}"
    );
}

#[test]
fn textures_decode_each_image_once_within_the_texel_budget() {
    // Three textures of one 2 × 1 image (different samplers, both encodings), and one of a
    // second image: under a budget of 2 texels only the first image fits.
    let image = data_uri(&crate::testing::png_claiming(2, 1));
    let materials = |second: u32| {
        format!(
            r#", "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}},
                    "metallicRoughnessTexture": {{"index": 1}}}},
                "emissiveTexture": {{"index": {second}}}, "emissiveFactor": [1, 1, 1]}}],
            "images": [{{"uri": "{image}"}}, {{"uri": "{image}"}}],
            "samplers": [{{"magFilter": 9728}}],
            "textures": [{{"source": 0}}, {{"source": 0, "sampler": 0}}, {{"source": 0}},
                         {{"source": 1}}]"#
        )
    };
    let textured = |second| {
        document(r#"[{"mesh": 0}]"#, &materials(second))
            .replace(r#""attributes""#, r#""material": 0, "attributes""#)
    };
    let options = LoadOptions {
        max_texels: 2,
        ..LoadOptions::default()
    };
    let path = Path::new("memory.gltf");
    let shared = load_gltf_from_bytes_with(path, textured(2).as_bytes(), &options).unwrap();
    assert_eq!(shared.textures.len(), 3);
    let error = load_gltf_from_bytes_with(path, textured(3).as_bytes(), &options).unwrap_err();
    assert!(matches!(error, SceneError::TooLarge { .. }), "{error}");
    let message = error.to_string();
    assert!(
        message.contains("image 1 (data URI)") && message.contains("max_texels"),
        "{message}"
    );
}
