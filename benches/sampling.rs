//! The cost of a path vertex's random numbers: the five pairs of dimensions a path tracer's
//! vertex draws (a light, a point on it, a lobe, a direction, Russian roulette), for a wave
//! of paths, drawn one at a time and prefetched eight paths at a time in SIMD lanes
//! (`SobolSampler::prefetch`) before the same draws.
//!
//! Run with `cargo bench --bench sampling`. Criterion reports path vertices per second for
//! both ways in the same run; both draw the same numbers.

use std::hint::black_box;

use criterion::{Criterion, Throughput};
use vcm_scene::sampling::{Sampler, SobolSampler};

/// Paths in the wave.
const PATHS: u64 = 1 << 16;

/// Pairs of dimensions a vertex reserves (the path tracer's).
const PAIRS_PER_VERTEX: u32 = 5;

/// The wave's samplers, moved to their second vertex's numbers.
fn samplers() -> Vec<SobolSampler> {
    (0..PATHS)
        .map(|path| {
            let mut sampler = SobolSampler::new(&[7, path % 4096], path / 4096);
            sampler.start_step(1, PAIRS_PER_VERTEX);
            sampler
        })
        .collect()
}

/// The draws of one vertex, summed so that none is optimized away.
fn draw_vertex(sampler: &mut SobolSampler) -> f32 {
    let (pick, point) = (sampler.uniform(), sampler.uniform2());
    let (lobe, direction) = (sampler.uniform(), sampler.uniform2());
    pick + point.x + point.y + lobe + direction.x + direction.y + sampler.uniform()
}

fn main() {
    // Without plots, as in the traversal benchmark: criterion's plotting breaks where the
    // workspace enables plotters' text backend without a registered font.
    let mut criterion = Criterion::default().without_plots().configure_from_args();
    let fresh = samplers();
    let mut group = criterion.benchmark_group("vertex_numbers");
    group.throughput(Throughput::Elements(PATHS));
    group.bench_function("one_at_a_time", |b| {
        b.iter_batched_ref(
            || fresh.clone(),
            |wave| wave.iter_mut().map(draw_vertex).sum::<f32>(),
            criterion::BatchSize::LargeInput,
        )
    });
    group.bench_function("prefetched", |b| {
        b.iter_batched_ref(
            || fresh.clone(),
            |wave| {
                SobolSampler::prefetch(black_box(&mut *wave).iter_mut());
                wave.iter_mut().map(draw_vertex).sum::<f32>()
            },
            criterion::BatchSize::LargeInput,
        )
    });
    group.finish();
    criterion.final_summary();
}
