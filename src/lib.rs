//! # vcm-rs
//!
//! A physically based renderer built around Vertex Connection and Merging. This crate is the
//! facade: it re-exports the workspace crates and connects them.
//!
//! - [`scene`]: loading glTF/OBJ scenes, materials, BSDFs, lights, camera, [`scene::SceneFeatures`].
//! - [`traversal`]: the [`traversal::Traversal`] trait over ray batches and its CPU backend.
//! - [`traversal_wgpu`]: the GPU backend (WGSL compute shaders through wgpu).
//! - [`vcm`]: the integrators themselves, the [`vcm::Film`] they accumulate into and image I/O.
//! - [`Backend`]: the traversal backends, chosen at run time.
//! - [`integrators`]: the light transport algorithms, their options and one builder for all.
//! - [`render_loop`]: the render loop: each frame's schedule and size, frames until a sample
//!   or time budget is spent.
//! - [`plot`]: PNG plots of error, CPU utilization and scheduler speed-ups.
//! - [`state`]: a render's state as a value and a file: checkpoint, resume, shards, merge.
//!
//! Rendering an image: a scene, a traversal backend, an integrator from the builder, frames
//! into a film (one sample per pixel per frame by default; frame `i` renders sample `i`, and
//! the image is a pure function of the scene, the options and the seed):
//!
//! ```
//! use std::sync::Arc;
//! use vcm_rs::integrators::{self, Algorithm, IntegratorOptions};
//! use vcm_rs::vcm::Film;
//!
//! let scene = Arc::new(vcm_rs::scene::Scene::load("scenes/cornell-box.gltf")?);
//! let traversal = Arc::new(vcm_rs::cpu_traversal(&scene)?);
//! let (width, height) = integrators::image_size(&scene, 48, None); // height from the camera
//! let options = IntegratorOptions {
//!     seed: 7,
//!     ..IntegratorOptions::default()
//! };
//! let mut vcm = integrators::build(Algorithm::Vcm, &scene, traversal, (width, height), &options)?;
//! let mut film = Film::new(width, height);
//! for sample in 0..4 {
//!     vcm.render_frame(&mut film, sample);
//! }
//! let image = film.image(); // mean radiance per pixel, row by row from the top left
//! assert_eq!(image.pixels.len(), (width * height) as usize);
//! assert!(image.pixels.iter().all(|p| p.is_finite() && p.min_element() >= 0.0));
//! let exr = std::env::temp_dir().join(format!("vcm-rs-doc-{}.exr", std::process::id()));
//! image.write_exr(&exr)?; // through a temporary file, renamed when complete
//! # std::fs::remove_file(&exr)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Tracing rays directly:
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

#![warn(missing_docs)]

use std::sync::Arc;

mod backend;
pub mod integrators;
pub mod plot;
pub mod render_loop;
pub mod state;

pub use vcm;
pub use vcm_gpu as gpu;
pub use vcm_scene as scene;
pub use vcm_traversal as traversal;
pub use vcm_traversal_wgpu as traversal_wgpu;

pub use backend::{Backend, BackendError, BuiltTraversal, Shading, Traversals};

use vcm_scene::texture::{Filter, UvTransform, WrapMode};
use vcm_scene::{Scene, Texture};
use vcm_traversal::{AlphaTest, BuildError, CpuBvh, CpuBvhOptions};
use vcm_traversal_wgpu::{
    AlphaMasks, AlphaTexture, Filter as GpuFilter, GpuBvh, GpuBvhOptions, GpuDevice, GpuError,
    MaskedTriangle, Wrap,
};

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

/// Builds the GPU traversal backend for `scene` on the preferred adapter (a hardware GPU,
/// else Mesa's lavapipe). Fails with instructions when there is no adapter at all. As on
/// the CPU, the kernels carry alpha-mask code only when the scene has alpha masks.
pub fn gpu_traversal(scene: &Arc<Scene>) -> Result<GpuBvh, GpuError> {
    let gpu = Arc::new(GpuDevice::open()?);
    let triangles = scene.triangle_corners();
    let options = GpuBvhOptions::default();
    if scene.features.alpha_masks {
        GpuBvh::with_alpha_masks(gpu, &triangles, options, &alpha_masks(scene))
    } else {
        GpuBvh::new(gpu, &triangles, options)
    }
}

/// The scene's alpha-masked triangles and the alpha channels of their textures, for the GPU.
pub fn alpha_masks(scene: &Scene) -> AlphaMasks {
    let mut textures = Vec::new();
    // Scene texture index → index in `textures`, for textures that masks use.
    let mut used = vec![None; scene.textures.len()];
    let triangles = (0..scene.mesh.triangle_count() as u32)
        .map(|t| {
            let mask = scene.material_of(t).alpha_mask()?;
            let texture = mask.texture.map(|r| {
                *used[r.index].get_or_insert_with(|| {
                    textures.push(alpha_texture(&scene.textures[r.index]));
                    textures.len() as u32 - 1
                })
            });
            // The transform is affine, so transforming the corners transforms every point.
            let transform = mask.texture.map_or(UvTransform::IDENTITY, |r| r.transform);
            let corner = |u, v| transform.apply(scene.mesh.uv_at(t as usize, u, v));
            Some(MaskedTriangle {
                uvs: [corner(0.0, 0.0), corner(1.0, 0.0), corner(0.0, 1.0)],
                texture,
                alpha_factor: mask.alpha,
                cutoff: mask.cutoff,
            })
        })
        .collect();
    AlphaMasks {
        textures,
        triangles,
    }
}

/// The alpha channel of `texture` with its wrap modes and filter.
fn alpha_texture(texture: &Texture) -> AlphaTexture {
    let wrap = |mode| match mode {
        WrapMode::Repeat => Wrap::Repeat,
        WrapMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrapMode::ClampToEdge => Wrap::ClampToEdge,
    };
    let (width, height) = (texture.width(), texture.height());
    let alpha = (0..height)
        .flat_map(|y| (0..width).map(move |x| (texture.texel(x, y).w * 255.0).round() as u8))
        .collect();
    AlphaTexture {
        width,
        height,
        wrap: [wrap(texture.wrap_u), wrap(texture.wrap_v)],
        filter: match texture.filter {
            Filter::Bilinear => GpuFilter::Bilinear,
            Filter::Nearest => GpuFilter::Nearest,
        },
        alpha,
    }
}
