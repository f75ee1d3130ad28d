//! A fingerprint of a scene's content, so that a render state is never resumed or merged with
//! samples of another scene.

use std::fmt::Write as _;

use glam::{Vec2, Vec3, Vec4};
use vcm_scene::Scene;
use vcm_scene::light::Light;
use xxhash_rust::xxh3::Xxh3;

/// The xxh3 (64-bit) hash of everything in `scene` that the image depends on: the mesh
/// (positions, normals, texture coordinates, tangents, colors, triangles, material ids), the
/// materials, the textures' texels and sampling, the lights other than the area lights (which
/// the mesh and materials define) and the file's cameras. Not the file's path or name: the
/// same scene moved elsewhere has the same hash.
pub fn scene_hash(scene: &Scene) -> u64 {
    let mut hasher = Hasher(Xxh3::new());
    let mesh = &scene.mesh;
    hasher.floats(mesh.positions.iter().flat_map(Vec3::to_array));
    hasher.floats(mesh.normals.iter().flat_map(Vec3::to_array));
    hasher.floats(mesh.uvs.iter().flat_map(Vec2::to_array));
    hasher.floats(mesh.tangents.iter().flat_map(Vec4::to_array));
    hasher.floats(mesh.colors.iter().flat_map(Vec3::to_array));
    hasher.words(mesh.triangles.iter().flatten().copied());
    hasher.words(mesh.material_ids.iter().copied());
    hasher.debug(&scene.materials);
    for texture in &scene.textures {
        let (width, height) = (texture.width(), texture.height());
        hasher.words([width, height]);
        let texels = (0..height).flat_map(|y| (0..width).map(move |x| texture.texel(x, y)));
        hasher.floats(texels.flat_map(|t| t.to_array()));
        hasher.debug(&(texture.wrap_u, texture.wrap_v, texture.filter));
    }
    for light in &scene.lights {
        if !matches!(light, Light::Area(_)) {
            hasher.debug(light);
        }
    }
    hasher.debug(&scene.cameras);
    hasher.0.digest()
}

/// Feeds numbers and debug text to an xxh3 hash; each part is preceded by its length so that
/// parts cannot run into one another.
struct Hasher(Xxh3);

impl Hasher {
    fn floats(&mut self, values: impl Iterator<Item = f32>) {
        self.words(values.map(f32::to_bits));
    }

    fn words(&mut self, values: impl IntoIterator<Item = u32>) {
        let mut count = 0u64;
        for value in values {
            self.0.update(&value.to_le_bytes());
            count += 1;
        }
        self.0.update(&count.to_le_bytes());
    }

    fn debug(&mut self, value: &impl std::fmt::Debug) {
        let mut text = String::new();
        let _ = write!(text, "{value:?}");
        self.0.update(text.as_bytes());
        self.0.update(&(text.len() as u64).to_le_bytes());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hash_follows_the_content_not_the_path() {
        let scene = Scene::load("scenes/cornell-box.gltf").unwrap();
        let hash = scene_hash(&scene);
        let moved = Scene {
            path: "elsewhere/box.gltf".into(),
            ..scene.clone()
        };
        assert_eq!(scene_hash(&moved), hash);
        let mut nudged = scene.clone();
        nudged.mesh.positions[0].x += 1e-6;
        assert_ne!(scene_hash(&nudged), hash);
        let mut recolored = scene.clone();
        recolored.materials[0] = recolored.materials[1].clone();
        assert_ne!(scene_hash(&recolored), hash);
        let other = Scene::load("scenes/cornell-water.gltf").unwrap();
        assert_ne!(scene_hash(&other), hash);
    }
}
