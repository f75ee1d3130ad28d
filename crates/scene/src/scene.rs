//! The loaded scene: geometry, materials, textures, lights, camera and what the scene contains.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use crate::bsdf::{Bsdf, Lobes};
use crate::camera::{Camera, FileCamera};
use crate::error::SceneError;
use crate::features::SceneFeatures;
use crate::light::{AreaLight, HitEmission, Light, LightSampler};
use crate::material::{AlphaMode, Material};
use crate::mesh::{Mesh, SurfacePoint};
use crate::shading_plan::ShadingPlan;
use crate::texture::Texture;

/// A scene ready to render. Immutable once built; share it by reference across threads.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The file the scene was loaded from.
    pub path: PathBuf,
    /// All triangles in world space.
    pub mesh: Mesh,
    /// Materials, indexed by [`Mesh::material_ids`].
    pub materials: Vec<Material>,
    /// Per material, its BSDF lobes when neither a texture nor a vertex color changes them
    /// (built once from `materials` by [`Scene::new`]; `None` for the others, whose lobes
    /// are built at every hit).
    pub material_lobes: Vec<Option<Lobes>>,
    /// Textures, indexed by [`crate::TextureRef::index`].
    pub textures: Vec<Texture>,
    /// Lights: one area light per emissive triangle, then punctual, directional and
    /// environment lights.
    pub lights: Vec<Light>,
    /// Power-proportional light selection.
    pub light_sampler: LightSampler,
    /// The camera rendered from: the file's first camera ([`Scene::cameras`]), another one
    /// chosen with [`Scene::use_camera`], or one framing the scene when the file has none.
    pub camera: Camera,
    /// The perspective cameras that the file's nodes place, in the order the node hierarchy
    /// is walked (depth first, children in order); empty for OBJ files and scenes built
    /// with [`Scene::new`].
    pub cameras: Vec<FileCamera>,
    /// What the scene contains, for integrators and pipelines to leave out what it does not need.
    pub features: SceneFeatures,
    /// The per-hit work shading does, chosen from `features`; set it to [`ShadingPlan::FULL`]
    /// to compare against a render that leaves nothing out.
    pub shading: ShadingPlan,
    /// Unsupported features and dropped data, each reported once, naming the file.
    pub warnings: Vec<String>,
    /// Zero-area triangles dropped while loading.
    pub dropped_triangles: usize,
}

