//! Writes the test scenes in `scenes/` as self-contained glTF files (buffers embedded as data
//! URIs), following the project's scene conventions:
//!
//! - `cornell-box`: area light under the ceiling, two diffuse blocks;
//! - `cornell-indirect`: the light faces the ceiling, so the room is lit indirectly;
//! - `cornell-specular`: a mirror sphere and a solid glass sphere;
//! - `cornell-specular-close`: the same, with the camera close to the spheres;
//! - `cornell-water`: the lower part of the room filled with water (IOR 1.33) under a wavy
//!   surface (an interface spanning the room), casting caustics on the floor;
//! - `cornell-point`: the room without its area light, lit by a point light above a floating
//!   glass sphere under a large mirror on the ceiling (caustics only light paths find);
//! - `large`: the room with 196 instanced spheres of mixed materials, ~1M triangles.
//!
//! Run with `cargo run --example make_scenes` from any folder.

use std::collections::BTreeSet;
use std::path::Path;

use base64::Engine;
use glam::{Quat, Vec3};
use serde_json::{Value, json};
use vcm_scene::shapes::icosphere;

/// Linear albedos of the classic Cornell box (white, red, green walls).
const WHITE: [f32; 3] = [0.725, 0.71, 0.68];
const RED: [f32; 3] = [0.63, 0.065, 0.05];
const GREEN: [f32; 3] = [0.14, 0.45, 0.091];

/// A triangle mesh: positions and counter-clockwise triangles (seen from the front).
type Geometry = (Vec<Vec3>, Vec<[u32; 3]>);

/// Accumulates meshes, materials and nodes, then writes one glTF document.
#[derive(Default)]
struct GltfWriter {
    buffer: Vec<u8>,
    buffer_views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    materials: Vec<Value>,
    nodes: Vec<Value>,
    cameras: Vec<Value>,
    /// `KHR_lights_punctual` lights.
    lights: Vec<Value>,
    extensions: BTreeSet<String>,
}

/// Accessor indices of one uploaded geometry.
#[derive(Clone, Copy)]
struct Accessors {
    position: usize,
    normal: usize,
    indices: usize,
}

