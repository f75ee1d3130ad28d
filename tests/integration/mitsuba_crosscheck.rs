//! Cross-check against an independent renderer: Mitsuba 3 renders the same glTF files, read by
//! `tools/mitsuba_reference.py` into its own plugins, and `vcm render` must give the same
//! images up to noise. This checks the scene conventions (units, one-sided emitters, Fresnel,
//! GGX roughness, thin sheets, tinted transmission, absorbing solids, punctual lights, the
//! environment, the camera, the box pixel filter, glossy highlights of small lights, sRGB
//! base colour and emissive textures with their UV orientation, filter and wrap, alpha-masked
//! cut-outs, mirrored nodes, one- and double-sided surfaces)
//! against a renderer that references come from, not against this renderer's own idea of them.
//!
//! Needs `python3` with the packages of `tools/requirements.txt`. Without them the test is
//! skipped with a message, unless `VCM_REQUIRE_MITSUBA=1` (set by `.ci/run`): then it fails.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::{Quat, Vec3};
use serde_json::{Value, json};
use vcm::image_io::RgbImage;

/// Image size (wider than high, so that the file's square aspect ratio must give way to the
/// output's and `yfov` stays the vertical field of view), samples per pixel and independent
/// renders per renderer.
const WIDTH: usize = 64;
const HEIGHT: usize = 48;
const SPP: u32 = 128;
const RENDERS: u64 = 6;
/// Pixels per side of the blocks whose means are compared.
const BLOCK: usize = 8;
/// Relative size of rounding differences between the two renderers' block means, counted
/// as noise where a block has none (an image differing by 10⁻³ still has t = 100 there).
const ROUNDING: f64 = 1e-5;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn python() -> String {
    std::env::var("VCM_PYTHON").unwrap_or_else(|_| "python3".into())
}

/// Why Mitsuba cannot run here, if it cannot.
fn mitsuba_missing() -> Option<String> {
    let probe = Command::new(python())
        .args(["-c", "import mitsuba, numpy"])
        .output();
    match probe {
        Ok(out) if out.status.success() => None,
        Ok(out) => Some(format!(
            "{} cannot import mitsuba and numpy: {}",
            python(),
            String::from_utf8_lossy(&out.stderr).trim()
        )),
        Err(e) => Some(format!("{} does not run: {e}", python())),
    }
}

fn load_scene(name: &str) -> Value {
    let path = root().join("scenes").join(format!("{name}.gltf"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    serde_json::from_str(&text).unwrap()
}

fn material<'a>(doc: &'a mut Value, name: &str) -> &'a mut Value {
    doc["materials"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|m| m["name"] == name)
        .unwrap_or_else(|| panic!("no material {name}"))
}

fn use_extension(doc: &mut Value, name: &str) {
    doc["extensionsUsed"]
        .as_array_mut()
        .unwrap()
        .push(json!(name));
}

/// cornell-specular with a rough mirror and rough, tinted solid glass.
fn rough() -> Value {
    let mut doc = load_scene("cornell-specular");
    material(&mut doc, "mirror")["pbrMetallicRoughness"]["roughnessFactor"] = json!(0.3);
    let glass = &mut material(&mut doc, "glass")["pbrMetallicRoughness"];
    glass["roughnessFactor"] = json!(0.25);
    glass["baseColorFactor"] = json!([0.9, 0.7, 0.5, 1.0]);
    doc
}

/// cornell-specular with a rough coloured conductor (copper-like F0, r = 0.3) as its mirror.
fn rough_copper() -> Value {
    let mut doc = load_scene("cornell-specular");
    let mirror = &mut material(&mut doc, "mirror")["pbrMetallicRoughness"];
    mirror["roughnessFactor"] = json!(0.3);
    mirror["baseColorFactor"] = json!([0.95, 0.64, 0.54, 1.0]);
    doc
}

/// cornell-specular with the glass as a tinted thin-walled sheet (no volume).
fn thin_sheet() -> Value {
    let mut doc = load_scene("cornell-specular");
    let glass = material(&mut doc, "glass");
    glass["extensions"]
        .as_object_mut()
        .unwrap()
        .remove("KHR_materials_volume");
    glass["pbrMetallicRoughness"]["baseColorFactor"] = json!([0.9, 0.6, 0.4, 1.0]);
    doc
}

/// cornell-specular with the glass sphere absorbing inside (`KHR_materials_volume`
/// attenuation: Mitsuba renders it as a homogeneous medium that only absorbs).
fn absorbing_glass() -> Value {
    let mut doc = load_scene("cornell-specular");
    let volume = &mut material(&mut doc, "glass")["extensions"]["KHR_materials_volume"];
    volume["attenuationColor"] = json!([0.9, 0.4, 0.2]);
    volume["attenuationDistance"] = json!(0.3);
    doc
}

