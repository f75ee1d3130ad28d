//! Build and run options of the CPU backend.

use crate::build::BuildPreset;

/// How to build and run a [`CpuBvh`](super::CpuBvh).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CpuBvhOptions {
    /// Hierarchy build quality.
    pub preset: BuildPreset,
    /// Rays per rayon task (values below 1 count as 1).
    pub chunk_size: usize,
    /// Which SIMD implementation of the node and triangle tests to run.
    pub kernel: CpuKernel,
}

/// Node- and triangle-test implementations of the CPU backend. Both node tests are
/// conservative and both triangle tests compute the same watertight test with the same
/// operations (the AVX2 one on 8 triangles at once), so they report the same hits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CpuKernel {
    /// The widest the CPU supports: 8-wide AVX2 + FMA node and leaf tests where available,
    /// else portable.
    #[default]
    Auto,
    /// 4-wide code for any target (e.g. to compare against the AVX2 path).
    Portable,
}

impl Default for CpuBvhOptions {
    /// The `Fast` preset, 256-ray chunks and the widest kernel. Throughput is flat from 64 to
    /// 4096 rays per chunk on both benchmark scenes (a chunk takes ≥ 20 µs, far above
    /// rayon's per-task cost), 16 loses ~2% on the Cornell box; 256 still leaves a 64k-ray
    /// batch 256 tasks to balance.
    fn default() -> Self {
        Self {
            preset: BuildPreset::default(),
            chunk_size: 256,
            kernel: CpuKernel::Auto,
        }
    }
}