impl GltfWriter {
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while !self.buffer.len().is_multiple_of(4) {
            self.buffer.push(0);
        }
        let offset = self.buffer.len();
        self.buffer.extend_from_slice(bytes);
        self.buffer_views.push(json!({
            "buffer": 0, "byteOffset": offset, "byteLength": bytes.len(), "target": target
        }));
        self.buffer_views.len() - 1
    }

    /// Adds a glTF material, recording the extensions it uses.
    fn material(&mut self, value: Value) -> usize {
        if let Some(extensions) = value.get("extensions").and_then(Value::as_object) {
            self.extensions.extend(extensions.keys().cloned());
        }
        self.materials.push(value);
        self.materials.len() - 1
    }

    fn diffuse(&mut self, name: &str, albedo: [f32; 3]) -> usize {
        self.material(json!({
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [albedo[0], albedo[1], albedo[2], 1.0],
                "metallicFactor": 0.0, "roughnessFactor": 1.0
            },
            "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}
        }))
    }

    fn emitter(&mut self, name: &str, color: [f32; 3], strength: f32) -> usize {
        self.material(json!({
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0
            },
            "emissiveFactor": color,
            "extensions": {
                "KHR_materials_emissive_strength": {"emissiveStrength": strength},
                "KHR_materials_specular": {"specularFactor": 0.0}
            }
        }))
    }

    /// A conductor with base color `color` and perceptual roughness `roughness` (0: mirror).
    fn metal(&mut self, name: &str, color: [f32; 3], roughness: f32) -> usize {
        self.material(json!({
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [color[0], color[1], color[2], 1.0],
                "metallicFactor": 1.0, "roughnessFactor": roughness
            }
        }))
    }

    /// A smooth dielectric bounding a solid volume (glass, water).
    fn dielectric(&mut self, name: &str, ior: f32) -> usize {
        self.material(json!({
            "name": name,
            "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.0},
            "extensions": {
                "KHR_materials_transmission": {"transmissionFactor": 1.0},
                "KHR_materials_ior": {"ior": ior},
                "KHR_materials_volume": {"thicknessFactor": 1.0}
            }
        }))
    }

    /// Uploads positions, smooth vertex normals and indices.
    fn upload(&mut self, (positions, triangles): &Geometry) -> Accessors {
        let mut normals = vec![Vec3::ZERO; positions.len()];
        for t in triangles {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let n = (b - a).cross(c - a);
            t.iter().for_each(|&i| normals[i as usize] += n);
        }
        let normals: Vec<Vec3> = normals.iter().map(|n| n.normalize()).collect();
        let floats = |v: &[Vec3]| -> Vec<u8> {
            v.iter()
                .flat_map(|p| p.to_array())
                .flat_map(f32::to_le_bytes)
                .collect()
        };
        let (min, max) = positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let indices: Vec<u8> = triangles
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let position_view = self.view(&floats(positions), 34962);
        let normal_view = self.view(&floats(&normals), 34962);
        let index_view = self.view(&indices, 34963);
        let position = self.accessors.len();
        self.accessors.extend([
            json!({"bufferView": position_view, "componentType": 5126, "count": positions.len(),
                   "type": "VEC3", "min": min.to_array(), "max": max.to_array()}),
            json!({"bufferView": normal_view, "componentType": 5126, "count": normals.len(), "type": "VEC3"}),
            json!({"bufferView": index_view, "componentType": 5125, "count": triangles.len() * 3, "type": "SCALAR"}),
        ]);
        Accessors {
            position,
            normal: position + 1,
            indices: position + 2,
        }
    }

    /// A glTF mesh drawing uploaded geometry with `material`; returns the mesh index.
    fn mesh(&mut self, name: &str, geometry: Accessors, material: usize) -> usize {
        self.meshes.push(json!({"name": name, "primitives": [{
            "attributes": {"POSITION": geometry.position, "NORMAL": geometry.normal},
            "indices": geometry.indices, "material": material
        }]}));
        self.meshes.len() - 1
    }

    /// Uploads `geometry` and places it once, untransformed.
    fn object(&mut self, name: &str, geometry: &Geometry, material: usize) {
        let accessors = self.upload(geometry);
        let mesh = self.mesh(name, accessors, material);
        self.instance(name, mesh, Vec3::ZERO, 1.0);
    }

    /// Places `mesh` at `translation` with uniform `scale`.
    fn instance(&mut self, name: &str, mesh: usize, translation: Vec3, scale: f32) {
        self.nodes.push(json!({
            "name": name, "mesh": mesh,
            "translation": translation.to_array(), "scale": [scale, scale, scale]
        }));
    }

    /// Adds a perspective camera at `eye` looking at `target` (+Y up).
    fn camera(&mut self, eye: Vec3, target: Vec3, yfov_degrees: f32) {
        // Camera axes: +X right, +Y up, looking down -Z.
        let forward = (target - eye).normalize();
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        let rotation = Quat::from_mat3(&glam::Mat3::from_cols(right, up, -forward));
        self.cameras
            .push(json!({"type": "perspective", "perspective": {
                "yfov": yfov_degrees.to_radians(), "aspectRatio": 1.0, "znear": 0.01
            }}));
        self.nodes.push(json!({
            "name": "camera", "camera": self.cameras.len() - 1,
            "rotation": rotation.to_array(), "translation": eye.to_array()
        }));
    }

    /// Adds a `KHR_lights_punctual` point light of radiant intensity `intensity · color`.
    fn point_light(&mut self, name: &str, position: Vec3, color: [f32; 3], intensity: f32) {
        self.extensions.insert("KHR_lights_punctual".into());
        self.lights.push(json!({
            "name": name, "type": "point", "color": color, "intensity": intensity
        }));
        self.nodes.push(json!({
            "name": name, "translation": position.to_array(),
            "extensions": {"KHR_lights_punctual": {"light": self.lights.len() - 1}}
        }));
    }

    fn write(self, path: &Path) -> std::io::Result<()> {
        let data = base64::engine::general_purpose::STANDARD.encode(&self.buffer);
        let mut document = json!({
            "asset": {"version": "2.0", "generator": "vcm-rs examples/make_scenes.rs"},
            "extensionsUsed": self.extensions,
            "scene": 0,
            "scenes": [{"nodes": (0..self.nodes.len()).collect::<Vec<_>>()}],
            "nodes": self.nodes, "meshes": self.meshes, "materials": self.materials,
            "cameras": self.cameras, "accessors": self.accessors, "bufferViews": self.buffer_views,
            "buffers": [{"byteLength": self.buffer.len(),
                         "uri": format!("data:application/octet-stream;base64,{data}")}]
        });
        if !self.lights.is_empty() {
            document["extensions"] = json!({"KHR_lights_punctual": {"lights": self.lights}});
        }
        std::fs::write(path, serde_json::to_string_pretty(&document)? + "\n")
    }
}

