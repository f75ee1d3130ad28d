//! Ray traversal throughput of the CPU and GPU backends on the same rays: primary,
//! diffuse-bounce and shadow rays on the committed Cornell box scene and on a ~1M-triangle
//! procedural scene, plus BVH build time and memory.
//!
//! Run with `cargo bench --bench traversal`. Rays/s are reported by criterion as element
//! throughput (`cpu/…`, `gpu-binary/…` and `gpu-wide/…`, the two GPU node layouts, in each
//! scene's group); the build statistics and the GPU adapter are printed before the
//! measurements, and each GPU layout's kernel-only rates (GPU timestamps around the dispatch,
//! without the upload and read-back that criterion's figures include) after them. Without a
//! GPU adapter only the CPU runs.

mod common;

use std::time::{Duration, Instant};

use common::{Scene, Workload, cornell_box, million_triangles};
use criterion::{Criterion, Throughput};
use vcm_traversal::{CpuBvh, CpuBvhOptions, HitBatch, RayBatch, Traversal};
use vcm_traversal_wgpu::{GpuBvh, GpuBvhOptions, NodeLayout};

/// Timed dispatches per ray set for the kernel-only rates (their median counts).
const KERNEL_REPEATS: u32 = 21;

/// GPU time spent on a ray set before its kernel-only rate is measured.
const WARM_UP: Duration = Duration::from_millis(300);

/// Rays per batch for the large-batch kernel-only rates.
const LARGE_BATCH: usize = 1 << 22;

/// Builds of the large scene timed for the build statistics.
const BUILD_REPEATS: usize = 3;

/// Builds `scene` `repeats` times, prints the fastest build and the memory per triangle, and
/// returns the last BVH.
fn build_and_report(scene: &Scene, repeats: usize) -> CpuBvh {
    let mut fastest = Duration::MAX;
    let mut bvh = None;
    for _ in 0..repeats {
        let built = CpuBvh::new(&scene.triangles, CpuBvhOptions::default()).expect("valid scene");
        fastest = fastest.min(built.build_time());
        bvh = Some(built);
    }
    let bvh = bvh.expect("at least one build");
    println!(
        "{}: {} triangles, BVH build {:.3} s (best of {repeats}), {:.1} bytes/triangle",
        scene.name,
        scene.triangles.len(),
        fastest.as_secs_f64(),
        bvh.memory_bytes() as f64 / scene.triangles.len() as f64,
    );
    bvh
}

fn bench_scene(criterion: &mut Criterion, scene: &Scene, build_repeats: usize) {
    let started = Instant::now();
    let bvh = build_and_report(scene, build_repeats);
    let workload = Workload::new(scene, &bvh);
    println!(
        "{}: {} primary, {} bounce, {} shadow rays (set up in {:.1} s)",
        scene.name,
        workload.primary.len(),
        workload.bounce.len(),
        workload.shadow.len(),
        started.elapsed().as_secs_f64(),
    );
    let mut gpus = Vec::new();
    for (name, layout) in [
        ("gpu-binary", NodeLayout::Binary),
        ("gpu-wide", NodeLayout::Wide),
    ] {
        let options = GpuBvhOptions {
            layout,
            ..GpuBvhOptions::default()
        };
        match GpuBvh::open(&scene.triangles, options) {
            Ok(gpu) => {
                println!(
                    "{}: {name} on {} built in {:.3} s, {:.1} bytes/triangle, stack {}",
                    scene.name,
                    gpu.device().describe(),
                    gpu.build_time().as_secs_f64(),
                    gpu.memory_bytes() as f64 / scene.triangles.len() as f64,
                    gpu.stack_size(),
                );
                gpus.push((name, gpu));
            }
            Err(error) => println!("{}: no GPU backend: {error}", scene.name),
        }
    }
    let mut backends: Vec<(&str, &dyn Traversal)> = vec![("cpu", &bvh)];
    backends.extend(
        gpus.iter()
            .map(|(name, gpu)| (*name, gpu as &dyn Traversal)),
    );
    let mut hits = HitBatch::default();
    let mut occluded = Vec::new();
    let mut group = criterion.benchmark_group(scene.name);
    for (backend, bvh) in &backends {
        group.throughput(Throughput::Elements(workload.primary.len() as u64));
        group.bench_function(format!("{backend}/primary_closest_hit"), |b| {
            b.iter(|| bvh.intersect(&workload.primary, &mut hits))
        });
        group.throughput(Throughput::Elements(workload.bounce.len() as u64));
        group.bench_function(format!("{backend}/diffuse_bounce_closest_hit"), |b| {
            b.iter(|| bvh.intersect(&workload.bounce, &mut hits))
        });
        group.throughput(Throughput::Elements(workload.shadow.len() as u64));
        group.bench_function(format!("{backend}/shadow_occlusion"), |b| {
            b.iter(|| bvh.occluded(&workload.shadow, &mut occluded))
        });
    }
    group.finish();
    for (name, gpu) in &gpus {
        print_kernel_rates(scene.name, name, gpu, &workload);
    }
}

