//! Small hand-written glTF documents exercising the conventions: transforms and winding,
//! cameras, punctual lights, material extensions and bad input.

use std::f32::consts::PI;
use std::path::Path;

use base64::Engine;
use glam::{Vec2, Vec3};
use vcm_scene::bsdf::TransportMode;
use vcm_scene::light::Light;
use vcm_scene::loader::load_gltf_from_bytes;
use vcm_scene::{Scene, SceneError};

/// One triangle in the z = 0 plane, counter-clockwise seen from +Z, as an embedded buffer.
fn triangle_buffer() -> String {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let bytes: Vec<u8> = positions.iter().flat_map(|f| f.to_le_bytes()).collect();
    let data = base64::engine::general_purpose::STANDARD.encode(bytes);
    format!(
        r#""buffers": [{{"byteLength": 36, "uri": "data:application/octet-stream;base64,{data}"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                        "min": [0,0,0], "max": [1,1,0]}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "material": 0}}]}}]"#
    )
}

fn document(nodes: &str, materials: &str, extra: &str) -> String {
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
        "nodes": {nodes}, "materials": {materials}, {} {extra}}}"#,
        triangle_buffer()
    )
}

const MATTE: &str = r#"[{"pbrMetallicRoughness": {"metallicFactor": 0}}]"#;

fn load(json: &str) -> Result<Scene, SceneError> {
    load_gltf_from_bytes(Path::new("memory.gltf"), json.as_bytes())
}

#[test]
fn node_transforms_place_geometry_and_mirroring_flips_the_winding() {
    let moved = load(&document(
        r#"[{"mesh": 0, "translation": [0, 0, 5]}]"#,
        MATTE,
        "",
    ))
    .unwrap();
    assert_eq!(moved.mesh.geometric_normal(0), Vec3::Z);
    assert_eq!(moved.mesh.corners(0)[1], Vec3::new(1.0, 0.0, 5.0));

    let nested =
        r#"[{"children": [1], "scale": [2, 2, 2]}, {"mesh": 0, "translation": [1, 0, 0]}]"#;
    let scene = load(&document(nested, MATTE, "")).unwrap();
    assert_eq!(scene.mesh.corners(0)[1], Vec3::new(4.0, 0.0, 0.0));

    // Mirroring in x leaves the triangle facing +Z, but reverses its winding order as seen
    // from +Z: the loader must swap it back (negative determinant rule).
    let mirrored = load(&document(
        r#"[{"mesh": 0, "scale": [-1, 1, 1]}]"#,
        MATTE,
        "",
    ))
    .unwrap();
    assert_eq!(mirrored.mesh.geometric_normal(0), Vec3::Z);
}

#[test]
fn the_first_camera_and_punctual_lights_are_read() {
    let nodes = r#"[{"children": [1, 2, 3, 4]},
        {"mesh": 0},
        {"camera": 0, "translation": [0, 0, 3]},
        {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 2, 0]},
        {"extensions": {"KHR_lights_punctual": {"light": 1}}, "rotation": [-0.7071068, 0, 0, 0.7071068]}]"#;
    let extra = r#", "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "intensity": 10, "color": [1, 0.5, 0.25]},
            {"type": "directional", "intensity": 3}]}}"#;
    let scene = load(&document(nodes, MATTE, extra)).unwrap();
    assert_eq!(scene.camera.position, Vec3::new(0.0, 0.0, 3.0));
    assert_eq!(scene.camera.yfov, 0.5);
    assert!((scene.camera.forward - -Vec3::Z).length() < 1e-6);
    assert_eq!(scene.lights.len(), 2);
    let Light::Point(point) = &scene.lights[0] else {
        panic!("not a point light")
    };
    assert_eq!(point.position, Vec3::new(0.0, 2.0, 0.0));
    assert_eq!(point.intensity, Vec3::new(10.0, 5.0, 2.5));
    let Light::Directional(sun) = &scene.lights[1] else {
        panic!("not directional")
    };
    // Rotating -90° about x turns the node's -Z into -Y: the light shines downward.
    assert!(
        (sun.direction - -Vec3::Y).length() < 1e-5,
        "{}",
        sun.direction
    );
    assert_eq!(sun.irradiance, Vec3::splat(3.0));
    let f = scene.features;
    assert_eq!(
        (f.lights.point, f.lights.directional, f.lights.area),
        (1, 1, 0)
    );
}