/// A quad from four corners in counter-clockwise order seen from its front.
fn quad(corners: [Vec3; 4]) -> Geometry {
    (corners.to_vec(), vec![[0, 1, 2], [0, 2, 3]])
}

/// An axis-aligned box of half size `half`, rotated about +Y and standing on y = `floor`,
/// with outward-facing triangles.
fn block(center_xz: (f32, f32), half: Vec3, angle_degrees: f32, floor: f32) -> Geometry {
    let rotation = Quat::from_rotation_y(angle_degrees.to_radians());
    let center = Vec3::new(center_xz.0, floor + half.y, center_xz.1);
    let corner = |(x, y, z): (f32, f32, f32)| center + rotation * (half * Vec3::new(x, y, z));
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    // Each face: four corners counter-clockwise seen from outside.
    let faces = [
        [(-1., -1., 1.), (1., -1., 1.), (1., 1., 1.), (-1., 1., 1.)],
        [
            (1., -1., -1.),
            (-1., -1., -1.),
            (-1., 1., -1.),
            (1., 1., -1.),
        ],
        [(1., -1., 1.), (1., -1., -1.), (1., 1., -1.), (1., 1., 1.)],
        [
            (-1., -1., -1.),
            (-1., -1., 1.),
            (-1., 1., 1.),
            (-1., 1., -1.),
        ],
        [(-1., 1., 1.), (1., 1., 1.), (1., 1., -1.), (-1., 1., -1.)],
        [
            (-1., -1., -1.),
            (1., -1., -1.),
            (1., -1., 1.),
            (-1., -1., 1.),
        ],
    ];
    for face in faces {
        let base = positions.len() as u32;
        positions.extend(face.map(corner));
        triangles.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
    }
    (positions, triangles)
}

/// `geometry` scaled by `radius` and moved to `center`.
fn placed((positions, triangles): Geometry, center: Vec3, radius: f32) -> Geometry {
    (
        positions.iter().map(|p| center + *p * radius).collect(),
        triangles,
    )
}

