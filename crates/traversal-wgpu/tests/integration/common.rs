//! Shared helpers of the GPU tests: the adapter (or a clear skip), random rays and the
//! comparison against the CPU backend.

use glam::Vec3;
use vcm_scene::sampling::{Rng, Sampler, sample_uniform_sphere};
use vcm_traversal::{HitBatch, RayBatch};
use vcm_traversal_wgpu::GpuDevice;

/// The preferred adapter, or `None` (with a note on stderr) when there is none and
/// `VCM_REQUIRE_GPU` is not set.
pub fn gpu() -> Option<GpuDevice> {
    vcm_traversal_wgpu::device_or_skip()
}

/// Random rays through a box: origins inside it, directions uniform, not normalised.
pub fn random_rays(rng: &mut Rng, min: Vec3, max: Vec3, count: usize) -> RayBatch {
    let mut rays = RayBatch::with_capacity(count);
    for _ in 0..count {
        let u = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
        let origin = min + (max - min) * u;
        let direction = sample_uniform_sphere(rng.uniform2()) * (0.5 + rng.uniform());
        rays.push(origin, direction, 0.0, f32::INFINITY);
    }
    rays
}

/// How two hit batches for the same rays compare.
#[derive(Debug, Default)]
pub struct Agreement {
    /// Rays with the same primitive (or both missing) and t within tolerance.
    pub same: usize,
    /// Rays where both hit different primitives at the same t (shared edges, overlaps).
    pub ties: usize,
    /// Everything else.
    pub different: usize,
}

/// Relative tolerance on t between the backends (different rounding, e.g. fused multiply-adds).
pub const T_TOLERANCE: f32 = 1e-5;

fn same_t(a: f32, b: f32) -> bool {
    (a - b).abs() <= T_TOLERANCE * a.abs().max(b.abs()).max(1e-3)
}

/// Compares `gpu` against `cpu` ray by ray.
pub fn compare(cpu: &HitBatch, gpu: &HitBatch) -> Agreement {
    let mut agreement = Agreement::default();
    for i in 0..cpu.len() {
        let (hit_a, hit_b) = (cpu.is_hit(i), gpu.is_hit(i));
        if !hit_a && !hit_b {
            agreement.same += 1;
        } else if hit_a && hit_b && same_t(cpu.t[i], gpu.t[i]) {
            if cpu.prim[i] == gpu.prim[i] {
                agreement.same += 1;
            } else {
                agreement.ties += 1;
            }
        } else {
            agreement.different += 1;
        }
    }
    agreement
}
