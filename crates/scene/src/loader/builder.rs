//! Collects what a loader reads, validates geometry, and assembles the [`Scene`].

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use crate::camera::{Camera, FileCamera};
use crate::error::SceneError;
use crate::light::{DirectionalLight, EnvironmentLight, EnvironmentMap, Light};
use crate::loader::options::LoadOptions;
use crate::material::{AlphaMode, Material};
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::texture::Texture;

/// The largest magnitude a vertex coordinate may have: 10¹⁸. Rendering squares distances
/// and multiplies edge vectors (areas, normals, pdf conversions); with coordinates up to
/// 10¹⁸, differences stay below 2·10¹⁸ and their squares and cross products below 10³⁸,
/// within single precision (3.4·10³⁸). Beyond it a triangle's area overflows to infinity,
/// which no later stage can work with.
const MAX_COORDINATE: f32 = 1e18;

/// One triangle primitive as read from a file, already in world space.
pub(crate) struct Primitive {
    /// For messages: e.g. `mesh 'Bottle' primitive 0`.
    pub name: String,
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub tangents: Option<Vec<Vec4>>,
    /// Linear RGBA vertex colors (glTF `COLOR_0`).
    pub colors: Option<Vec<Vec4>>,
    /// Indices into `positions`, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    pub material: u32,
}

/// A directional light waiting for the scene bounds (its emission disk covers the scene).
struct PendingDirectional {
    direction: Vec3,
    irradiance: Vec3,
}

/// Accumulates a scene while a loader reads a file.
pub(crate) struct SceneBuilder {
    path: PathBuf,
    mesh: Mesh,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    lights: Vec<Light>,
    directional: Vec<PendingDirectional>,
    /// The environment's radiance (and image), placed around the scene once its bounds are
    /// known.
    environment: Option<(Vec3, Option<Arc<EnvironmentMap>>)>,
    /// The file's usable cameras, in the order the loader met them.
    pub cameras: Vec<FileCamera>,
    warnings: Vec<String>,
    degenerate_triangles: usize,
    /// Most triangles and vertices the mesh may reach (the load options').
    max_triangles: u64,
    max_vertices: u64,
    /// Texels the textures may still decode to (the load options' `max_texels`, less those
    /// decoded).
    texels_left: u64,
    max_texels: u64,
}

impl SceneBuilder {
    pub fn new(path: &Path, options: &LoadOptions) -> Self {
        SceneBuilder {
            path: path.to_path_buf(),
            mesh: Mesh::default(),
            materials: Vec::new(),
            textures: Vec::new(),
            lights: Vec::new(),
            directional: Vec::new(),
            environment: None,
            cameras: Vec::new(),
            warnings: Vec::new(),
            degenerate_triangles: 0,
            max_triangles: options.max_triangles,
            max_vertices: options.max_vertices(),
            texels_left: options.max_texels,
            max_texels: options.max_texels,
        }
    }