/// Nodes placing an orthographic camera (skipped with a warning), then "Front" at z = 3,
/// "Side" (its node "SideNode") at x = 4 and "Front" again at z = 6, all unnamed ones aside.
fn four_placed_cameras() -> Scene {
    let nodes = r#"[{"children": [1, 2, 3, 4, 5]},
        {"mesh": 0},
        {"camera": 2, "translation": [0, 0, 9]},
        {"camera": 0, "translation": [0, 0, 3]},
        {"camera": 1, "name": "SideNode", "translation": [4, 0, 0],
         "rotation": [0, 0.7071068, 0, 0.7071068]},
        {"camera": 0, "translation": [0, 0, 6]}]"#;
    let extra = r#", "cameras": [
        {"type": "perspective", "name": "Front", "perspective": {"yfov": 0.5, "znear": 0.1}},
        {"type": "perspective", "name": "Side", "perspective": {"yfov": 0.7, "znear": 0.1}},
        {"type": "orthographic", "name": "Plan",
         "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}}]"#;
    load(&document(nodes, MATTE, extra)).unwrap()
}

#[test]
fn every_placed_perspective_camera_is_listed_and_the_first_is_used() {
    let scene = four_placed_cameras();
    let listed: Vec<String> = scene.cameras.iter().map(ToString::to_string).collect();
    assert_eq!(
        listed,
        ["0 'Front'", "1 'Side' (node 'SideNode')", "0 'Front'"]
    );
    assert_eq!(scene.camera, scene.cameras[0].camera);
    assert_eq!(scene.camera.position, Vec3::new(0.0, 0.0, 3.0));
    assert!(
        scene.warnings.iter().any(|w| w.contains("orthographic")),
        "{:?}",
        scene.warnings
    );
}

#[test]
fn another_camera_is_chosen_by_index_or_name() {
    for choice in ["1", "Side", "SideNode"] {
        let mut scene = four_placed_cameras();
        scene.use_camera(choice).unwrap();
        assert_eq!(scene.camera.position, Vec3::new(4.0, 0.0, 0.0), "{choice}");
        assert_eq!(scene.camera.yfov, 0.7);
        // Turned 90° about +Y, the node's -Z is -X: the camera looks back at the origin.
        assert!((scene.camera.forward - -Vec3::X).length() < 1e-6);
    }
    // A camera that two nodes place: the first placement.
    let mut scene = four_placed_cameras();
    scene.use_camera("Side").unwrap();
    scene.use_camera("0").unwrap();
    assert_eq!(scene.camera.position, Vec3::new(0.0, 0.0, 3.0));
}

