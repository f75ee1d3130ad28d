//! Running the single-ray kernels over ray batches: rayon over fixed-size chunks, with the
//! node test chosen once per CPU and compiled into the chunk loops, and each chunk traced
//! one ray at a time or several in turn as [`Pace`] says.

use std::time::Instant;

use rayon::prelude::*;

use super::filter::HitFilter;
use super::geometry::LeafGeometry;
use super::kernel::{AnyHit, ClosestHit, Found, LANES_LARGE, Search, Walk, search, search_in_turn};
use super::node::{NodeTest, Portable};
use super::pacing::Pacing;
use super::ray::PreparedRay;
use super::triangle::TriangleTest;
use crate::batch::{HitBatch, NO_HIT, RayBatch};

#[cfg(target_arch = "x86_64")]
use super::node::Avx2;

/// The widest node test this CPU supports.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Simd {
    /// 4-wide, any target.
    Portable,
    /// 8-wide AVX2 + FMA.
    #[cfg(target_arch = "x86_64")]
    Avx2(Avx2),
}

impl Simd {
    /// Picks the widest node test available at run time.
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx2) = Avx2::detect() {
            return Self::Avx2(avx2);
        }
        Self::Portable
    }
}

/// Everything a chunk of rays is traced against.
pub(crate) struct Kernel<'a, F> {
    /// The hierarchy and leaf triangles.
    pub geometry: &'a LeafGeometry,
    /// Alpha handling.
    pub filter: F,
    /// Node test to run.
    pub simd: Simd,
    /// Rays per rayon task.
    pub chunk_size: usize,
    /// Whether a thread takes several rays in turn or one at a time.
    pub pace: Pace<'a>,
}

/// How the chunks of a batch are traced.
#[derive(Clone, Copy)]
pub(crate) enum Pace<'a> {
    /// All several rays in turn (true) or all one ray at a time.
    Fixed(bool),
    /// As the measured estimate prefers, some the other way to keep measuring.
    Measured(&'a Pacing),
}

impl Pace<'_> {
    /// Runs a chunk of `rays` rays of a batch, `trace(interleaved)`, and takes in its time
    /// where measured.
    #[inline(always)]
    fn run(self, rays: usize, trace: impl FnOnce(bool)) {
        match self {
            Self::Fixed(interleaved) => trace(interleaved),
            Self::Measured(pacing) => {
                let interleaved = pacing.next_chunk();
                let start = Instant::now();
                trace(interleaved);
                pacing.record(interleaved, rays, start.elapsed().as_nanos() as f64);
            }
        }
    }
}

/// A chunk to trace: the batch, the chunk's first ray and whether its rays go in turn.
type Chunk<'a> = (&'a RayBatch, usize, bool);

/// One chunk of a [`HitBatch`].
struct HitsMut<'a> {
    t: &'a mut [f32],
    prim: &'a mut [u32],
    u: &'a mut [f32],
    v: &'a mut [f32],
}

impl<F: HitFilter> Kernel<'_, F> {
    /// Closest hits of all rays, in parallel.
    pub fn intersect(&self, rays: &RayBatch, hits: &mut HitBatch) {
        rays.assert_consistent();
        hits.resize(rays.len());
        let size = self.chunk_size;
        hits.t
            .par_chunks_mut(size)
            .zip(hits.prim.par_chunks_mut(size))
            .zip(hits.u.par_chunks_mut(size))
            .zip(hits.v.par_chunks_mut(size))
            .enumerate()
            .for_each(|(chunk, (((t, prim), u), v))| {
                self.pace.run(t.len(), |interleaved| {
                    let out = HitsMut { t, prim, u, v };
                    let chunk = (rays, chunk * size, interleaved);
                    match self.simd {
                        Simd::Portable => self.closest_chunk(Portable, chunk, out),
                        #[cfg(target_arch = "x86_64")]
                        // SAFETY: `Avx2` exists only on CPUs with AVX2 and FMA.
                        Simd::Avx2(avx2) => unsafe { self.closest_chunk_avx2(avx2, chunk, out) },
                    }
                });
            });
    }

    /// Occlusion of all rays, in parallel.
    pub fn occluded(&self, rays: &RayBatch, occluded: &mut Vec<bool>) {
        rays.assert_consistent();
        occluded.resize(rays.len(), false);
        let size = self.chunk_size;
        occluded
            .par_chunks_mut(size)
            .enumerate()
            .for_each(|(chunk, out)| {
                self.pace.run(out.len(), |interleaved| {
                    let chunk = (rays, chunk * size, interleaved);
                    match self.simd {
                        Simd::Portable => self.occluded_chunk(Portable, chunk, out),
                        #[cfg(target_arch = "x86_64")]
                        // SAFETY: `Avx2` exists only on CPUs with AVX2 and FMA.
                        Simd::Avx2(avx2) => unsafe { self.occluded_chunk_avx2(avx2, chunk, out) },
                    }
                });
            });
    }

    /// Runs the search for `T` for the chunk's `count` rays from `start`, in turn when
    /// `interleaved`, handing each result to `done`.
    #[inline(always)]
    fn search_chunk<T: Default, N: NodeTest + TriangleTest>(
        &self,
        node_test: N,
        (rays, start, interleaved): Chunk<'_>,
        count: usize,
        mut done: impl FnMut(usize, Option<Found<T>>),
    ) where
        Found<T>: Search,
    {
        let (geometry, filter) = (self.geometry, &self.filter);
        if interleaved {
            let rays = (count, |j| prepare(rays, start + j));
            search_in_turn::<T, N, F, LANES_LARGE>(geometry, node_test, filter, rays, done);
        } else {
            let walk = &mut Walk::new(geometry);
            for j in 0..count {
                let ray = prepare(rays, start + j);
                done(
                    j,
                    ray.map(|ray| search(geometry, node_test, filter, walk, &ray)),
                );
            }
        }
    }

    #[inline(always)]
    fn closest_chunk<N: NodeTest + TriangleTest>(
        &self,
        node_test: N,
        chunk: Chunk<'_>,
        out: HitsMut<'_>,
    ) {
        self.search_chunk(
            node_test,
            chunk,
            out.t.len(),
            |j, search: Option<ClosestHit>| {
                (out.t[j], out.prim[j], out.u[j], out.v[j]) = match search.and_then(|s| s.hit) {
                    Some((leaf, candidate)) => {
                        let (u, v) = candidate.barycentrics();
                        (candidate.t, self.geometry.ids[leaf], u, v)
                    }
                    None => (f32::INFINITY, NO_HIT, 0.0, 0.0),
                };
            },
        );
    }

    #[inline(always)]
    fn occluded_chunk<N: NodeTest + TriangleTest>(
        &self,
        node_test: N,
        chunk: Chunk<'_>,
        out: &mut [bool],
    ) {
        self.search_chunk(node_test, chunk, out.len(), |j, search: Option<AnyHit>| {
            out[j] = search.is_some_and(|s| s.hit);
        });
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn closest_chunk_avx2(&self, node_test: Avx2, chunk: Chunk<'_>, out: HitsMut<'_>) {
        self.closest_chunk(node_test, chunk, out);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn occluded_chunk_avx2(&self, node_test: Avx2, chunk: Chunk<'_>, out: &mut [bool]) {
        self.occluded_chunk(node_test, chunk, out);
    }
}

#[inline(always)]
fn prepare(rays: &RayBatch, i: usize) -> Option<PreparedRay> {
    PreparedRay::new(
        rays.origin(i),
        rays.direction(i),
        rays.tmin[i],
        rays.tmax[i],
    )
}