/// The Cornell box lit by a point light, a tilted directional light through its open side
/// and a constant environment, its area light switched off.
fn punctual_lights() -> Value {
    let mut doc = load_scene("cornell-box");
    material(&mut doc, "light")["emissiveFactor"] = json!([0.0, 0.0, 0.0]);
    use_extension(&mut doc, "KHR_lights_punctual");
    use_extension(&mut doc, "VCM_environment");
    doc["extensions"] = json!({
        "KHR_lights_punctual": {"lights": [
            {"type": "point", "intensity": 2.5, "color": [1.0, 0.9, 0.8]},
            {"type": "directional", "intensity": 1.5, "color": [0.8, 0.9, 1.0]}
        ]},
        "VCM_environment": {"color": [0.2, 0.3, 0.5], "strength": 0.8}
    });
    let sun =
        Quat::from_rotation_y(20f32.to_radians()) * Quat::from_rotation_x(-25f32.to_radians());
    let first = doc["nodes"].as_array().unwrap().len();
    let nodes = doc["nodes"].as_array_mut().unwrap();
    nodes.push(json!({"name": "bulb", "translation": [0.3, 0.75, 0.1],
                      "extensions": {"KHR_lights_punctual": {"light": 0}}}));
    nodes.push(json!({"name": "sun", "rotation": sun.to_array(),
                      "extensions": {"KHR_lights_punctual": {"light": 1}}}));
    let roots = doc["scenes"][0]["nodes"].as_array_mut().unwrap();
    roots.extend([json!(first), json!(first + 1)]);
    doc
}

/// The float values of accessor `index`, from a buffer held as a base64 data URI.
fn accessor_floats(doc: &Value, index: &Value) -> Vec<f32> {
    use base64::Engine;
    let accessor = &doc["accessors"][index.as_u64().unwrap() as usize];
    let view = &doc["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
    let uri = doc["buffers"][view["buffer"].as_u64().unwrap() as usize]["uri"]
        .as_str()
        .unwrap();
    let bytes = base64::engine::general_purpose::STANDARD
        .decode(uri.split_once(',').unwrap().1)
        .unwrap();
    let start = (view["byteOffset"].as_u64().unwrap_or(0)
        + accessor["byteOffset"].as_u64().unwrap_or(0)) as usize;
    let width = match accessor["type"].as_str().unwrap() {
        "VEC2" => 2,
        "VEC3" => 3,
        other => panic!("accessor type {other}"),
    };
    let count = accessor["count"].as_u64().unwrap() as usize * width;
    bytes[start..start + 4 * count]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect()
}

/// The Cornell box with a 5 × 4 texel poster (sRGB PNG `poster.png`, written to `dir`)
/// covering its back wall, repeated across it (u from −0.3 to 2.2, v from 0.1 to 1.6), read
/// through a sampler with the glTF filter and wrap codes given: the wall's base colour, or
/// with `glowing` its emission (on the white wall), then once across the wall (u and v from
/// 0 to 1).
fn poster(dir: &Path, filter: u32, wrap: u32, glowing: bool) -> Value {
    let texels: [[u8; 3]; 20] = [
        [230, 20, 20],
        [20, 200, 40],
        [30, 30, 220],
        [240, 240, 240],
        [10, 10, 10],
        [250, 200, 0],
        [120, 60, 200],
        [0, 180, 180],
        [200, 100, 50],
        [60, 60, 60],
        [90, 200, 90],
        [250, 250, 120],
        [20, 20, 20],
        [180, 30, 120],
        [255, 255, 255],
        [40, 40, 160],
        [160, 160, 160],
        [230, 120, 0],
        [10, 90, 30],
        [200, 0, 80],
    ];
    image::RgbImage::from_raw(5, 4, texels.concat())
        .unwrap()
        .save(dir.join("poster.png"))
        .unwrap();

    let mut doc = load_scene("cornell-box");
    let back = doc["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .position(|m| m["name"] == "back")
        .unwrap();
    let positions = accessor_floats(
        &doc,
        &doc["meshes"][back]["primitives"][0]["attributes"]["POSITION"],
    );
    let uvs: Vec<u8> = positions
        .chunks_exact(3)
        .flat_map(|p| {
            let (u, v) = ((p[0] + 1.0) / 2.0, (1.0 - p[1]) / 2.0);
            // Mitsuba samples a textured emitter through its UV map, which must cover the
            // unit square once.
            if glowing {
                [u, v]
            } else {
                [u * 2.5 - 0.3, v * 1.5 + 0.1]
            }
        })
        .flat_map(f32::to_le_bytes)
        .collect();
    let accessor = push_accessor(
        &mut doc,
        &uvs,
        json!({"componentType": 5126, "count": uvs.len() / 8, "type": "VEC2"}),
    );
    let material = push(
        &mut doc,
        "materials",
        if glowing {
            json!({
                "name": "glowing poster",
                "pbrMetallicRoughness": {"baseColorFactor": [0.725, 0.71, 0.68, 1.0],
                                         "metallicFactor": 0.0, "roughnessFactor": 1.0},
                "emissiveTexture": {"index": 0}, "emissiveFactor": [1.0, 1.0, 1.0],
                "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}
            })
        } else {
            json!({
                "name": "poster",
                "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                         "metallicFactor": 0.0, "roughnessFactor": 1.0},
                "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}
            })
        },
    );
    let primitive = &mut doc["meshes"][back]["primitives"][0];
    primitive["attributes"]["TEXCOORD_0"] = json!(accessor);
    primitive["material"] = json!(material);
    doc["samplers"] =
        json!([{"magFilter": filter, "minFilter": filter, "wrapS": wrap, "wrapT": wrap}]);
    doc["images"] = json!([{"uri": "poster.png"}]);
    doc["textures"] = json!([{"source": 0, "sampler": 0}]);
    doc
}

/// The Cornell box lit only by a hard-edged spot light (cones 0.005 rad apart) near the
/// ceiling, aimed down at the back right.
fn spot() -> Value {
    let mut doc = load_scene("cornell-box");
    material(&mut doc, "light")["emissiveFactor"] = json!([0.0, 0.0, 0.0]);
    use_extension(&mut doc, "KHR_lights_punctual");
    doc["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "spot", "intensity": 6.0, "color": [1.0, 0.8, 0.6],
         "spot": {"innerConeAngle": 0.35, "outerConeAngle": 0.355}}
    ]}});
    let aim = Quat::from_rotation_arc(-Vec3::Z, Vec3::new(0.4, -1.0, -0.3).normalize());
    let node = push(
        &mut doc,
        "nodes",
        json!({
            "name": "spot", "translation": [-0.4, 0.9, 0.1], "rotation": aim.to_array(),
            "extensions": {"KHR_lights_punctual": {"light": 0}}
        }),
    );
    doc["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!(node));
    doc
}

