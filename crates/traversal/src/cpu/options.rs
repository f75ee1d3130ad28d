//! Build and run options of the CPU backend.

use obvhs::BvhBuildParams;

/// obvhs build quality presets, from fastest build to best hierarchy.
///
/// `Slow` and `VerySlow` split large triangles' boxes before building (a triangle may then be
/// stored in several leaves).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BuildPreset {
    /// No reinsertion, one primitive per leaf.
    Fastest,
    /// Minimal search radius, light reinsertion.
    VeryFast,
    /// Small search radius, light reinsertion. The default: on a 1M-triangle scene its
    /// hierarchy costs the same node and triangle tests per ray as `Medium`'s (within 0.5%)
    /// and builds 10–15% faster.
    #[default]
    Fast,
    /// Medium search radius, more reinsertion.
    Medium,
    /// Spatial pre-splits, large search radius.
    Slow,
    /// Spatial pre-splits, full reinsertion.
    VerySlow,
}

/// How to build and run a [`CpuBvh`](super::CpuBvh).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CpuBvhOptions {
    /// Hierarchy build quality.
    pub preset: BuildPreset,
    /// Rays per rayon task (values below 1 count as 1).
    pub chunk_size: usize,
    /// Which SIMD implementation of the node test to run.
    pub kernel: CpuKernel,
}

/// Node-test implementations of the CPU backend. Both are conservative and use the same
/// triangle test, so they report the same hits (up to exact ties).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CpuKernel {
    /// The widest the CPU supports: 8-wide AVX2 + FMA where available, else portable.
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

impl BuildPreset {
    /// The obvhs parameters of this preset.
    pub(super) fn params(self) -> BvhBuildParams {
        match self {
            Self::Fastest => BvhBuildParams::fastest_build(),
            Self::VeryFast => BvhBuildParams::very_fast_build(),
            Self::Fast => BvhBuildParams::fast_build(),
            Self::Medium => BvhBuildParams::medium_build(),
            Self::Slow => BvhBuildParams::slow_build(),
            Self::VerySlow => BvhBuildParams::very_slow_build(),
        }
    }
}
