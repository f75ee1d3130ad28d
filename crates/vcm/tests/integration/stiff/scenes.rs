//! Scenes assembled in code, placed anywhere at any scale.

use glam::Vec3;
use vcm_scene::light::Light;
use vcm_scene::{Camera, Material, Scene};

use crate::common;

/// A similarity transform x ↦ scale · x + offset applied to a whole scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Uniform scale factor.
    pub scale: f32,
    /// Translation after scaling (scene units).
    pub offset: Vec3,
}

impl Placement {
    /// The scene as built.
    pub const IDENTITY: Placement = Placement {
        scale: 1.0,
        offset: Vec3::ZERO,
    };

    /// Scaled by `scale` around the origin.
    pub fn scaled(scale: f32) -> Placement {
        Placement {
            scale,
            offset: Vec3::ZERO,
        }
    }

    fn apply(&self, p: Vec3) -> Vec3 {
        p * self.scale + self.offset
    }
}

/// Geometry, materials, lights and a camera, gathered before they become a [`Scene`].
#[derive(Clone, Debug)]
pub struct SceneParts {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    material_ids: Vec<u32>,
    materials: Vec<Material>,
    lights: Vec<Light>,
    camera: Camera,
}

impl SceneParts {
    /// An empty scene seen by `camera`.
    pub fn new(camera: Camera) -> SceneParts {
        SceneParts {
            positions: Vec::new(),
            triangles: Vec::new(),
            material_ids: Vec::new(),
            materials: Vec::new(),
            lights: Vec::new(),
            camera,
        }
    }

    /// Adds `material` and returns its index.
    pub fn material(&mut self, material: Material) -> u32 {
        self.materials.push(material);
        self.materials.len() as u32 - 1
    }

    /// Adds triangles over `positions` (indices local to them) made of `material`.
    pub fn mesh(&mut self, positions: &[Vec3], triangles: &[[u32; 3]], material: u32) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(positions);
        self.triangles
            .extend(triangles.iter().map(|t| t.map(|i| i + base)));
        self.material_ids
            .extend(std::iter::repeat_n(material, triangles.len()));
    }

    /// Adds the quad `corners` (counter-clockwise seen from its front) made of `material`.
    pub fn quad(&mut self, corners: [Vec3; 4], material: u32) {
        self.mesh(&corners, &[[0, 1, 2], [0, 2, 3]], material);
    }

    /// Adds a punctual light.
    pub fn light(&mut self, light: Light) {
        self.lights.push(light);
    }

    /// The scene moved by `placement`: positions and the camera move, point and spot
    /// intensities grow with the square of the scale so that the image stays the same.
    pub fn build(&self, placement: Placement) -> Scene {
        let positions = self.positions.iter().map(|&p| placement.apply(p)).collect();
        let lights = self
            .lights
            .iter()
            .map(|light| place_light(light, placement))
            .collect();
        let camera = Camera {
            position: placement.apply(self.camera.position),
            ..self.camera
        };
        common::scene(
            common::mesh(positions, self.triangles.clone(), self.material_ids.clone()),
            self.materials.clone(),
            lights,
            camera,
        )
    }
}

/// `light` moved by `placement`.
fn place_light(light: &Light, placement: Placement) -> Light {
    let s2 = placement.scale * placement.scale;
    match light.clone() {
        Light::Point(mut point) => {
            point.position = placement.apply(point.position);
            point.intensity *= s2;
            Light::Point(point)
        }
        Light::Spot(mut spot) => {
            spot.position = placement.apply(spot.position);
            spot.intensity *= s2;
            Light::Spot(spot)
        }
        other => panic!("placing {other:?} is not needed by the suite"),
    }
}

/// A camera at `position` looking along `forward` (unit) with `up` roughly up.
pub fn camera_looking(position: Vec3, forward: Vec3, up: Vec3, yfov: f32) -> Camera {
    let right = forward.cross(up).normalize();
    Camera {
        position,
        right,
        up: right.cross(forward),
        forward,
        yfov,
        aspect_ratio: None,
    }
}

/// An emitting material of radiance `radiance` that reflects nothing.
pub fn emitter(radiance: f32) -> Material {
    Material {
        emission: Vec3::splat(radiance),
        ..Material::diffuse("emitter", Vec3::ZERO)
    }
}