/// A wavy water surface over x, z ∈ [−w, w] around height `level`, facing up (`n` × `n` cells).
/// It is an interface, not a closed mesh: the room below it is water (IOR from the material),
/// above it air, as in a pool filled to the brim of the region it spans.
fn water_surface(w: f32, level: f32, n: u32) -> Geometry {
    let height = |x: f32, z: f32| {
        level
            + 0.025 * (7.0 * x + 1.3).sin() * (5.0 * z - 0.4).cos()
            + 0.012 * (13.0 * (x + z)).sin()
    };
    let coordinate = |i: u32| -w + 2.0 * w * i as f32 / n as f32;
    let index = |i: u32, j: u32| i * (n + 1) + j;
    let positions = (0..=n)
        .flat_map(|i| (0..=n).map(move |j| (coordinate(j), coordinate(i))))
        .map(|(x, z)| Vec3::new(x, height(x, z), z))
        .collect();
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..n {
            // Vertex (i, j) sits at x = coordinate(j), z = coordinate(i); this winding faces +Y.
            let (a, b, c, d) = (
                index(i, j),
                index(i, j + 1),
                index(i + 1, j + 1),
                index(i + 1, j),
            );
            triangles.extend([[a, d, c], [a, c, b]]);
        }
    }
    (positions, triangles)
}

/// Which light the room gets.
enum RoomLight {
    /// A quad under the ceiling shining down.
    Down,
    /// A quad below the ceiling shining up at it.
    Up,
    /// None: the scene brings its own light.
    Absent,
}

/// The Cornell room: a 2×2×2 box open toward +Z, with walls and an area light.
fn cornell_room(w: &mut GltfWriter, light: RoomLight) -> usize {
    let white = w.diffuse("white", WHITE);
    let red = w.diffuse("red", RED);
    let green = w.diffuse("green", GREEN);
    let v = Vec3::new;
    let walls = [
        (
            "floor",
            [
                v(-1., -1., 1.),
                v(1., -1., 1.),
                v(1., -1., -1.),
                v(-1., -1., -1.),
            ],
            white,
        ),
        (
            "ceiling",
            [
                v(-1., 1., -1.),
                v(1., 1., -1.),
                v(1., 1., 1.),
                v(-1., 1., 1.),
            ],
            white,
        ),
        (
            "back",
            [
                v(-1., -1., -1.),
                v(1., -1., -1.),
                v(1., 1., -1.),
                v(-1., 1., -1.),
            ],
            white,
        ),
        (
            "left",
            [
                v(-1., -1., 1.),
                v(-1., -1., -1.),
                v(-1., 1., -1.),
                v(-1., 1., 1.),
            ],
            red,
        ),
        (
            "right",
            [
                v(1., -1., -1.),
                v(1., -1., 1.),
                v(1., 1., 1.),
                v(1., 1., -1.),
            ],
            green,
        ),
    ];
    for (name, corners, material) in walls {
        w.object(name, &quad(corners), material);
    }
    let s = 0.23;
    let corners = match light {
        RoomLight::Down => [
            v(-s, 0.998, -s),
            v(s, 0.998, -s),
            v(s, 0.998, s),
            v(-s, 0.998, s),
        ],
        RoomLight::Up => [v(-s, 0.9, -s), v(-s, 0.9, s), v(s, 0.9, s), v(s, 0.9, -s)],
        RoomLight::Absent => return white,
    };
    let emitter = w.emitter("light", [1.0, 0.706, 0.235], 17.0);
    w.object("light", &quad(corners), emitter);
    white
}

fn blocks(w: &mut GltfWriter, material: usize) {
    let tall = block((-0.33, -0.3), Vec3::new(0.3, 0.6, 0.3), 17.0, -1.0);
    w.object("tall block", &tall, material);
    let short = block((0.34, 0.32), Vec3::splat(0.3), -17.0, -1.0);
    w.object("short block", &short, material);
}

fn standard_camera(w: &mut GltfWriter) {
    w.camera(Vec3::new(0.0, 0.0, 3.9), Vec3::ZERO, 38.0);
}

fn cornell_box(light: RoomLight) -> GltfWriter {
    let mut w = GltfWriter::default();
    let white = cornell_room(&mut w, light);
    blocks(&mut w, white);
    standard_camera(&mut w);
    w
}

