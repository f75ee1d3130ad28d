//! # vcm-scene
//!
//! Everything a renderer needs to know about a scene: loading glTF 2.0 and Wavefront OBJ/MTL
//! files, triangle geometry in world space, materials and their BSDFs, textures, lights with
//! their sampling routines, the camera, and [`SceneFeatures`] (what the scene contains, so that
//! renderers can leave out what it does not need; [`ShadingPlan`] leaves out per-hit work).
//!
//! The mapping from file contents to physics follows the project's scene conventions: linear
//! Rec.709 RGB, sRGB-decoded color textures, glTF metallic-roughness materials with the
//! `KHR_materials_{specular, transmission, ior, volume, emissive_strength}` extensions,
//! one-sided area emission from the front face, and `KHR_lights_punctual` point, spot and
//! directional lights in radiometric units.
//!
//! ```no_run
//! let scene = vcm_scene::Scene::load("scenes/cornell-box.gltf")?;
//! println!("{} triangles, {} lights", scene.mesh.triangle_count(), scene.lights.len());
//! for warning in &scene.warnings {
//!     eprintln!("warning: {warning}");
//! }
//! # Ok::<(), vcm_scene::SceneError>(())
//! ```

#![warn(missing_docs)]

pub mod bsdf;
pub mod camera;
pub mod decision;
pub mod error;
pub mod features;
pub mod frame;
pub mod image_limits;
pub mod light;
pub mod loader;
pub mod material;
pub mod mesh;
pub mod real;
pub mod relight;
pub mod sampling;
pub mod scene;
pub mod shading_plan;
pub mod shapes;
pub mod testing;
pub mod texture;

pub use camera::{Camera, FileCamera, Projection};
pub use decision::Decision;
pub use error::SceneError;
pub use features::SceneFeatures;
pub use loader::LoadOptions;
pub use material::{AlphaMode, Material};
pub use mesh::{Bounds, Mesh, SurfacePoint};
pub use real::Real;
pub use scene::Scene;
pub use shading_plan::ShadingPlan;
pub use texture::{Filter, Texture, TextureRef, UvTransform};
