//! Lights for models that come without them (third-party models such as the Khronos
//! samples), for tests and experiments.

use glam::Vec3;

use crate::Scene;
use crate::light::{EnvironmentLight, Light, PointLight};

/// `loaded` with its lights replaced by a point light above the model's front right (its
/// intensity scaled to the model's size) and a dim constant sky.
pub fn lit_by_bulb_and_sky(loaded: Scene) -> Scene {
    let bounds = loaded.mesh.bounds();
    let radius = bounds.radius();
    let sky = Light::Environment(EnvironmentLight {
        radiance: Vec3::new(0.3, 0.35, 0.4),
        map: None,
        scene_center: bounds.center(),
        scene_radius: radius,
    });
    let bulb = Light::Point(PointLight {
        position: bounds.center() + Vec3::new(1.0, 1.2, 1.5) * radius,
        intensity: Vec3::splat(3.0 * radius * radius),
    });
    let Scene {
        path,
        mesh,
        materials,
        textures,
        camera,
        ..
    } = loaded;
    Scene::new(
        path,
        mesh,
        materials,
        textures,
        vec![bulb, sky],
        camera,
        Vec::new(),
    )
}