fn cornell_specular(close: bool) -> GltfWriter {
    let mut w = GltfWriter::default();
    cornell_room(&mut w, RoomLight::Down);
    let mirror = w.metal("mirror", [1.0, 1.0, 1.0], 0.0);
    let glass = w.dielectric("glass", 1.5);
    let r = 0.35;
    let sphere = |x: f32, z: f32| placed(icosphere(4), Vec3::new(x, -1.0 + r + 1e-3, z), r);
    w.object("mirror sphere", &sphere(-0.45, -0.35), mirror);
    w.object("glass sphere", &sphere(0.45, 0.3), glass);
    if close {
        w.camera(Vec3::new(0.0, -0.35, 1.3), Vec3::new(0.0, -0.62, 0.0), 50.0);
    } else {
        standard_camera(&mut w);
    }
    w
}

fn cornell_water() -> GltfWriter {
    let mut w = GltfWriter::default();
    let white = cornell_room(&mut w, RoomLight::Down);
    blocks(&mut w, white);
    let water = w.dielectric("water", 1.33);
    // Inset from the walls so its border does not coincide with them.
    w.object("water", &water_surface(0.999, -0.45, 96), water);
    standard_camera(&mut w);
    w
}

fn cornell_point() -> GltfWriter {
    let mut w = GltfWriter::default();
    cornell_room(&mut w, RoomLight::Absent);
    let mirror = w.metal("mirror", [1.0, 1.0, 1.0], 0.0);
    let glass = w.dielectric("glass", 1.5);
    let v = Vec3::new;
    let m = 0.75;
    let ceiling_mirror = [
        v(-m, 0.99, -m),
        v(m, 0.99, -m),
        v(m, 0.99, m),
        v(-m, 0.99, m),
    ];
    w.object("ceiling mirror", &quad(ceiling_mirror), mirror);
    let sphere = placed(icosphere(4), Vec3::new(0.0, -0.45, 0.1), 0.3);
    w.object("glass sphere", &sphere, glass);
    w.point_light("bulb", Vec3::new(0.0, 0.5, 0.1), [1.0, 0.85, 0.65], 1.5);
    standard_camera(&mut w);
    w
}

/// The room with a 14 × 14 grid of instanced spheres (5,120 triangles each) in four materials.
fn large() -> GltfWriter {
    let mut w = GltfWriter::default();
    cornell_room(&mut w, RoomLight::Down);
    let materials = [
        w.diffuse("matte", [0.6, 0.6, 0.6]),
        w.material(json!({"name": "plastic", "pbrMetallicRoughness": {
            "baseColorFactor": [0.2, 0.3, 0.7, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.4}})),
        w.metal("gold", [1.0, 0.78, 0.34], 0.3),
        w.dielectric("glass", 1.5),
    ];
    let sphere = w.upload(&icosphere(4));
    let meshes: Vec<usize> = materials
        .iter()
        .map(|&m| w.mesh("sphere", sphere, m))
        .collect();
    let n = 14;
    let radius = 0.06;
    for i in 0..n {
        for j in 0..n {
            let x = -0.85 + 1.7 * j as f32 / (n - 1) as f32;
            let z = -0.85 + 1.7 * i as f32 / (n - 1) as f32;
            let center = Vec3::new(x, -1.0 + radius + 1e-3, z);
            w.instance("sphere", meshes[((i + j) % 4) as usize], center, radius);
        }
    }
    standard_camera(&mut w);
    w
}

fn main() -> std::io::Result<()> {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    std::fs::create_dir_all(&out)?;
    let scenes = [
        ("cornell-box", cornell_box(RoomLight::Down)),
        ("cornell-indirect", cornell_box(RoomLight::Up)),
        ("cornell-specular", cornell_specular(false)),
        ("cornell-specular-close", cornell_specular(true)),
        ("cornell-water", cornell_water()),
        ("cornell-point", cornell_point()),
        ("large", large()),
    ];
    for (name, writer) in scenes {
        let path = out.join(format!("{name}.gltf"));
        writer.write(&path)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