/// Appends `bytes` as a new base64 buffer with one view; returns the view's index.
fn push_buffer_view(doc: &mut Value, bytes: &[u8]) -> usize {
    use base64::Engine;
    let buffer = doc["buffers"].as_array().unwrap().len();
    doc["buffers"].as_array_mut().unwrap().push(json!({
        "byteLength": bytes.len(),
        "uri": format!("data:application/octet-stream;base64,{}",
                       base64::engine::general_purpose::STANDARD.encode(bytes))
    }));
    let view = doc["bufferViews"].as_array().unwrap().len();
    doc["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({"buffer": buffer, "byteLength": bytes.len()}));
    view
}

/// Appends `bytes` as a new buffer and view, and `accessor` (all but its `bufferView`) over
/// them; returns the accessor's index.
fn push_accessor(doc: &mut Value, bytes: &[u8], mut accessor: Value) -> usize {
    accessor["bufferView"] = json!(push_buffer_view(doc, bytes));
    push(doc, "accessors", accessor)
}

/// Makes the scene's root nodes those of `doc`'s nodes whose name `keep` accepts (every node of
/// the scenes used here is a root).
fn keep_nodes(doc: &mut Value, keep: impl Fn(&str) -> bool) {
    let nodes: Vec<usize> = (0..doc["nodes"].as_array().unwrap().len())
        .filter(|&i| keep(doc["nodes"][i]["name"].as_str().unwrap_or("")))
        .collect();
    doc["scenes"][0]["nodes"] = json!(nodes);
}

/// Appends `value` to the array `doc[key]`; returns its index.
fn push(doc: &mut Value, key: &str, value: Value) -> usize {
    let array = doc[key].as_array_mut().unwrap();
    array.push(value);
    array.len() - 1
}

/// The Cornell box with a white panel between the camera and the blocks, tilted so that the
/// face the camera sees is lit from the ceiling; the panel's front (counter-clockwise) face
/// looks away from the camera. One-sided, the camera sees its black back; double-sided, the
/// lit face.
fn panel(double_sided: bool) -> Value {
    let normal = Vec3::new(0.0, -0.5, -0.87).normalize();
    quad(
        Vec3::new(0.1, 0.05, 0.35),
        normal,
        (0.35, 0.3),
        double_sided,
    )
}

/// The Cornell box with a white rectangle named "panel" added (see [`add_quad`]).
fn quad(centre: Vec3, normal: Vec3, half_sizes: (f32, f32), double_sided: bool) -> Value {
    let mut doc = load_scene("cornell-box");
    let material = json!({
        "name": "panel", "doubleSided": double_sided,
        "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0],
                                 "metallicFactor": 0.0, "roughnessFactor": 1.0},
        "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}
    });
    add_quad(&mut doc, "panel", (centre, normal, half_sizes), material);
    doc
}