#[test]
fn a_camera_that_is_not_there_is_an_error_listing_those_that_are() {
    // Index 2 is the orthographic camera, which is not supported; 3 does not exist.
    for choice in ["2", "3", "Plan", "front"] {
        let mut scene = four_placed_cameras();
        let error = scene.use_camera(choice).unwrap_err().to_string();
        assert_eq!(
            error,
            format!(
                "memory.gltf: no camera '{choice}': the file's cameras are 0 'Front', \
                 1 'Side' (node 'SideNode'), 0 'Front'"
            )
        );
        assert_eq!(scene.camera.position, Vec3::new(0.0, 0.0, 3.0));
    }
    let mut no_cameras = load(&document(r#"[{"mesh": 0}]"#, MATTE, "")).unwrap();
    let error = no_cameras.use_camera("0").unwrap_err().to_string();
    assert_eq!(
        error,
        "memory.gltf: no camera '0': the file places no perspective camera"
    );
}

#[test]
fn material_extensions_map_to_the_material_model() {
    let materials = r#"[{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1],
            "metallicFactor": 0, "roughnessFactor": 0},
        "emissiveFactor": [1, 0.5, 0],
        "extensions": {
            "KHR_materials_emissive_strength": {"emissiveStrength": 4},
            "KHR_materials_transmission": {"transmissionFactor": 1},
            "KHR_materials_ior": {"ior": 1.33},
            "KHR_materials_volume": {"thicknessFactor": 0.1},
            "KHR_materials_specular": {"specularFactor": 0.5}}}]"#;
    let scene = load(&document(r#"[{"mesh": 0}]"#, materials, "")).unwrap();
    let m = &scene.materials[0];
    assert_eq!(m.emission, Vec3::new(4.0, 2.0, 0.0));
    assert_eq!((m.transmission, m.ior, m.specular), (1.0, 1.33, 0.5));
    assert!(!m.thin_walled);
    assert_eq!(scene.features.lights.area, 1);
    assert!(scene.features.materials.transmission && scene.features.materials.specular);
    let light = scene.emission_on_hit(0, 0.2, 0.2, -Vec3::Z).unwrap();
    assert_eq!(light.radiance, Vec3::new(4.0, 2.0, 0.0));
    // One-sided emission: nothing leaves the back face.
    assert!(scene.emission_on_hit(0, 0.2, 0.2, Vec3::Z).is_none());
    let point = scene.surface_point(0, 0.25, 0.25);
    assert_eq!(point.uv, Vec2::ZERO);
}

/// `KHR_materials_volume` attenuation is Beer–Lambert absorption inside a solid:
/// σ = −ln(attenuationColor) / attenuationDistance; a thin-walled surface has no inside, and
/// a distance that is not positive is an error naming the material.
#[test]
fn volume_attenuation_is_an_absorption_coefficient() {
    let glass = |volume: &str| {
        format!(
            r#"[{{"name": "tinted", "pbrMetallicRoughness": {{"metallicFactor": 0}},
            "extensions": {{"KHR_materials_transmission": {{"transmissionFactor": 1}},
                "KHR_materials_volume": {volume}}}}}]"#
        )
    };
    let solid = r#"{"thicknessFactor": 1, "attenuationColor": [1, 0.5, 0.25],
        "attenuationDistance": 2}"#;
    let scene = load(&document(r#"[{"mesh": 0}]"#, &glass(solid), "")).unwrap();
    let m = &scene.materials[0];
    assert!(m.bounds_volume());
    let expected = Vec3::new(0.0, 2.0f32.ln() / 2.0, 4.0f32.ln() / 2.0);
    assert!(
        (m.absorption - expected).abs().max_element() < 1e-6,
        "{}",
        m.absorption
    );
    assert!(scene.features.absorbing_volumes);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);

    let clear = r#"{"thicknessFactor": 1}"#;
    let scene = load(&document(r#"[{"mesh": 0}]"#, &glass(clear), "")).unwrap();
    assert_eq!(scene.materials[0].absorption, Vec3::ZERO);
    assert!(!scene.features.absorbing_volumes);

    let thin = r#"{"attenuationColor": [0.5, 0.5, 0.5], "attenuationDistance": 1}"#;
    let scene = load(&document(r#"[{"mesh": 0}]"#, &glass(thin), "")).unwrap();
    assert!(scene.materials[0].thin_walled && !scene.features.absorbing_volumes);

    let bad = r#"{"thicknessFactor": 1, "attenuationDistance": 0}"#;
    let error = load(&document(r#"[{"mesh": 0}]"#, &glass(bad), "")).unwrap_err();
    assert!(error.to_string().contains("tinted"), "{error}");
}

#[test]
fn bad_documents_are_errors_not_panics() {
    let cases = [
        ("not json", "{ this is not json"),
        (
            "cyclic nodes",
            r#"[{"mesh": 0, "children": [1]}, {"children": [0]}]"#,
        ),
        (
            "NaN transform",
            r#"[{"mesh": 0, "translation": [0, 1e39, 0]}]"#,
        ),
    ];
    for (what, nodes) in cases {
        let json = if what == "not json" {
            nodes.to_string()
        } else {
            document(nodes, MATTE, "")
        };
        let error = load(&json)
            .err()
            .unwrap_or_else(|| panic!("{what}: loaded"));
        assert!(error.to_string().contains("memory.gltf"), "{what}: {error}");
    }
    let required = r#", "extensionsUsed": ["KHR_draco_mesh_compression"],
        "extensionsRequired": ["KHR_draco_mesh_compression"]"#;
    let error = load(&document(r#"[{"mesh": 0}]"#, MATTE, required)).unwrap_err();
    assert!(
        error.to_string().contains("KHR_draco_mesh_compression"),
        "{error}"
    );
    // An ior below 1 is outside the extension's range: clamped to 1, with a warning.
    let bad_ior = r#"[{"extensions": {"KHR_materials_ior": {"ior": 0.5}}}]"#;
    let scene = load(&document(r#"[{"mesh": 0}]"#, bad_ior, "")).unwrap();
    assert_eq!(scene.materials[0].ior, 1.0);
    let warned = scene.warnings.iter().any(|w| w.contains("ior 0.5 (now 1)"));
    assert!(warned, "{:?}", scene.warnings);
}

/// An image needs a `uri` or a `bufferView`, and one in a buffer view needs a `mimeType`
/// (glTF 2.0 §5.18); files without them (found by fuzzing) are errors naming the image.
#[test]
fn images_without_a_source_are_errors() {
    let textured = r#"[{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]"#;
    let cases = [
        (
            "no source",
            r#"[{"name": "lost"}]"#,
            "neither a uri nor a bufferView",
        ),
        ("no mime type", r#"[{"bufferView": 0}]"#, "needs a mimeType"),
    ];
    for (what, images, reason) in cases {
        let extra = format!(r#", "textures": [{{"source": 0}}], "images": {images}"#);
        let error = load(&document(r#"[{"mesh": 0}]"#, textured, &extra))
            .err()
            .unwrap_or_else(|| panic!("{what}: loaded"))
            .to_string();
        assert!(
            error.contains("memory.gltf") && error.contains("image 0") && error.contains(reason),
            "{what}: {error}"
        );
    }
}

#[test]
fn a_scene_without_camera_is_framed_from_plus_z() {
    let scene = load(&document(r#"[{"mesh": 0}]"#, MATTE, "")).unwrap();
    assert_eq!(scene.camera.forward, -Vec3::Z);
    assert!(scene.camera.position.z > 0.0);
    assert!((scene.camera.yfov - 45f32.to_radians()).abs() < 1e-6);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

/// `KHR_materials_specular` and `KHR_materials_transmission` textures multiply their
/// factors: the specular texture by its alpha, the specular colour texture (sRGB) by its RGB,
/// the transmission texture by its red channel.
#[test]
fn specular_and_transmission_textures_multiply_their_factors() {
    let dir = tempfile::tempdir().unwrap();
    // Left texel: red 0, green 188 (sRGB for 0.50 linear), blue 0, alpha 0; right: all 255.
    let mut layers = image::RgbaImage::from_pixel(2, 1, image::Rgba([255, 255, 255, 255]));
    layers.put_pixel(0, 0, image::Rgba([0, 188, 0, 0]));
    layers.save(dir.path().join("layers.png")).unwrap();
    let materials = r#"[{"pbrMetallicRoughness": {"metallicFactor": 0},
        "extensions": {
            "KHR_materials_specular": {"specularFactor": 0.8, "specularTexture": {"index": 0},
                "specularColorFactor": [1, 0.5, 1], "specularColorTexture": {"index": 0}},
            "KHR_materials_transmission": {"transmissionFactor": 0.6,
                "transmissionTexture": {"index": 0}}}}]"#;
    let extra = r#", "images": [{"uri": "layers.png"}], "samplers": [{"magFilter": 9728}],
        "textures": [{"source": 0, "sampler": 0}],
        "extensionsUsed": ["KHR_materials_specular", "KHR_materials_transmission"]"#;
    let json = document(r#"[{"mesh": 0}]"#, materials, extra);
    let scene = load_gltf_from_bytes(&dir.path().join("scene.gltf"), json.as_bytes()).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let material = &scene.materials[0];
    assert!(material.uniform_bsdf_params().is_none());
    let at = |u| material.bsdf_params(&scene.textures, Vec2::new(u, 0.5));
    let (left, right) = (at(0.25), at(0.75));
    assert_eq!((left.specular, right.specular), (0.0, 0.8));
    assert_eq!((left.transmission, right.transmission), (0.0, 0.6));
    assert_eq!(right.specular_color, Vec3::new(1.0, 0.5, 1.0));
    let expected = Vec3::new(0.0, 0.25, 0.0);
    assert!(
        (left.specular_color - expected).abs().max_element() < 0.003,
        "{}",
        left.specular_color
    );
    // Somewhere transmissive, somewhere diffuse: both lobe classes are present.
    let classes = scene.features.materials;
    assert!(classes.transmission && classes.diffuse && scene.features.textures);
}

/// A triangle whose TEXCOORD_0 is (0.25, 0.5) at every corner and TEXCOORD_1 (0.75, 0.5),
/// textured with `columns.png` (black left, white right, sampled nearest) by `material`.
fn two_uv_sets(dir: &Path, material: &str) -> Scene {
    let floats: [f32; 21] = [
        0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, // positions
        0.25, 0.5, 0.25, 0.5, 0.25, 0.5, // TEXCOORD_0
        0.75, 0.5, 0.75, 0.5, 0.75, 0.5, // TEXCOORD_1
    ];
    let bytes: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
    let data = base64::engine::general_purpose::STANDARD.encode(bytes);
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
        "nodes": [{{"mesh": 0}}], "materials": [{material}],
        "buffers": [{{"byteLength": 84, "uri": "data:application/octet-stream;base64,{data}"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 36}},
            {{"buffer": 0, "byteOffset": 36, "byteLength": 24}},
            {{"buffer": 0, "byteOffset": 60, "byteLength": 24}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "min": [0,0,0], "max": [1,1,0]}},
            {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}},
            {{"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1,
            "TEXCOORD_1": 2}}, "material": 0}}]}}],
        "images": [{{"uri": "columns.png"}}], "samplers": [{{"magFilter": 9728}}],
        "textures": [{{"source": 0, "sampler": 0}}],
        "extensionsUsed": ["KHR_texture_transform"]}}"#
    );
    load_gltf_from_bytes(&dir.join("scene.gltf"), json.as_bytes()).unwrap()
}

/// A material whose textures use TEXCOORD_1 (`texCoord`, or the texture transform's
/// override) looks them up there; one whose textures mix sets keeps those on the base
/// color's set and says so.
#[test]
fn textures_on_the_second_texture_coordinate_set_look_up_there() {
    let dir = tempfile::tempdir().unwrap();
    let mut columns = image::RgbaImage::from_pixel(2, 1, image::Rgba([0, 0, 0, 255]));
    columns.put_pixel(1, 0, image::Rgba([255, 255, 255, 255]));
    columns.save(dir.path().join("columns.png")).unwrap();
    let base_color = |scene: &Scene| {
        let point = scene.surface_point(0, 0.3, 0.3);
        scene.materials[0]
            .bsdf_params(&scene.textures, point.uv)
            .base_color
            .x
    };
    let set_0 = r#"{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}"#;
    let set_1 = r#"{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1}}}"#;
    let transformed = r#"{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
        "extensions": {"KHR_texture_transform": {"texCoord": 1}}}}}"#;
    for (material, white) in [(set_0, false), (set_1, true), (transformed, true)] {
        let scene = two_uv_sets(dir.path(), material);
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        assert_eq!(
            base_color(&scene),
            if white { 1.0 } else { 0.0 },
            "{material}"
        );
    }
    let mixed = r#"{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1}},
        "emissiveFactor": [1, 1, 1], "emissiveTexture": {"index": 0}}"#;
    let scene = two_uv_sets(dir.path(), mixed);
    assert_eq!(base_color(&scene), 1.0);
    assert_eq!(scene.materials[0].emissive_texture, None);
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("only those on set 1")),
        "{:?}",
        scene.warnings
    );
}

