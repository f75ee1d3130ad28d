//! # vcm-rs
//!
//! A physically based renderer built around Vertex Connection and Merging. This crate is the
//! facade: it re-exports the workspace crates and connects them.
//!
//! - [`scene`]: loading glTF/OBJ scenes, materials, BSDFs, lights, camera, [`scene::SceneFeatures`].
//! - [`traversal`]: the [`traversal::Traversal`] trait over ray batches and its CPU backend.
//! - [`Backend`]: the traversal backends, chosen at run time.
//! - [`integrators`]: the light transport algorithms, their options and one builder for all.
//!
//! ```no_run
//! use vcm_rs::traversal::{HitBatch, RayBatch, Traversal};
//!
//! let scene = std::sync::Arc::new(vcm_rs::scene::Scene::load("scenes/cornell-box.gltf")?);
//! let bvh = vcm_rs::cpu_traversal(&scene)?;
//! let mut rays = RayBatch::default();
//! let (origin, dir) = (scene.camera.position, scene.camera.forward);
//! rays.push(origin, dir, 0.0, f32::INFINITY);
//! let mut hits = HitBatch::default();
//! bvh.intersect(&rays, &mut hits);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::sync::Arc;

mod backend;
pub mod integrators;

pub use vcm_scene as scene;
pub use vcm_traversal as traversal;

pub use backend::Backend;

use vcm_scene::Scene;
use vcm_traversal::{AlphaTest, BuildError, CpuBvh, CpuBvhOptions};

/// The scene's alpha masks as seen by a traversal backend.
struct SceneAlpha(Arc<Scene>);

impl AlphaTest for SceneAlpha {
    fn is_masked(&self, prim: u32) -> bool {
        self.0.is_alpha_masked(prim)
    }

    fn is_opaque_at(&self, prim: u32, u: f32, v: f32) -> bool {
        self.0.is_opaque_at(prim, u, v)
    }
}

/// Builds the CPU traversal backend for `scene`. Alpha-masked triangles are tested against
/// their texture only when the scene has alpha masks; otherwise no alpha code runs.
pub fn cpu_traversal(scene: &Arc<Scene>) -> Result<CpuBvh, BuildError> {
    let triangles = scene.triangle_corners();
    let options = CpuBvhOptions::default();
    if scene.features.alpha_masks {
        let alpha = Arc::new(SceneAlpha(Arc::clone(scene)));
        CpuBvh::with_alpha_test(&triangles, options, alpha)
    } else {
        CpuBvh::new(&triangles, options)
    }
}