/// Adds to `doc` a rectangle named `name` of the glTF material `material`: `half_sizes` along
/// x and along `normal` × x from `centre`, its front (counter-clockwise) face towards
/// `normal`.
fn add_quad(doc: &mut Value, name: &str, placement: (Vec3, Vec3, (f32, f32)), material: Value) {
    let (centre, normal, half_sizes) = placement;
    let (u, v) = (Vec3::X * half_sizes.0, normal.cross(Vec3::X) * half_sizes.1);
    // Counter-clockwise seen from the side `normal` points to: (u × v) ∥ normal.
    let corners = [
        centre - u - v,
        centre + u - v,
        centre + u + v,
        centre - u + v,
    ];
    let (min, max) = corners
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), c| {
            (lo.min(*c), hi.max(*c))
        });
    let positions: Vec<u8> = corners
        .iter()
        .flat_map(|c| c.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let indices: Vec<u8> = [0u32, 1, 2, 0, 2, 3]
        .into_iter()
        .flat_map(u32::to_le_bytes)
        .collect();
    let position = push_accessor(
        doc,
        &positions,
        json!({
            "componentType": 5126, "count": 4, "type": "VEC3",
            "min": min.to_array(), "max": max.to_array()
        }),
    );
    let index = push_accessor(
        doc,
        &indices,
        json!({"componentType": 5125, "count": 6, "type": "SCALAR"}),
    );
    let material = push(doc, "materials", material);
    let mesh = push(
        doc,
        "meshes",
        json!({"name": name, "primitives": [
            {"attributes": {"POSITION": position}, "indices": index, "material": material}
        ]}),
    );
    let node = push(doc, "nodes", json!({"name": name, "mesh": mesh}));
    doc["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!(node));
}

/// Veach's multiple importance sampling scene (Veach 1997, fig. 9.8) in the Cornell box, its
/// blocks removed and its light off: four white metal plates of GGX α = 0.005, 0.02, 0.05 and
/// 0.1, each tilted to reflect a row of four square lights toward the camera. The lights have
/// equal power and sides from 0.01 to 0.3: small bright ones on sharp plates are light
/// sampling's weak case, large ones on rough plates BSDF sampling's.
fn mis_plates() -> Value {
    let mut doc = load_scene("cornell-box");
    material(&mut doc, "light")["emissiveFactor"] = json!([0.0, 0.0, 0.0]);
    keep_nodes(&mut doc, |name| {
        !["tall block", "short block"].contains(&name)
    });
    let camera = Vec3::new(0.0, 0.0, 3.9);
    let lights = Vec3::new(0.0, 0.7, -0.8);
    for (i, alpha) in [0.005f32, 0.02, 0.05, 0.1].into_iter().enumerate() {
        let centre = Vec3::new(0.0, -0.75 + 0.3 * i as f32, 0.4 - 0.3 * i as f32);
        let normal = ((camera - centre).normalize() + (lights - centre).normalize()).normalize();
        let plate = json!({
            "name": format!("plate {i}"),
            "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                                     "metallicFactor": 1.0, "roughnessFactor": alpha.sqrt()}
        });
        add_quad(&mut doc, "plate", (centre, normal, (0.75, 0.1)), plate);
    }
    let colours = [
        [1.0, 0.4, 0.4],
        [0.4, 1.0, 0.4],
        [0.4, 0.4, 1.0],
        [1.0, 1.0, 0.6],
    ];
    for (i, (half, colour)) in [0.005f32, 0.015, 0.05, 0.15]
        .into_iter()
        .zip(colours)
        .enumerate()
    {
        let centre = Vec3::new(-0.6 + 0.4 * i as f32, 0.7, -0.8);
        let normal = (Vec3::new(0.0, -0.4, 0.3) - centre).normalize();
        let lamp = json!({
            "name": format!("lamp {i}"), "emissiveFactor": colour,
            "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0],
                                     "metallicFactor": 0.0, "roughnessFactor": 1.0},
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 0.2 / (half * half)},
                           "KHR_materials_specular": {"specularFactor": 0.0}}
        });
        add_quad(&mut doc, "lamp", (centre, normal, (half, half)), lamp);
    }
    doc
}