/// Morph targets and skins would change the image; they are not supported, so each is
/// reported once, naming the file.
#[test]
fn unsupported_geometry_features_are_warned_once() {
    let triangle = r#""attributes": {"POSITION": 0}"#;
    let extended = r#""attributes": {"POSITION": 0}, "targets": [{"POSITION": 0}]"#;
    let nodes = r#"[{"children": [1, 2]}, {"mesh": 0, "skin": 0}, {"mesh": 0}]"#;
    let json =
        document(nodes, MATTE, r#", "skins": [{"joints": [0]}]"#).replace(triangle, extended);
    let scene = load(&json).unwrap();
    for feature in ["morph targets", "skinning"] {
        let warnings = scene.warnings.iter().filter(|w| w.contains(feature));
        let named: Vec<_> = warnings
            .filter(|w| w.starts_with("memory.gltf: "))
            .collect();
        assert_eq!(named.len(), 1, "{feature}: {:?}", scene.warnings);
    }
    let plain = load(&document(r#"[{"mesh": 0}]"#, MATTE, "")).unwrap();
    assert!(plain.warnings.is_empty(), "{:?}", plain.warnings);
}

/// A sampler's filters choose between nearest-texel and bilinear lookups (mipmaps aside); one
/// that mixes them is filtered bilinearly and reported.
#[test]
fn sampler_filters_choose_nearest_or_bilinear_lookups() {
    let dir = tempfile::tempdir().unwrap();
    // Black left column, white right column.
    let mut columns = image::RgbaImage::from_pixel(2, 2, image::Rgba([0, 0, 0, 255]));
    columns.put_pixel(1, 0, image::Rgba([255, 255, 255, 255]));
    columns.put_pixel(1, 1, image::Rgba([255, 255, 255, 255]));
    columns.save(dir.path().join("columns.png")).unwrap();
    let material = r#"[{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]"#;
    let load_with = |sampler: &str| {
        let extra = format!(
            r#", "images": [{{"uri": "columns.png"}}], "samplers": [{{{sampler}}}],
            "textures": [{{"source": 0, "sampler": 0}}]"#
        );
        let json = document(r#"[{"mesh": 0}]"#, material, &extra);
        let path = dir.path().join("scene.gltf");
        load_gltf_from_bytes(&path, json.as_bytes()).unwrap()
    };
    // Between the columns' centers, 0.1 texel into the black one: bilinear filtering
    // interpolates the decoded (linear) values 0 and 1 there at 0.4.
    let lookup = |scene: &Scene| {
        let uv = Vec2::new(0.45, 0.5);
        scene.materials[0]
            .bsdf_params(&scene.textures, uv)
            .base_color
            .x
    };
    let warned = |scene: &Scene| scene.warnings.iter().any(|w| w.contains("nearest"));
    let (nearest, bilinear) = (0.0, 0.4);
    for (sampler, expected) in [
        (r#""magFilter": 9728"#, nearest),
        (r#""minFilter": 9984"#, nearest),
        (r#""magFilter": 9728, "minFilter": 9986"#, nearest),
        (r#""magFilter": 9729, "minFilter": 9987"#, bilinear),
        (r#""wrapS": 33071"#, bilinear),
        // Mixed: the magnification filter decides (texels larger than a pixel show it).
        (r#""magFilter": 9728, "minFilter": 9729"#, nearest),
        (r#""magFilter": 9728, "minFilter": 9987"#, nearest),
        (r#""magFilter": 9729, "minFilter": 9984"#, bilinear),
    ] {
        let scene = load_with(sampler);
        assert!(!warned(&scene), "{sampler}: {:?}", scene.warnings);
        let value = lookup(&scene);
        assert!(
            (value - expected).abs() < 0.01,
            "{sampler}: {value} != {expected}"
        );
    }
}

/// `KHR_texture_transform` moves, rotates and scales where a texture is looked up, for every
/// texture of a material; a malformed one is an error naming the file.
#[test]
fn texture_transforms_move_the_lookup() {
    let dir = tempfile::tempdir().unwrap();
    // Top row red, green; bottom row blue, white (glTF's v runs down the image).
    let mut quad = image::RgbaImage::new(2, 2);
    quad.put_pixel(0, 0, image::Rgba([255, 0, 0, 255]));
    quad.put_pixel(1, 0, image::Rgba([0, 255, 0, 255]));
    quad.put_pixel(0, 1, image::Rgba([0, 0, 255, 255]));
    quad.put_pixel(1, 1, image::Rgba([255, 255, 255, 255]));
    quad.save(dir.path().join("quad.png")).unwrap();
    let load_with = |transform: &str| {
        let material = format!(
            r#"[{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0,
                "extensions": {{"KHR_texture_transform": {transform}}}}}}},
                "normalTexture": {{"index": 0,
                "extensions": {{"KHR_texture_transform": {transform}}}}}}}]"#
        );
        let extra = r#", "images": [{"uri": "quad.png"}], "textures": [{"source": 0}],
            "extensionsUsed": ["KHR_texture_transform"]"#;
        let json = document(r#"[{"mesh": 0}]"#, &material, extra);
        load_gltf_from_bytes(&dir.path().join("scene.gltf"), json.as_bytes())
    };
    let base_color = |scene: &Scene, uv: Vec2| {
        let material = &scene.materials[0];
        material.bsdf_params(&scene.textures, uv).base_color
    };
    let red_corner = Vec2::new(0.25, 0.25);

    let shifted = load_with(r#"{"offset": [0.5, 0]}"#).unwrap();
    assert!(shifted.warnings.is_empty(), "{:?}", shifted.warnings);
    assert_eq!(base_color(&shifted, red_corner), Vec3::new(0.0, 1.0, 0.0));
    // The normal map reads the same texel: green is +y in tangent space.
    let normal = shifted.materials[0].tangent_space_normal(&shifted.textures, red_corner);
    let green = Vec3::new(-1.0, 1.0, -1.0).normalize();
    assert!(normal.unwrap().abs_diff_eq(green, 1e-6), "{normal:?}");

    // A quarter turn: uv' = (v, −u) + offset, so the top-left quadrant's center (0.25,
    // 0.25) reads the bottom-left texel.
    let turned = load_with(r#"{"rotation": 1.5707964, "offset": [0, 1]}"#).unwrap();
    assert!(base_color(&turned, red_corner).abs_diff_eq(Vec3::Z, 1e-5));

    let untransformed = load_with("{}").unwrap();
    assert_eq!(base_color(&untransformed, red_corner), Vec3::X);

    let error = load_with(r#"{"scale": [2]}"#).unwrap_err().to_string();
    assert!(
        error.contains("scene.gltf") && error.contains("`scale`"),
        "{error}"
    );
}

/// The triangle of [`document`] with `COLOR_0` from `colors` (12 bytes: three RGBA corners,
/// normalized unsigned bytes) on a second mesh, drawn by node 1 beside the plain mesh 0.
fn colored_document(colors: [u8; 12], materials: &str) -> String {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let mut bytes: Vec<u8> = positions.iter().flat_map(|f| f.to_le_bytes()).collect();
    bytes.extend(colors);
    let data = base64::engine::general_purpose::STANDARD.encode(bytes);
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0, 1]}}],
        "nodes": [{{"mesh": 0}}, {{"mesh": 1, "translation": [0, 0, 1]}}],
        "materials": {materials},
        "buffers": [{{"byteLength": 48, "uri": "data:application/octet-stream;base64,{data}"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 36}},
                        {{"buffer": 0, "byteOffset": 36, "byteLength": 12}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                        "min": [0,0,0], "max": [1,1,0]}},
                      {{"bufferView": 1, "componentType": 5121, "normalized": true,
                        "count": 3, "type": "VEC4"}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "material": 0}}]}},
                   {{"primitives": [{{"attributes": {{"POSITION": 0, "COLOR_0": 1}},
                                      "material": 0}}]}}]}}"#
    )
}

