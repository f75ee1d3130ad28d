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
    /// Whether a thread traces several rays in turn or one at a time.
    pub interleave: Interleave,
}

/// How many rays a thread traces at once. Taking several in turn, each step of a ray
/// prefetches the node or triangles its next step reads, so that on a hierarchy too large
/// for the caches one ray's cache misses overlap the others' work; where everything stays
/// in cache, or the rays are coherent enough to share what is cached, it only costs the
/// switching. All modes report the same hits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Interleave {
    /// One at a time where the traversal data (nodes, triangles, ids) fits in
    /// [`INTERLEAVE_ABOVE_BYTES`]; above, whichever measures faster: most chunks the way that
    /// was faster on earlier chunks, one in sixteen the other way, timed per chunk
    /// (separately for closest-hit and occlusion batches), several in turn until measured.
    #[default]
    Auto,
    /// One ray at a time.
    Off,
    /// Several rays in turn.
    On,
}

/// Traversal data up to which [`Interleave::Auto`] takes one ray at a time, and above which it
/// measures both ways: a core's L2 cache on current x86 CPUs (1 MiB on this project's
/// machines), where every access hits the cache and rays in turn only cost the switching
/// (2–4% on the Cornell box).
pub const INTERLEAVE_ABOVE_BYTES: usize = 1 << 20;

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
    /// The `Auto` preset, 256-ray chunks and the widest kernel. Throughput is flat from 64 to
    /// 4096 rays per chunk on both benchmark scenes (a chunk takes ≥ 20 µs, far above
    /// rayon's per-task cost), 16 loses ~2% on the Cornell box; 256 still leaves a 64k-ray
    /// batch 256 tasks to balance.
    fn default() -> Self {
        Self {
            preset: BuildPreset::default(),
            chunk_size: 256,
            kernel: CpuKernel::Auto,
            interleave: Interleave::Auto,
        }
    }
}
