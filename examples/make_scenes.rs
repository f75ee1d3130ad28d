//! Writes the test scenes in `scenes/` as self-contained glTF files (buffers embedded as data
//! URIs), following the project's scene conventions.
//!
//! Run with `cargo run --example make_scenes` from the repository root.

use std::path::Path;

use base64::Engine;
use glam::{Mat4, Quat, Vec3};
use serde_json::{Value, json};

/// Linear albedos of the classic Cornell box (white, red, green walls).
const WHITE: [f32; 3] = [0.725, 0.71, 0.68];
const RED: [f32; 3] = [0.63, 0.065, 0.05];
const GREEN: [f32; 3] = [0.14, 0.45, 0.091];

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

    fn material(&mut self, value: Value) -> usize {
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

    /// Adds a triangle mesh (counter-clockwise triangles seen from the front) as its own node.
    fn mesh(&mut self, name: &str, positions: &[Vec3], triangles: &[[u32; 3]], material: usize) {
        let (mut min, mut max) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let mut normals = vec![Vec3::ZERO; positions.len()];
        for t in triangles {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let n = (b - a).cross(c - a);
            t.iter().for_each(|&i| normals[i as usize] += n);
        }
        let floats = |v: &[Vec3]| -> Vec<u8> {
            v.iter()
                .flat_map(|p| p.to_array())
                .flat_map(f32::to_le_bytes)
                .collect()
        };
        positions.iter().for_each(|p| {
            min = min.min(*p);
            max = max.max(*p);
        });
        let normals: Vec<Vec3> = normals.iter().map(|n| n.normalize()).collect();
        let indices: Vec<u8> = triangles
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let position_view = self.view(&floats(positions), 34962);
        let normal_view = self.view(&floats(&normals), 34962);
        let index_view = self.view(&indices, 34963);
        let first = self.accessors.len();
        self.accessors.extend([
            json!({"bufferView": position_view, "componentType": 5126, "count": positions.len(),
                   "type": "VEC3", "min": min.to_array(), "max": max.to_array()}),
            json!({"bufferView": normal_view, "componentType": 5126, "count": normals.len(), "type": "VEC3"}),
            json!({"bufferView": index_view, "componentType": 5125, "count": triangles.len() * 3, "type": "SCALAR"}),
        ]);
        self.meshes.push(json!({"name": name, "primitives": [{
            "attributes": {"POSITION": first, "NORMAL": first + 1},
            "indices": first + 2, "material": material
        }]}));
        self.nodes
            .push(json!({"name": name, "mesh": self.meshes.len() - 1}));
    }

    /// Adds a perspective camera at `eye` looking at `target` (+Y up).
    fn camera(&mut self, eye: Vec3, target: Vec3, yfov_degrees: f32) {
        // Camera axes: +X right, +Y up, looking down -Z.
        let forward = (target - eye).normalize();
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        let rotation = Quat::from_mat3(&glam::Mat3::from_cols(right, up, -forward));
        let translation = eye;
        self.cameras
            .push(json!({"type": "perspective", "perspective": {
                "yfov": yfov_degrees.to_radians(), "aspectRatio": 1.0, "znear": 0.01
            }}));
        self.nodes.push(json!({
            "name": "camera", "camera": self.cameras.len() - 1,
            "rotation": rotation.to_array(), "translation": translation.to_array()
        }));
    }

    fn write(self, path: &Path) -> std::io::Result<()> {
        let data = base64::engine::general_purpose::STANDARD.encode(&self.buffer);
        let document = json!({
            "asset": {"version": "2.0", "generator": "vcm-rs examples/make_scenes.rs"},
            "extensionsUsed": ["KHR_materials_emissive_strength", "KHR_materials_specular"],
            "scene": 0,
            "scenes": [{"nodes": (0..self.nodes.len()).collect::<Vec<_>>()}],
            "nodes": self.nodes, "meshes": self.meshes, "materials": self.materials,
            "cameras": self.cameras, "accessors": self.accessors, "bufferViews": self.buffer_views,
            "buffers": [{"byteLength": self.buffer.len(),
                         "uri": format!("data:application/octet-stream;base64,{data}")}]
        });
        std::fs::write(path, serde_json::to_string_pretty(&document)? + "\n")
    }
}

/// A quad from four corners in counter-clockwise order seen from its front.
fn quad(corners: [Vec3; 4]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    (corners.to_vec(), vec![[0, 1, 2], [0, 2, 3]])
}

/// An axis-aligned box of half size `half`, rotated about +Y and standing on y = `floor`,
/// with outward-facing triangles.
fn block(
    center_xz: (f32, f32),
    half: Vec3,
    angle_degrees: f32,
    floor: f32,
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let transform = Mat4::from_rotation_translation(
        Quat::from_rotation_y(angle_degrees.to_radians()),
        Vec3::new(center_xz.0, floor + half.y, center_xz.1),
    );
    let corner = |x: f32, y: f32, z: f32| transform.transform_point3(half * Vec3::new(x, y, z));
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
        positions.extend(face.map(|(x, y, z)| corner(x, y, z)));
        triangles.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
    }
    (positions, triangles)
}

/// The Cornell box: a 2×2×2 room open toward +Z, an area light under the ceiling, two diffuse
/// blocks, and a camera outside the open side.
fn cornell_box() -> GltfWriter {
    let mut w = GltfWriter::default();
    let white = w.diffuse("white", WHITE);
    let red = w.diffuse("red", RED);
    let green = w.diffuse("green", GREEN);
    let light = w.emitter("light", [1.0, 0.706, 0.235], 17.0);
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
        let (p, t) = quad(corners);
        w.mesh(name, &p, &t, material);
    }
    let s = 0.23;
    let (p, t) = quad([
        v(-s, 0.998, -s),
        v(s, 0.998, -s),
        v(s, 0.998, s),
        v(-s, 0.998, s),
    ]);
    w.mesh("light", &p, &t, light);
    let (p, t) = block((-0.33, -0.3), v(0.3, 0.6, 0.3), 17.0, -1.0);
    w.mesh("tall block", &p, &t, white);
    let (p, t) = block((0.34, 0.32), v(0.3, 0.3, 0.3), -17.0, -1.0);
    w.mesh("short block", &p, &t, white);
    w.camera(v(0.0, 0.0, 3.9), v(0.0, 0.0, 0.0), 38.0);
    w
}

fn main() -> std::io::Result<()> {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    std::fs::create_dir_all(&out)?;
    let path = out.join("cornell-box.gltf");
    cornell_box().write(&path)?;
    println!("wrote {}", path.display());
    Ok(())
}