/// Pure Lambertian, albedo 0.5.
const GREY: &str = r#"[{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1],
    "metallicFactor": 0}, "extensions": {"KHR_materials_specular": {"specularFactor": 0}}}]"#;

/// `COLOR_0` multiplies the base color (glTF 2.0 §3.9.2): linear (bytes are not sRGB
/// decoded), interpolated across the triangle, white on primitives without it.
#[test]
fn vertex_colors_multiply_the_base_color() {
    // Corners: red, green at 51/255 = 0.2, blue.
    let colors = [255, 0, 0, 255, 0, 51, 0, 255, 0, 0, 255, 255];
    let scene = load(&colored_document(colors, GREY)).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert!(scene.features.vertex_colors);
    assert!(
        scene.material_lobes[0].is_none(),
        "tinted: lobes at every hit"
    );
    let expected = Vec3::new(0.25, 0.2 * 0.25, 0.5);
    let point = scene.surface_point(1, 0.25, 0.5);
    assert!(
        (point.vertex_color - expected).length() < 1e-6,
        "{}",
        point.vertex_color
    );
    // A Lambertian BSDF at normal incidence: f·cos = albedo / π, albedo = 0.5 × color.
    let bsdf = scene.bsdf(&point);
    let f = bsdf.eval(Vec3::Z, Vec3::Z, TransportMode::Radiance).f_cos;
    let albedo = 0.5 * expected;
    assert!((f * PI - albedo).length() < 1e-5, "{f} vs {albedo}");
    let plain = scene.surface_point(0, 0.25, 0.5);
    assert_eq!(plain.vertex_color, Vec3::ONE);
    let f = scene
        .bsdf(&plain)
        .eval(Vec3::Z, Vec3::Z, TransportMode::Radiance);
    assert!((f.f_cos * PI - Vec3::splat(0.5)).length() < 1e-5);

    // All-white colors change nothing: none are kept, the lobes stay built once.
    let white = load(&colored_document([255; 12], GREY)).unwrap();
    assert!(white.mesh.colors.is_empty() && !white.features.vertex_colors);
    assert!(white.material_lobes[0].is_some());
}

