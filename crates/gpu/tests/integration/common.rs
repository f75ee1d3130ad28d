//! Shared helpers: the adapter (or a clear skip), scenes, and the images of the CPU's and
//! the GPU's path tracers and light tracers.

use std::path::PathBuf;
use std::sync::Arc;

use glam::Vec3;
use vcm::{Film, Integrator, PathTracer, PtSettings, Schedule, Vcm, VcmSettings};
use vcm_gpu::{GpuBidirectional, GpuPathTracer};
use vcm_scene::Scene;
use vcm_traversal::{CpuBvh, CpuBvhOptions};
use vcm_traversal_wgpu::{GpuBvh, GpuBvhOptions, GpuDevice};

/// The preferred adapter, or `None` (with a note on stderr) when there is none and
/// `VCM_REQUIRE_GPU` is not set.
pub fn gpu() -> Option<Arc<GpuDevice>> {
    vcm_traversal_wgpu::device_or_skip().map(Arc::new)
}

/// A scene of the repository's `scenes/`.
pub fn scene(name: &str) -> Arc<Scene> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../../scenes/{name}.gltf"));
    Arc::new(Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())))
}

/// A model of `../shared/scenes/khronos-samples/` (beside the checkout), lit by a point light
/// and a dim sky.
pub fn lit_khronos_model(file: &str) -> Arc<Scene> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/scenes/khronos-samples")
        .join(file);
    let loaded = Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Arc::new(vcm_scene::relight::lit_by_bulb_and_sky(loaded))
}

/// A scene of `scenes/` with its glTF changed by `edit` (written to a temporary folder).
pub fn scene_variant(name: &str, edit: impl FnOnce(&mut serde_json::Value)) -> Arc<Scene> {
    scene_variant_with(name, edit, &[])
}

/// [`scene_variant`] with `files` (name, bytes) beside the glTF, for it to refer to.
pub fn scene_variant_with(
    name: &str,
    edit: impl FnOnce(&mut serde_json::Value),
    files: &[(&str, &[u8])],
) -> Arc<Scene> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../../scenes/{name}.gltf"));
    let mut gltf: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut gltf);
    let dir = tempfile::tempdir().unwrap();
    for (file, bytes) in files {
        std::fs::write(dir.path().join(file), bytes).unwrap();
    }
    let changed = dir.path().join(format!("{name}.gltf"));
    std::fs::write(&changed, gltf.to_string()).unwrap();
    Arc::new(Scene::load(&changed).unwrap_or_else(|e| panic!("{name} variant: {e}")))
}

/// The mean radiance per pixel after `frames` frames of `samples` samples per pixel each.
pub fn render(integrator: &mut dyn Integrator, frames: u32, samples: u32) -> Vec<Vec3> {
    let (width, height) = integrator.image_size();
    integrator
        .set_schedule(Schedule {
            samples_per_frame: samples,
            ..Schedule::ONE_BATCH
        })
        .unwrap();
    let mut film = Film::new(width, height);
    for frame in 0..frames {
        integrator.render_frame(&mut film, frame * samples);
    }
    film.mean()
}

/// The CPU's hierarchy over `scene`.
fn cpu_bvh(scene: &Scene) -> Arc<CpuBvh> {
    Arc::new(CpuBvh::new(&scene.triangle_corners(), CpuBvhOptions::default()).unwrap())
}

/// The GPU backend's hierarchy over `scene`.
fn gpu_bvh(gpu: &Arc<GpuDevice>, scene: &Scene) -> GpuBvh {
    GpuBvh::new(
        Arc::clone(gpu),
        &scene.triangle_corners(),
        GpuBvhOptions::default(),
    )
    .unwrap()
}

/// The CPU path tracer's image of `scene`.
pub fn cpu_image(scene: &Arc<Scene>, settings: PtSettings, frames: u32, samples: u32) -> Vec<Vec3> {
    let mut tracer = PathTracer::new(Arc::clone(scene), cpu_bvh(scene), settings).unwrap();
    render(&mut tracer, frames, samples)
}

/// The GPU path tracer's image of `scene`.
pub fn gpu_image(
    gpu: &Arc<GpuDevice>,
    scene: &Arc<Scene>,
    settings: PtSettings,
    frames: u32,
    samples: u32,
) -> Vec<Vec3> {
    let bvh = gpu_bvh(gpu, scene);
    let mut tracer = GpuPathTracer::new(Arc::clone(scene), &bvh, settings).unwrap();
    render(&mut tracer, frames, samples)
}

/// The CPU's image of `scene` with a bidirectional algorithm (`settings.algorithm`).
pub fn cpu_bidir_image(
    scene: &Arc<Scene>,
    settings: VcmSettings,
    frames: u32,
    samples: u32,
) -> Vec<Vec3> {
    let mut integrator = Vcm::new(Arc::clone(scene), cpu_bvh(scene), settings).unwrap();
    render(&mut integrator, frames, samples)
}

/// The GPU's image of `scene` with a bidirectional algorithm (`settings.algorithm`).
pub fn gpu_bidir_image(
    gpu: &Arc<GpuDevice>,
    scene: &Arc<Scene>,
    settings: VcmSettings,
    frames: u32,
    samples: u32,
) -> Vec<Vec3> {
    let bvh = gpu_bvh(gpu, scene);
    let mut tracer = GpuBidirectional::new(Arc::clone(scene), &bvh, settings).unwrap();
    render(&mut tracer, frames, samples)
}