/// A double-sided ceiling below the light, cut out by an alpha mask: a 4 × 4 texel RGBA
/// texture (`mask.png`, written to `dir`, sampled nearest) whose alpha is 0 or 1 per texel,
/// across it once. The light reaches the room only through the holes (shadow rays and light
/// paths pass the cut-outs), the camera sees the light and the ceiling through them.
fn masked_panel(dir: &Path) -> Value {
    let holes = [[1, 0, 1, 1], [0, 1, 0, 1], [1, 1, 0, 0], [1, 0, 1, 1]];
    let colours = [
        [230u8, 40, 40],
        [40, 200, 60],
        [240, 240, 240],
        [60, 60, 220],
    ];
    let texels: Vec<u8> = (0..16)
        .flat_map(|i| {
            let [r, g, b] = colours[i % 4];
            [r, g, b, if holes[i / 4][i % 4] == 1 { 255 } else { 0 }]
        })
        .collect();
    image::RgbaImage::from_raw(4, 4, texels)
        .unwrap()
        .save(dir.join("mask.png"))
        .unwrap();

    let mut doc = quad(Vec3::new(0.0, 0.7, 0.0), Vec3::NEG_Y, (0.8, 0.8), true);
    // The panel's corners run (−u, −v), (u, −v), (u, v), (−u, v); glTF's v runs down the image.
    let uvs: Vec<u8> = [[0.0f32, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]
        .into_iter()
        .flatten()
        .flat_map(f32::to_le_bytes)
        .collect();
    let accessor = push_accessor(
        &mut doc,
        &uvs,
        json!({"componentType": 5126, "count": 4, "type": "VEC2"}),
    );
    let panel = doc["meshes"].as_array().unwrap().len() - 1;
    doc["meshes"][panel]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(accessor);
    let material = material(&mut doc, "panel");
    material["alphaMode"] = json!("MASK");
    material["pbrMetallicRoughness"]["baseColorFactor"] = json!([1.0, 1.0, 1.0, 1.0]);
    material["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    doc["samplers"] = json!([{"magFilter": 9728, "minFilter": 9728}]);
    doc["images"] = json!([{"uri": "mask.png"}]);
    doc["textures"] = json!([{"source": 0, "sampler": 0}]);
    doc
}

/// The Cornell box with every mesh node mirrored (scale −1 along x, the camera untouched):
/// glTF turns the winding order of a mirrored node around, so the walls and the light still
/// face the room.
fn mirrored() -> Value {
    let mut doc = load_scene("cornell-box");
    for node in doc["nodes"].as_array_mut().unwrap() {
        if node.get("mesh").is_some() {
            node["scale"] = json!([-1.0, 1.0, 1.0]);
        }
    }
    doc
}

/// cornell-water, camera included, under a parent node that scales it by 10⁴, turns it and
/// moves it 4·10⁴ units away.
fn scaled_water() -> Value {
    let mut doc = load_scene("cornell-water");
    let roots = doc["scenes"][0]["nodes"].take();
    let turn = Quat::from_rotation_y(0.7);
    let parent = doc["nodes"].as_array().unwrap().len();
    doc["nodes"].as_array_mut().unwrap().push(json!({
        "name": "world", "scale": [1e4, 1e4, 1e4], "translation": [3e4, -2e4, 1e4],
        "rotation": turn.to_array(), "children": roots
    }));
    doc["scenes"][0]["nodes"] = json!([parent]);
    doc
}

/// The Cornell box's floor and blocks (no walls, no light) under an equirectangular sky
/// (`sky.exr`, 64 × 32 pixels, written to `dir`): one colour for 30° either side of the
/// horizon, where the camera sees it (Mitsuba's envmap interpolates between its pixels, the
/// renderer keeps them constant, so the sky seen directly must not change there), a gradient
/// up to the zenith, a darker ground and a soft sun 50° up toward +X and −Z, whose shadows
/// tell a mirrored or turned map apart.
fn open_sky(dir: &Path) -> Value {
    let (width, height) = (64, 32);
    let sun = Vec3::new(1.0, 0.0, -1.0).normalize() * 50f32.to_radians().cos()
        + Vec3::Y * 50f32.to_radians().sin();
    let pixels = (0..width * height)
        .map(|i| {
            // The direction through the pixel's centre (the README's mapping).
            let (u, v) = ((i % width) as f32 + 0.5, (i / width) as f32 + 0.5);
            let phi = (u / width as f32 - 0.5) * std::f32::consts::TAU;
            let theta = v / height as f32 * std::f32::consts::PI;
            let direction = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            let elevation = std::f32::consts::FRAC_PI_2 - theta;
            let band = 30f32.to_radians();
            let sky = if elevation > band {
                Vec3::new(0.3, 0.5, 1.0) * (1.0 + (elevation - band))
            } else if elevation < -band {
                Vec3::new(0.25, 0.2, 0.15)
            } else {
                Vec3::new(0.3, 0.5, 1.0)
            };
            let angle = direction.dot(sun).clamp(-1.0, 1.0).acos();
            sky + Vec3::new(40.0, 36.0, 30.0) * (-(angle / 0.12).powi(2)).exp()
        })
        .collect();
    let map = RgbImage {
        width,
        height,
        pixels,
    };
    map.write_exr(&dir.join("sky.exr")).unwrap();

    let mut doc = load_scene("cornell-box");
    let kept = ["floor", "tall block", "short block", "camera"];
    keep_nodes(&mut doc, |name| kept.contains(&name));
    use_extension(&mut doc, "VCM_environment");
    doc["extensions"] = json!({"VCM_environment": {"image": "sky.exr"}});
    doc
}

/// One comparison: a scene, the algorithm `vcm render` uses and the path length limit both use.
struct Case {
    name: &'static str,
    scene: Value,
    algo: &'static str,
    max_depth: Option<u32>,
}

impl Case {
    fn pt(name: &'static str, scene: Value) -> Case {
        Case {
            name,
            scene,
            algo: "pt",
            max_depth: None,
        }
    }

    fn with(self, algo: &'static str, max_depth: Option<u32>) -> Case {
        Case {
            algo,
            max_depth,
            ..self
        }
    }
}

/// Runs `command`, failing with its error output if it fails.
fn run(command: &mut Command) {
    let output = command.output().unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// Runs `command`, which writes the image `out`, and reads it.
fn render_to(command: &mut Command, out: &Path) -> RgbImage {
    run(command);
    RgbImage::read_exr(out).unwrap()
}

/// `RENDERS` images of the case's scene (written to `scene`) by `vcm render` and as many by
/// Mitsuba.
fn render_both(dir: &Path, case: &Case, scene: &Path) -> [Vec<RgbImage>; 2] {
    let (width, height) = (WIDTH.to_string(), HEIGHT.to_string());
    let spp = SPP.to_string();
    // Both take `--max-depth` in segments and default to no limit.
    let depth = case.max_depth.map(|d| d.to_string());
    let depth_args = depth.iter().flat_map(|d| ["--max-depth", d.as_str()]);
    let common: Vec<&str> = ["--width", &width, "--height", &height, "--spp", &spp]
        .into_iter()
        .chain(depth_args)
        .collect();
    let name = case.name;
    let ours = (1..=RENDERS)
        .map(|seed| {
            let out = dir.join(format!("{name}-vcm-{seed}.exr"));
            let mut vcm = Command::new(env!("CARGO_BIN_EXE_vcm"));
            vcm.arg("render").arg(scene).args(&common);
            vcm.args([
                "--algo",
                case.algo,
                "--seed",
                &(seed + 100).to_string(),
                "-o",
            ]);
            render_to(vcm.arg(&out), &out)
        })
        .collect();
    // One Mitsuba process renders every seed (its start, Python, Mitsuba and the scene, cost
    // more than the renders); its output path names each image with `{seed}`.
    let out = |seed: &str| dir.join(format!("{name}-mitsuba-{seed}.exr"));
    let seeds: Vec<String> = (1..=RENDERS).map(|seed| seed.to_string()).collect();
    let mut mitsuba = Command::new(python());
    mitsuba.arg(root().join("tools/mitsuba_reference.py"));
    mitsuba.arg(scene).arg(out("{seed}"));
    run(mitsuba.args(&common).arg("--seed").args(&seeds));
    let theirs = seeds
        .iter()
        .map(|seed| RgbImage::read_exr(&out(seed)).unwrap())
        .collect();
    [ours, theirs]
}

/// Per render, the mean of each colour channel over each `BLOCK`² block, then over the image:
/// `[block][channel]`, the whole image last.
fn block_means(image: &RgbImage) -> Vec<[f64; 3]> {
    assert_eq!((image.width, image.height), (WIDTH, HEIGHT));
    let per_row = WIDTH / BLOCK;
    let count = per_row * (HEIGHT / BLOCK);
    let mut blocks = vec![[0.0; 3]; count + 1];
    for (i, p) in image.pixels.iter().enumerate() {
        let block = (i / WIDTH / BLOCK) * per_row + (i % WIDTH) / BLOCK;
        for (c, v) in [p.x, p.y, p.z].into_iter().enumerate() {
            blocks[block][c] += f64::from(v) / (BLOCK * BLOCK) as f64;
            blocks[count][c] += f64::from(v) / (WIDTH * HEIGHT) as f64;
        }
    }
    blocks
}

/// Mean and variance of the mean of `values`.
fn mean_and_variance(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var / n)
}

/// Welch's t statistic of each block and channel (the whole image last) between two sets of
/// independent renders.
fn welch_t(ours: &[RgbImage], theirs: &[RgbImage]) -> Vec<[f64; 3]> {
    let a: Vec<_> = ours.iter().map(block_means).collect();
    let b: Vec<_> = theirs.iter().map(block_means).collect();
    (0..a[0].len())
        .map(|block| {
            std::array::from_fn(|c| {
                let (ma, va) =
                    mean_and_variance(&a.iter().map(|r| r[block][c]).collect::<Vec<_>>());
                let (mb, vb) =
                    mean_and_variance(&b.iter().map(|r| r[block][c]).collect::<Vec<_>>());
                // Blocks without noise (sky seen directly) still differ by rounding: f32
                // pixel sums and Mitsuba's interpolation weights, ~10⁻⁶ of the value.
                let rounding = ROUNDING * ma.abs().max(mb.abs());
                let spread = (va + vb + rounding * rounding).sqrt();
                if spread == 0.0 {
                    0.0
                } else {
                    (ma - mb) / spread
                }
            })
        })
        .collect()
}

#[test]
fn vcm_render_agrees_with_mitsuba() {
    if let Some(reason) = mitsuba_missing() {
        let required = std::env::var("VCM_REQUIRE_MITSUBA").is_ok_and(|v| v == "1");
        assert!(!required, "VCM_REQUIRE_MITSUBA=1 but {reason}");
        eprintln!(
            "skipped: {reason} (pip install -r tools/requirements.txt; set VCM_REQUIRE_MITSUBA=1 to make this an error)"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        Case::pt("cornell-box", load_scene("cornell-box")),
        Case::pt("cornell-indirect", load_scene("cornell-indirect")),
        Case::pt("cornell-specular", load_scene("cornell-specular")),
        Case::pt(
            "cornell-specular-close",
            load_scene("cornell-specular-close"),
        ),
        Case::pt("cornell-specular-depth-3", load_scene("cornell-specular")).with("pt", Some(3)),
        Case::pt(
            "cornell-specular-depth-3-bpt",
            load_scene("cornell-specular"),
        )
        .with("bpt", Some(3)),
        Case::pt("cornell-water", load_scene("cornell-water")),
        Case::pt("rough", rough()),
        Case::pt("rough-bpt", rough()).with("bpt", None),
        Case::pt("rough-copper", rough_copper()),
        Case::pt("thin-sheet", thin_sheet()),
        Case::pt("absorbing-glass", absorbing_glass()),
        Case::pt("absorbing-glass-bpt", absorbing_glass()).with("bpt", None),
        Case::pt("punctual-lights", punctual_lights()),
        Case::pt("punctual-lights-bpt", punctual_lights()).with("bpt", None),
        Case::pt("spot", spot()),
        Case::pt("mis-plates", mis_plates()),
        Case::pt("mis-plates-bpt", mis_plates()).with("bpt", None),
        Case::pt("scaled-water", scaled_water()),
        Case::pt("mirrored", mirrored()),
        Case::pt("one-sided-panel", panel(false)),
        Case::pt("double-sided-panel", panel(true)),
        // glTF's LINEAR and REPEAT; NEAREST and MIRRORED_REPEAT.
        Case::pt("poster", poster(dir.path(), 9729, 10497, false)),
        Case::pt(
            "poster-nearest-mirrored",
            poster(dir.path(), 9728, 33648, false),
        ),
        // An emissive texture, lighting the room beside the ceiling light. Mitsuba's renders of
        // it are not always the same for one seed (about one process in six gives another
        // image, with one thread too; ours are bit-identical), so these two cases print
        // slightly different t values from run to run.
        Case::pt("glowing-poster", poster(dir.path(), 9729, 10497, true)),
        Case::pt("glowing-poster-bpt", poster(dir.path(), 9729, 10497, true)).with("bpt", None),
        Case::pt("masked-panel", masked_panel(dir.path())),
        Case::pt("masked-panel-bpt", masked_panel(dir.path())).with("bpt", None),
        Case::pt("open-sky", open_sky(dir.path())),
        Case::pt("open-sky-bpt", open_sky(dir.path())).with("bpt", None),
    ];
    // `VCM_CROSSCHECK_CASES=a,b` runs only the cases named (while working on one).
    let only = std::env::var("VCM_CROSSCHECK_CASES").ok();
    let wanted = |name: &str| {
        only.as_ref()
            .is_none_or(|o| o.split(',').any(|c| c == name))
    };
    let wanted: Vec<&Case> = cases.iter().filter(|case| wanted(case.name)).collect();
    // The cases run side by side, one per core: a Mitsuba render of this size keeps one core
    // busy, and the test is the longest of the suite. On threads of their own: rayon's pool,
    // on which the other tests of this binary render, would sit blocked on the processes.
    let next = AtomicUsize::new(0);
    let workers = std::thread::available_parallelism().map_or(1, usize::from);
    let failures: Vec<String> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                scope.spawn(|| {
                    std::iter::from_fn(|| wanted.get(next.fetch_add(1, Ordering::Relaxed)))
                        .filter_map(|case| check_case(dir.path(), case))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|handle| handle.join().unwrap())
            .collect()
    });
    assert!(failures.is_empty(), "differs from Mitsuba: {failures:?}");
}

/// Renders `case` with both renderers in `dir` and compares them; what differs, if anything.
fn check_case(dir: &Path, case: &Case) -> Option<String> {
    let name = case.name;
    let scene: PathBuf = dir.join(format!("{name}.gltf"));
    std::fs::write(&scene, serde_json::to_string(&case.scene).unwrap()).unwrap();
    let [ours, theirs] = render_both(dir, case, &scene);
    let t = welch_t(&ours, &theirs);
    let (image, blocks) = t.split_last().unwrap();
    // Welch's t between two sets of 6 renders has about 10 degrees of freedom when the two
    // renderers are equally noisy, 5 when one dominates. The image means: |t| > 8 has a
    // probability of 5·10⁻⁴ at 5 degrees of freedom (10⁻⁵ at 10), for each of the 60
    // channels tested. The blocks: a block is off when any channel has |t| > 4 (at most
    // 3 × 1% at 5 degrees of freedom, 3 × 0.25% at 10); more than 8 of 48 such blocks has
    // a binomial probability below 10⁻⁴ at 3% per block. Caustics through glass are heavy
    // tailed, so 6 renders can underestimate their variance: the margins are wide (runs
    // with other seeds and sizes reached an image |t| of 4.7 and 4 blocks off). A region
    // that differs by a few percent moves many blocks at once: GGX with α = r instead of
    // r² on the rough scene puts 27% of the blocks' channels above 4 and the image at
    // t = 15.
    let image_ok = image.iter().all(|t| t.abs() < 8.0);
    let off = blocks
        .iter()
        .filter(|b| b.iter().any(|t| t.abs() > 4.0))
        .count();
    let worst = blocks.iter().flatten().fold(0.0f64, |m, t| m.max(t.abs()));
    eprintln!(
        "{name}: image t {:.2?}, {off} of {} blocks with |t| > 4, largest block |t| {worst:.2}",
        image,
        blocks.len()
    );
    (!image_ok || off > 8).then(|| format!("{name}: image t {image:.2?}, {off} blocks off"))
}

#[test]
fn welch_t_tells_a_brighter_image_from_noise() {
    // Two sets of images with the same noise: equal means give small t, a 2% brighter set
    // (twice the spread of the means) gives a large one.
    let image = |seed: u64, gain: f32| {
        let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let pixels = (0..WIDTH * HEIGHT)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let u = (state >> 40) as f32 / (1u64 << 24) as f32;
                Vec3::splat(gain * (0.5 + 0.2 * (u - 0.5)))
            })
            .collect();
        RgbImage {
            width: WIDTH,
            height: HEIGHT,
            pixels,
        }
    };
    let base: Vec<_> = (0..RENDERS).map(|s| image(s, 1.0)).collect();
    let same: Vec<_> = (10..10 + RENDERS).map(|s| image(s, 1.0)).collect();
    let brighter: Vec<_> = (10..10 + RENDERS).map(|s| image(s, 1.02)).collect();
    let whole = |t: Vec<[f64; 3]>| t.last().unwrap()[0];
    assert!(whole(welch_t(&base, &same)).abs() < 8.0);
    assert!(whole(welch_t(&base, &brighter)) < -8.0);
}