/// Vertex alpha would cut out masked surfaces, which the traversal does not do: reported.
/// Integer colors must be normalized.
#[test]
fn vertex_color_alpha_on_masks_is_warned_and_bad_colors_are_errors() {
    let masked = r#"[{"alphaMode": "MASK", "pbrMetallicRoughness": {"metallicFactor": 0}}]"#;
    let half_alpha = [255, 255, 255, 128, 255, 255, 255, 255, 255, 255, 255, 255];
    let scene = load(&colored_document(half_alpha, masked)).unwrap();
    let warned: Vec<_> = scene
        .warnings
        .iter()
        .filter(|w| w.starts_with("memory.gltf: mesh 1 primitive 0: COLOR_0 alpha"))
        .collect();
    assert_eq!(warned.len(), 1, "{:?}", scene.warnings);
    let opaque = load(&colored_document(half_alpha, GREY)).unwrap();
    assert!(opaque.warnings.is_empty(), "{:?}", opaque.warnings);

    let json = colored_document([255; 12], GREY).replace(r#""normalized": true,"#, "");
    let message = load(&json).unwrap_err().to_string();
    assert!(
        message.contains("memory.gltf") && message.contains("not normalized"),
        "{message}"
    );
}

/// `VCM_environment` (the renderer's own extension) adds a constant sky around the scene;
/// a malformed one is an error naming the file and the property.
#[test]
fn the_environment_extension_adds_a_sky() {
    let extra = r#", "extensionsUsed": ["VCM_environment"],
        "extensions": {"VCM_environment": {"color": [0.5, 1, 2], "strength": 2}}"#;
    let scene = load(&document(r#"[{"mesh": 0}]"#, MATTE, extra)).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.features.lights.environment, 1);
    let Some(Light::Environment(sky)) = scene.lights.last() else {
        panic!("no environment: {:?}", scene.lights)
    };
    assert_eq!(sky.radiance, Vec3::new(1.0, 2.0, 4.0));
    assert_eq!(sky.scene_radius, scene.features.bounds.radius());
    let (index, seen) = scene.emission_on_escape(Vec3::Z).unwrap();
    assert_eq!(
        (index, seen.radiance),
        (scene.lights.len() - 1, sky.radiance)
    );

    let bad = extra.replace("\"strength\": 2", "\"strength\": -2");
    let message = load(&document(r#"[{"mesh": 0}]"#, MATTE, &bad))
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("memory.gltf") && message.contains("`strength`"),
        "{message}"
    );
    let plain = load(&document(r#"[{"mesh": 0}]"#, MATTE, "")).unwrap();
    assert!(plain.emission_on_escape(Vec3::Z).is_none());
}

/// `VCM_environment` with an `image`: an equirectangular OpenEXR or Radiance HDR file beside
/// the scene (told apart by content: the HDR files are named `.exr` too), scaled by color ·
/// strength; a missing image, or one in neither format, is an error naming it.
#[test]
fn the_environment_extension_reads_an_equirectangular_image() {
    let dir = tempfile::tempdir().unwrap();
    // 4 × 2: the top row (the upper hemisphere) red, green, blue, white from left to right
    // (values RGBE stores exactly).
    let texel = |x: usize, y: usize| match (x, y) {
        (0, 0) => (1.0, 0.0, 0.0),
        (1, 0) => (0.0, 1.0, 0.0),
        (2, 0) => (0.0, 0.0, 1.0),
        (3, 0) => (1.0, 1.0, 1.0),
        _ => (0.0, 0.0, 0.0),
    };
    let write_exr = |path: &std::path::Path| {
        exr::prelude::write_rgb_file(path, 4, 2, |x, y| {
            let (r, g, b) = texel(x, y);
            (r as f32, g as f32, b as f32)
        })
        .unwrap()
    };
    let write_hdr = |path: &std::path::Path| {
        let pixels: Vec<_> = (0..8)
            .map(|i| {
                let (r, g, b) = texel(i % 4, i / 4);
                image::Rgb([r as f32, g as f32, b as f32])
            })
            .collect();
        let file = std::fs::File::create(path).unwrap();
        image::codecs::hdr::HdrEncoder::new(file)
            .encode(&pixels, 4, 2)
            .unwrap()
    };
    let extra = r#", "extensionsUsed": ["VCM_environment"],
        "extensions": {"VCM_environment": {"strength": 2, "image": "sky.exr"}}"#;
    let gltf = dir.path().join("scene.gltf");
    std::fs::write(&gltf, document(r#"[{"mesh": 0}]"#, MATTE, extra)).unwrap();
    // Radiance files open with `#?RADIANCE` (the image crate's encoder) or `#?RGBE`.
    let write_rgbe = |path: &std::path::Path| {
        write_hdr(path);
        let bytes = std::fs::read(path).unwrap();
        let body = bytes.strip_prefix(b"#?RADIANCE".as_slice()).unwrap();
        std::fs::write(path, [b"#?RGBE".as_slice(), body].concat()).unwrap();
    };
    for write in [
        &write_exr as &dyn Fn(&std::path::Path),
        &write_hdr,
        &write_rgbe,
    ] {
        write(&dir.path().join("sky.exr"));
        let scene = Scene::load(&gltf).unwrap();
        // Up and toward -Z is the second quarter of the top row; up and toward +X the third.
        let up = |d: Vec3| (d + Vec3::Y).normalize();
        let seen = |d: Vec3| scene.emission_on_escape(up(d)).unwrap().1.radiance;
        assert_eq!(seen(-Vec3::Z), Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(seen(Vec3::X), Vec3::new(0.0, 0.0, 2.0));
        assert_eq!(
            scene.emission_on_escape(-Vec3::Y).unwrap().1.radiance,
            Vec3::ZERO
        );
    }

    let refused = |bytes: &[u8], reason: &str| {
        std::fs::write(dir.path().join("sky.exr"), bytes).unwrap();
        let message = Scene::load(&gltf).unwrap_err().to_string();
        assert!(
            message.contains("scene.gltf")
                && message.contains("'sky.exr'")
                && message.contains(reason),
            "{message}"
        );
    };
    refused(b"P3 4 2 255", "neither an OpenEXR nor a Radiance HDR image");
    // A header claiming 40000² texels (19 GB as linear RGB) is refused before any allocation.
    refused(
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 40000 +X 40000\n\x02\x02\x01\x00",
        "40000 × 40000 texels, more than the",
    );
    std::fs::remove_file(dir.path().join("sky.exr")).unwrap();
    let message = Scene::load(&gltf).unwrap_err().to_string();
    assert!(
        message.contains("scene.gltf") && message.contains("'sky.exr'"),
        "{message}"
    );
}