impl Scene {
    /// Loads a glTF (`.gltf`, `.glb`) or OBJ (`.obj`) file with the default
    /// [`LoadOptions`](crate::LoadOptions).
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        crate::loader::load(path.as_ref())
    }

    /// Loads a glTF (`.gltf`, `.glb`) or OBJ (`.obj`) file within `options` (how many
    /// triangles it may expand to, whether it may read files outside its folder).
    pub fn load_with(
        path: impl AsRef<Path>,
        options: &crate::LoadOptions,
    ) -> Result<Scene, SceneError> {
        crate::loader::load_with(path.as_ref(), options)
    }

    /// Assembles a scene from parts: area lights are made for every emissive triangle and
    /// placed before `punctual_lights`.
    pub fn new(
        path: PathBuf,
        mesh: Mesh,
        materials: Vec<Material>,
        textures: Vec<Texture>,
        punctual_lights: Vec<Light>,
        camera: Camera,
        warnings: Vec<String>,
    ) -> Scene {
        let mut lights: Vec<Light> = (0..mesh.triangle_count())
            .filter_map(|t| {
                let material = &materials[mesh.material_ids[t] as usize];
                material.is_emissive().then(|| {
                    Light::Area(AreaLight {
                        triangle: t as u32,
                        corners: mesh.corners(t),
                        uvs: mesh.triangles[t].map(|i| mesh.uvs[i as usize]),
                        normal: mesh.geometric_normal(t),
                        area: mesh.area(t),
                        emission: material.emission,
                        texture: material.emissive_texture,
                        cut_out: material.alpha_mask(),
                    })
                })
            })
            .collect();
        lights.extend(punctual_lights);
        let light_sampler = LightSampler::new(&lights, &textures, mesh.triangle_count());
        let features = SceneFeatures::of(&mesh, &materials, &textures, &lights);
        let material_lobes = materials
            .iter()
            .zip(mesh.tinted_materials(materials.len()))
            .map(|(m, tinted)| {
                let uniform = m.uniform_bsdf_params().filter(|_| !tinted);
                uniform.map(|params| Lobes::new(&params))
            })
            .collect();
        Scene {
            path,
            mesh,
            materials,
            material_lobes,
            textures,
            lights,
            light_sampler,
            camera,
            cameras: Vec::new(),
            features,
            shading: ShadingPlan::for_features(&features),
            warnings,
            dropped_triangles: 0,
        }
    }

    /// Renders from the file's camera `choice`: a number is the index of a camera in the
    /// file's `cameras` array, anything else the name of a camera or of the node that places
    /// it. Where several nodes place the same camera, or several cameras share a name, the
    /// first in [`Scene::cameras`] is taken. Fails, listing the cameras there are, when none
    /// matches (orthographic and degenerate cameras are not among them: loading warned about
    /// them).
    pub fn use_camera(&mut self, choice: &str) -> Result<(), SceneError> {
        let by_index = choice
            .parse::<usize>()
            .ok()
            .and_then(|index| self.cameras.iter().find(|c| c.index == index));
        let chosen = by_index.or_else(|| self.cameras.iter().find(|c| c.is_named(choice)));
        if let Some(chosen) = chosen {
            self.camera = chosen.camera;
            return Ok(());
        }
        let reason = if self.cameras.is_empty() {
            "the file places no perspective camera".to_string()
        } else {
            let list: Vec<String> = self.cameras.iter().map(ToString::to_string).collect();
            format!("the file's cameras are {}", list.join(", "))
        };
        Err(SceneError::Camera {
            path: self.path.clone(),
            choice: choice.to_string(),
            reason,
        })
    }

    /// The material of triangle `triangle`.
    #[inline]
    pub fn material_of(&self, triangle: u32) -> &Material {
        &self.materials[self.mesh.material_ids[triangle as usize] as usize]
    }

    /// The surface point at barycentrics (u, v) of `triangle`, with the normal map applied
    /// (texture coordinates and normal maps as far as [`Scene::shading`] plans them).
    #[inline]
    pub fn surface_point(&self, triangle: u32, u: f32, v: f32) -> SurfacePoint {
        let t = triangle as usize;
        let plan = &self.shading;
        let uv = if plan.texture_coordinates || plan.normal_maps {
            self.mesh.uv_at(t, u, v)
        } else {
            Vec2::ZERO
        };
        let normal_map = if plan.normal_maps {
            let material = self.material_of(triangle);
            material
                .normal_texture
                .and_then(|_| material.tangent_space_normal(&self.textures, uv))
        } else {
            None
        };
        self.mesh.surface_point(t, u, v, uv, normal_map)
    }

    /// The BSDF at a surface point.
    #[inline]
    pub fn bsdf(&self, point: &SurfacePoint) -> Bsdf {
        let index = point.material as usize;
        let material = &self.materials[index];
        let (n_g, n_s) = (point.geometric_normal, point.shading_normal);
        match &self.material_lobes[index] {
            Some(lobes) => Bsdf::from_lobes(lobes, n_g, n_s, material.double_sided),
            None => {
                let mut params = material.bsdf_params(&self.textures, point.uv);
                params.base_color *= point.vertex_color;
                Bsdf::new(&params, n_g, n_s, material.double_sided)
            }
        }
    }

    /// Emission seen by a ray with unit direction `ray_dir` that hits `triangle` at (u, v), or
    /// `None` when the triangle does not emit toward the ray.
    #[inline]
    pub fn emission_on_hit(
        &self,
        triangle: u32,
        u: f32,
        v: f32,
        ray_dir: Vec3,
    ) -> Option<HitEmission> {
        if !self.shading.emitter_lookups {
            return None;
        }
        let light = self.light_sampler.light_of_triangle(triangle)?;
        match &self.lights[light] {
            Light::Area(area) => area.radiance_on_hit(&self.textures, ray_dir, u, v),
            _ => None,
        }
    }

    /// Radiance from the environment seen by a path that leaves the scene along the unit
    /// `direction`, with the environment light's index; `None` without an environment.
    #[inline]
    pub fn emission_on_escape(&self, direction: Vec3) -> Option<(usize, HitEmission)> {
        let index = self.light_sampler.environment()?;
        match &self.lights[index] {
            Light::Environment(environment) => {
                Some((index, environment.radiance_on_escape(direction)))
            }
            _ => None,
        }
    }

    /// True when triangle `triangle` has an alpha-masked material.
    pub fn is_alpha_masked(&self, triangle: u32) -> bool {
        matches!(
            self.material_of(triangle).alpha_mode,
            AlphaMode::Mask { .. }
        )
    }

    /// For alpha-masked triangles: whether the surface is present at barycentrics (u, v).
    pub fn is_opaque_at(&self, triangle: u32, u: f32, v: f32) -> bool {
        let uv = self.mesh.uv_at(triangle as usize, u, v);
        self.material_of(triangle).is_opaque_at(&self.textures, uv)
    }

    /// Triangle corner positions in mesh order, the input of a traversal backend.
    pub fn triangle_corners(&self) -> Vec<[Vec3; 3]> {
        (0..self.mesh.triangle_count())
            .map(|t| self.mesh.corners(t))
            .collect()
    }
}
