//! The CPU backend: obvhs's 8-wide BVH (CWBVH) with exact single-precision child boxes,
//! traversed nearest child first on rayon, one ray at a time per thread or several in turn
//! (whichever measures faster), with a watertight triangle test.

mod batch;
mod filter;
mod geometry;
mod kernel;
mod node;
mod options;
mod pacing;
mod ray;
mod triangle;
mod wide_node;

use std::fmt;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;

use self::batch::{Kernel, Pace, Simd};
use self::filter::{HitFilter, Masked, Opaque};
use self::geometry::LeafGeometry;
pub use self::options::{CpuBvhOptions, CpuKernel, INTERLEAVE_ABOVE_BYTES, Interleave};
use self::pacing::Pacing;
use crate::alpha::AlphaTest;
use crate::batch::{HitBatch, RayBatch};
use crate::error::BuildError;
use crate::traversal::Traversal;

/// [`CpuBvh::pacing`]'s entry for closest-hit batches.
const CLOSEST: usize = 0;

/// [`CpuBvh::pacing`]'s entry for occlusion batches.
const OCCLUSION: usize = 1;

/// An alpha test with its answers to [`AlphaTest::is_masked`] cached in leaf order.
struct AlphaState {
    test: Arc<dyn AlphaTest>,
    masked: Vec<bool>,
}

/// CPU ray traversal over an 8-wide BVH built with obvhs's parallel PLOC builder and
/// converted from its compressed layout (CWBVH) to 256-byte nodes with exact child boxes.
///
/// Triangles are copied into BVH leaf order (nine coordinate planes, 36 bytes each) so
/// leaves index them directly; an id map turns leaf positions back into the caller's ids.
/// Batches are split into chunks traced in parallel on the current rayon pool, one ray at a
/// time or several in turn ([`Interleave`]), with a node's eight children and the triangles
/// of its hit leaves tested 8 at a time where the CPU has AVX2.
pub struct CpuBvh {
    geometry: LeafGeometry,
    alpha: Option<AlphaState>,
    simd: Simd,
    chunk_size: usize,
    interleave: Interleave,
    /// Whether the traversal data outgrows [`INTERLEAVE_ABOVE_BYTES`].
    large: bool,
    /// What [`Interleave::Auto`] measured on a large hierarchy, for closest-hit and for
    /// occlusion batches.
    pacing: [Pacing; 2],
    build_time: Duration,
}

impl CpuBvh {
    /// Builds the backend over `triangles`; triangle `i` is reported as primitive `i`.
    ///
    /// Fails if a vertex is not finite or there are `u32::MAX` triangles or more. An empty
    /// slice is fine: every ray misses.
    pub fn new(triangles: &[[Vec3; 3]], options: CpuBvhOptions) -> Result<Self, BuildError> {
        let start = Instant::now();
        let geometry = LeafGeometry::build(triangles, options.preset)?;
        Ok(Self {
            large: geometry.memory_bytes() > INTERLEAVE_ABOVE_BYTES,
            pacing: [Pacing::new(), Pacing::new()],
            geometry,
            alpha: None,
            simd: match options.kernel {
                CpuKernel::Auto => Simd::detect(),
                CpuKernel::Portable => Simd::Portable,
            },
            chunk_size: options.chunk_size.max(1),
            interleave: options.interleave,
            build_time: start.elapsed(),
        })
    }

    /// Like [`new`](Self::new), with masked triangles alpha-tested during traversal.
    /// [`AlphaTest::is_masked`] is called once per triangle here and cached.
    pub fn with_alpha_test(
        triangles: &[[Vec3; 3]],
        options: CpuBvhOptions,
        alpha: Arc<dyn AlphaTest>,
    ) -> Result<Self, BuildError> {
        let mut bvh = Self::new(triangles, options)?;
        let masked = bvh
            .geometry
            .ids
            .iter()
            .map(|&id| alpha.is_masked(id))
            .collect();
        bvh.alpha = Some(AlphaState {
            test: alpha,
            masked,
        });
        Ok(bvh)
    }

    /// Wall-clock time [`new`](Self::new) took: validation, hierarchy build and leaf layout.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Bytes of traversal data: nodes, leaf-order triangles and the leaf-to-id map.
    pub fn memory_bytes(&self) -> usize {
        self.geometry.memory_bytes()
    }

    /// The kernel for a closest-hit (`query` 0) or occlusion (1) batch.
    fn kernel<F: HitFilter>(&self, filter: F, query: usize) -> Kernel<'_, F> {
        Kernel {
            geometry: &self.geometry,
            filter,
            simd: self.simd,
            chunk_size: self.chunk_size,
            pace: match self.interleave {
                Interleave::Auto if self.large => Pace::Measured(&self.pacing[query]),
                Interleave::Auto => Pace::Fixed(false),
                Interleave::Off => Pace::Fixed(false),
                Interleave::On => Pace::Fixed(true),
            },
        }
    }

    fn masked<'a>(&'a self, alpha: &'a AlphaState, query: usize) -> Kernel<'a, Masked<'a>> {
        let filter = Masked {
            alpha: alpha.test.as_ref(),
            masked: &alpha.masked,
            ids: &self.geometry.ids,
        };
        self.kernel(filter, query)
    }
}

impl fmt::Debug for CpuBvh {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CpuBvh")
            .field("nodes", &self.geometry.nodes.len())
            .field("leaf_triangles", &self.geometry.triangles.len())
            .field("alpha_test", &self.alpha.is_some())
            .field("simd", &self.simd)
            .field("chunk_size", &self.chunk_size)
            .field("interleave", &self.interleave)
            .field("pacing", &self.pacing)
            .field("build_time", &self.build_time)
            .finish()
    }
}

impl Traversal for CpuBvh {
    fn intersect(&self, rays: &RayBatch, hits: &mut HitBatch) {
        match &self.alpha {
            None => self.kernel(Opaque, CLOSEST).intersect(rays, hits),
            Some(alpha) => self.masked(alpha, CLOSEST).intersect(rays, hits),
        }
    }

    fn occluded(&self, rays: &RayBatch, occluded: &mut Vec<bool>) {
        match &self.alpha {
            None => self.kernel(Opaque, OCCLUSION).occluded(rays, occluded),
            Some(alpha) => self.masked(alpha, OCCLUSION).occluded(rays, occluded),
        }
    }
}