/// Prints the rays/s of the GPU kernels alone (GPU timestamps, no upload or read-back), the
/// figure to compare with other GPU traversal kernels: on each ray set as it is, and on the set
/// repeated to [`LARGE_BATCH`] rays, enough to fill a large GPU.
fn print_kernel_rates(scene: &str, backend: &str, gpu: &GpuBvh, workload: &Workload) {
    let sets = [
        ("primary", &workload.primary, false),
        ("bounce", &workload.bounce, false),
        ("shadow", &workload.shadow, true),
    ];
    // Lavapipe's rate does not grow with the batch, and 4M rays take minutes there.
    let sizes: &[bool] = if gpu.device().is_software() {
        &[false]
    } else {
        &[false, true]
    };
    for &large in sizes {
        let rates: Vec<String> = sets
            .iter()
            .filter_map(|&(label, rays, occlusion)| {
                let repeated;
                let rays = if large {
                    repeated = repeat_to(rays, LARGE_BATCH);
                    &repeated
                } else {
                    rays
                };
                // Keep the GPU busy for a while first, so that it runs at its full clock.
                let mut busy = Duration::ZERO;
                while busy < WARM_UP {
                    busy += gpu.kernel_time(rays, occlusion, KERNEL_REPEATS)? * KERNEL_REPEATS;
                }
                let time = gpu.kernel_time(rays, occlusion, KERNEL_REPEATS)?;
                let rate = rays.len() as f64 / time.as_secs_f64() / 1e6;
                Some(format!("{label} {rate:.1}"))
            })
            .collect();
        let batch = if large {
            "batches of ≥4M rays"
        } else {
            "the sets as they are"
        };
        if rates.is_empty() {
            println!("{scene}: {backend} kernel only: the adapter has no timestamp queries");
            return;
        }
        println!(
            "{scene}: {backend} kernel only, {batch}: {} M rays/s",
            rates.join(", ")
        );
    }
}

/// `rays` repeated whole until the batch holds at least `count` rays.
fn repeat_to(rays: &RayBatch, count: usize) -> RayBatch {
    let copies = count.div_ceil(rays.len().max(1));
    let repeat = |v: &Vec<f32>| v.repeat(copies);
    RayBatch {
        origin_x: repeat(&rays.origin_x),
        origin_y: repeat(&rays.origin_y),
        origin_z: repeat(&rays.origin_z),
        dir_x: repeat(&rays.dir_x),
        dir_y: repeat(&rays.dir_y),
        dir_z: repeat(&rays.dir_z),
        tmin: repeat(&rays.tmin),
        tmax: repeat(&rays.tmax),
    }
}

fn main() {
    println!(
        "rayon threads: {}, available parallelism: {}",
        rayon::current_num_threads(),
        std::thread::available_parallelism().map_or(0, |n| n.get()),
    );
    // No HTML plots: the throughput figures are what matters, and criterion's plotting breaks
    // when the workspace enables plotters' ab_glyph text backend (used by `vcm render`'s plots)
    // without a registered font.
    let mut criterion = Criterion::default()
        .without_plots()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4))
        .configure_from_args();
    bench_scene(&mut criterion, &cornell_box(), 1);
    bench_scene(&mut criterion, &million_triangles(), BUILD_REPEATS);
    criterion.final_summary();
}
