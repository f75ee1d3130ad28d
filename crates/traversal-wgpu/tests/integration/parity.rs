//! The GPU backend against the CPU backend on the same rays, for every scene in `scenes/`:
//! camera rays, incoherent rays, diffuse bounces from the camera hits and finite shadow rays.

use glam::{Vec2, Vec3};
use vcm_scene::Scene;
use vcm_scene::sampling::{Rng, Sampler, sample_uniform_sphere};
use vcm_traversal::{CpuBvh, CpuBvhOptions, HitBatch, RayBatch, Traversal};
use vcm_traversal_wgpu::{GpuBvh, GpuBvhOptions, NodeLayout};

use crate::common::{Agreement, compare, gpu, random_rays};

const SCENES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes");

/// Camera rays through a `size`² grid of jittered pixel positions.
fn camera_rays(scene: &Scene, rng: &mut Rng, size: u32) -> RayBatch {
    let mut rays = RayBatch::with_capacity((size * size) as usize);
    for y in 0..size {
        for x in 0..size {
            let raster = Vec2::new(x as f32, y as f32) + rng.uniform2();
            let direction = scene.camera.direction(size, size, raster);
            rays.push(scene.camera.position, direction, 0.0, f32::INFINITY);
        }
    }
    rays
}

/// From every hit of `primary`: a ray in a random direction and a shadow ray towards a
/// random point of the scene's box that stops short of it.
fn secondary_rays(
    primary: &RayBatch,
    hits: &HitBatch,
    rng: &mut Rng,
    min: Vec3,
    max: Vec3,
) -> [RayBatch; 2] {
    let (mut bounces, mut shadows) = (RayBatch::default(), RayBatch::default());
    let scale = (max - min).length();
    for i in (0..hits.len()).filter(|&i| hits.is_hit(i)) {
        let point = primary.origin(i) + hits.t[i] * primary.direction(i);
        let tmin = 1e-4 * scale;
        bounces.push(
            point,
            sample_uniform_sphere(rng.uniform2()),
            tmin,
            f32::INFINITY,
        );
        let target = min + (max - min) * Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
        shadows.push(point, target - point, tmin / scale, 1.0 - 1e-4);
    }
    [bounces, shadows]
}

fn assert_parity(name: &str, kind: &str, agreement: &Agreement, total: usize) {
    eprintln!("{name} {kind}: {agreement:?} of {total}");
    assert_eq!(agreement.same + agreement.ties + agreement.different, total);
    assert_eq!(
        agreement.different, 0,
        "{name} {kind}: rays that disagree beyond ties"
    );
    assert!(
        agreement.same as f64 >= 0.9999 * total as f64,
        "{name} {kind}: only {} of {total} rays report the same primitive",
        agreement.same
    );
}

#[test]
fn every_scene_matches_the_cpu_backend() {
    let Some(device) = gpu().map(std::sync::Arc::new) else {
        return;
    };
    let mut paths: Vec<_> = std::fs::read_dir(SCENES)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "gltf"))
        .collect();
    paths.sort();
    assert!(
        paths.len() >= 6,
        "expected the generated scenes in {SCENES}"
    );
    for path in paths {
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let scene = Scene::load(&path).unwrap();
        let triangles = scene.triangle_corners();
        let cpu = CpuBvh::new(&triangles, CpuBvhOptions::default()).unwrap();
        let gpus = [NodeLayout::Binary, NodeLayout::Wide].map(|layout| {
            let options = GpuBvhOptions {
                layout,
                ..GpuBvhOptions::default()
            };
            (
                layout,
                GpuBvh::new(device.clone(), &triangles, options).unwrap(),
            )
        });
        let bounds = scene.mesh.bounds();
        let mut rng = Rng::new(7, 0);
        let camera = camera_rays(&scene, &mut rng, 192);
        let incoherent = random_rays(&mut rng, bounds.min, bounds.max, 30_000);
        let mut cpu_hits = HitBatch::default();
        cpu.intersect(&camera, &mut cpu_hits);
        let [bounces, shadows] =
            secondary_rays(&camera, &cpu_hits, &mut rng, bounds.min, bounds.max);
        for (layout, gpu) in &gpus {
            let name = format!("{name} ({layout:?})");
            for (kind, rays) in [
                ("camera", &camera),
                ("incoherent", &incoherent),
                ("bounce", &bounces),
            ] {
                let (mut a, mut b) = (HitBatch::default(), HitBatch::default());
                cpu.intersect(rays, &mut a);
                gpu.intersect(rays, &mut b);
                assert_parity(&name, kind, &compare(&a, &b), rays.len());
            }
            let (mut a, mut b) = (Vec::new(), Vec::new());
            cpu.occluded(&shadows, &mut a);
            gpu.occluded(&shadows, &mut b);
            let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
            eprintln!("{name} shadow: {differ} of {} differ", shadows.len());
            assert!(
                differ as f64 <= 1e-4 * shadows.len() as f64,
                "{name}: {differ} shadow rays differ"
            );
        }
    }
}