    /// Takes `width` × `height` texels for the image `name` out of what the load options
    /// let the textures decode to; `Err` when they do not fit.
    pub fn reserve_texels(
        &mut self,
        name: &str,
        width: u32,
        height: u32,
    ) -> Result<(), SceneError> {
        let texels = u64::from(width) * u64::from(height);
        match self.texels_left.checked_sub(texels) {
            Some(left) => {
                self.texels_left = left;
                Ok(())
            }
            None => {
                let reason = format!(
                    "texture {name}: its {width} × {height} texels take the textures past the \
                     {} texels the load options allow (max_texels)",
                    self.max_texels
                );
                Err(SceneError::too_large(&self.path, reason))
            }
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Records a warning once (repeated identical warnings are dropped).
    pub fn warn(&mut self, message: impl Into<String>) {
        let message = message.into();
        if !self.warnings.contains(&message) {
            self.warnings.push(message);
        }
    }

    /// Warns (once) that `feature` of the file is not supported and is ignored.
    pub fn warn_unsupported(&mut self, feature: &str) {
        let message = format!(
            "{}: {feature} is not supported and is ignored",
            self.path().display()
        );
        self.warn(message);
    }

    /// Adds a point or spot light.
    pub fn add_light(&mut self, light: Light) {
        self.lights.push(light);
    }

    /// Adds a directional light travelling along `direction` with irradiance `irradiance`.
    pub fn add_directional(&mut self, direction: Vec3, irradiance: Vec3) {
        self.directional.push(PendingDirectional {
            direction,
            irradiance,
        });
    }

    /// Sets the environment's radiance: constant from every direction, or a scale of `map`.
    pub fn set_environment(&mut self, radiance: Vec3, map: Option<Arc<EnvironmentMap>>) {
        self.environment = Some((radiance, map));
    }

    fn geometry_error(&self, name: &str, reason: String) -> SceneError {
        SceneError::geometry(&self.path, name, reason)
    }

    /// Validates a primitive and appends it; zero-area triangles are dropped and counted.
    pub fn add_primitive(&mut self, p: Primitive) -> Result<(), SceneError> {
        let n = p.positions.len();
        let vertices = (self.mesh.positions.len() + n) as u64;
        let triangles = (self.mesh.triangles.len() + p.triangles.len()) as u64;
        if vertices > self.max_vertices || triangles > self.max_triangles {
            let reason = format!(
                "{}: the scene reaches {triangles} triangles and {vertices} vertices, more than \
                 the load options allow ({} triangles, {} vertices)",
                p.name, self.max_triangles, self.max_vertices
            );
            return Err(SceneError::too_large(&self.path, reason));
        }
        if let Some(i) = p.positions.iter().position(|v| !v.is_finite()) {
            return Err(self.geometry_error(
                &p.name,
                format!("vertex {i} has a non-finite position {}", p.positions[i]),
            ));
        }
        let huge = |v: &Vec3| v.abs().max_element() > MAX_COORDINATE;
        if let Some(i) = p.positions.iter().position(huge) {
            let reason = format!(
                "vertex {i} has position {}, beyond the ±{MAX_COORDINATE:e} within which \
                 distances and areas can be computed in single precision",
                p.positions[i]
            );
            return Err(self.geometry_error(&p.name, reason));
        }
        let lengths = [
            ("normals", p.normals.as_ref().map(Vec::len)),
            ("texture coordinates", p.uvs.as_ref().map(Vec::len)),
            ("tangents", p.tangents.as_ref().map(Vec::len)),
            ("vertex colors", p.colors.as_ref().map(Vec::len)),
        ];
        for (what, len) in lengths {
            if let Some(len) = len.filter(|&len| len != n) {
                let reason = format!("{len} {what} for {n} positions");
                return Err(self.geometry_error(&p.name, reason));
            }
        }
        let finite_attributes = p.normals.iter().flatten().all(|v| v.is_finite())
            && p.uvs.iter().flatten().all(|v| v.is_finite())
            && p.tangents.iter().flatten().all(|v| v.is_finite())
            && p.colors.iter().flatten().all(|v| v.is_finite());
        if !finite_attributes {
            let reason =
                "non-finite normal, texture coordinate, tangent or vertex color".to_string();
            return Err(self.geometry_error(&p.name, reason));
        }
        if let Some(tri) = p
            .triangles
            .iter()
            .find(|t| t.iter().any(|&i| i as usize >= n))
        {
            let reason = format!("triangle {tri:?} indexes past the {n} vertices");
            return Err(self.geometry_error(&p.name, reason));
        }
        let material = p.material;
        if material as usize >= self.materials.len() {
            let reason = format!("material {material} does not exist");
            return Err(self.geometry_error(&p.name, reason));
        }

        if let Some(colors) = &p.colors {
            self.add_colors(&p.name, material, colors);
        } else if !self.mesh.colors.is_empty() {
            self.mesh.colors.extend(std::iter::repeat_n(Vec3::ONE, n));
        }
        let base = self.mesh.positions.len() as u32;
        let first_triangle = self.mesh.triangles.len();
        self.mesh.normals.extend(match p.normals {
            Some(normals) => normals.iter().map(|v| v.normalize_or_zero()).collect(),
            None => vec![Vec3::ZERO; n],
        });
        self.mesh
            .uvs
            .extend(p.uvs.unwrap_or_else(|| vec![Vec2::ZERO; n]));
        let has_tangents = p.tangents.is_some();
        self.mesh
            .tangents
            .extend(p.tangents.unwrap_or_else(|| vec![Vec4::ZERO; n]));
        for tri in &p.triangles {
            let [a, b, c] = tri.map(|i| p.positions[i as usize]);
            let area = 0.5 * (b - a).cross(c - a).length();
            if area > 0.0 && area.is_finite() {
                self.mesh.triangles.push(tri.map(|i| i + base));
                self.mesh.material_ids.push(material);
            } else {
                self.degenerate_triangles += 1;
            }
        }
        self.mesh.positions.extend(p.positions);
        let needs_tangents = self.materials[material as usize].normal_texture.is_some();
        if needs_tangents && !has_tangents {
            self.mesh
                .generate_tangents(first_triangle..self.mesh.triangles.len());
        }
        Ok(())
    }

    /// Appends a primitive's vertex colors (clamped to [0, 1]) before its vertices are
    /// added. The mesh keeps none until some vertex is not white; from then on, one per
    /// vertex (white for the vertices before).
    fn add_colors(&mut self, name: &str, material: u32, colors: &[Vec4]) {
        let masked = matches!(
            self.materials[material as usize].alpha_mode,
            AlphaMode::Mask { .. }
        );
        if masked && colors.iter().any(|c| c.w < 1.0) {
            let message = format!(
                "{}: {name}: COLOR_0 alpha does not cut out alpha-masked surfaces (the \
                 material's alpha alone does)",
                self.path.display()
            );
            self.warn(message);
        }
        let rgb = colors
            .iter()
            .map(|c| c.truncate().clamp(Vec3::ZERO, Vec3::ONE));
        if self.mesh.colors.is_empty() {
            if rgb.clone().all(|c| c == Vec3::ONE) {
                return;
            }
            self.mesh.colors = vec![Vec3::ONE; self.mesh.positions.len()];
        }
        self.mesh.colors.extend(rgb);
    }

    /// Finishes the scene: builds area lights, directional lights, the default camera.
    pub fn finish(mut self) -> Scene {
        if self.degenerate_triangles > 0 {
            let count = self.degenerate_triangles;
            self.warn(format!("dropped {count} degenerate (zero-area) triangles"));
        }
        let bounds = self.mesh.bounds();
        let (scene_center, scene_radius) = if bounds.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            (bounds.center(), bounds.radius().max(f32::MIN_POSITIVE))
        };
        for pending in std::mem::take(&mut self.directional) {
            self.lights.push(Light::Directional(DirectionalLight {
                direction: pending.direction,
                irradiance: pending.irradiance,
                scene_center,
                scene_radius,
            }));
        }
        if let Some((radiance, map)) = self.environment.take() {
            self.lights.push(Light::Environment(EnvironmentLight {
                radiance,
                map,
                scene_center,
                scene_radius,
            }));
        }
        let camera = self
            .cameras
            .first()
            .map_or_else(|| Camera::framing(&bounds), |c| c.camera);
        let mut scene = Scene::new(
            self.path,
            self.mesh,
            self.materials,
            self.textures,
            self.lights,
            camera,
            self.warnings,
        );
        scene.dropped_triangles = self.degenerate_triangles;
        scene.cameras = self.cameras;
        scene
    }
}
