//! The random walk every path makes, camera or light, from vertex to vertex: its numbers,
//! its current segment, its throughput with Russian roulette, and what its MIS weights
//! remember of it. The general vertex ([`Walk::scatter`]) and the lanes' vertices
//! ([`crate::lambert::continuation`]) end in the same two steps, [`Walk::survives`] and
//! [`Walk::advance`].

use glam::Vec3;
use vcm_scene::Scene;
use vcm_scene::bsdf::{BsdfSample, FixedOutgoing, LobeKind, Pdfs, TransportMode};
use vcm_scene::sampling::{Sampler, SobolSampler};

use crate::medium::Medium;
use crate::roulette::Roulette;
use crate::surface_hit::SurfaceHit;

/// The state of a path's random walk between waves; `M` is what its MIS weights remember
/// of it (path tracing: how the current segment was sampled, [`crate::path_state::SegmentOrigin`];
/// the VCM family: the recursive quantities, [`crate::bidir::mis::SubpathMis`]).
#[derive(Clone, Debug)]
pub(crate) struct Walk<M> {
    /// The path's numbers: its stratified sequence at its sample index.
    pub rng: SobolSampler,
    /// Origin of the current segment.
    pub origin: Vec3,
    /// Unit direction of the current segment.
    pub direction: Vec3,
    /// Product of the sampling weights so far (camera: dimensionless; light: emitted power
    /// over the sampling pdfs), with the transmittances of the segments and the Russian
    /// roulette factors.
    pub throughput: Vec3,
    /// What the current segment runs through.
    pub medium: Medium,
    /// What the MIS weights remember of the walk.
    pub mis: M,
    /// Segments including the current one (the first ray is 1).
    pub segments: u32,
    /// How Russian roulette judges the throughput.
    pub roulette: Roulette,
}

impl<M> Walk<M> {
    /// Moves the path's numbers to those of the vertex it has just reached, `pairs` pairs
    /// of dimensions per vertex ([`SobolSampler::start_step`]), and returns them.
    pub fn start_vertex(&mut self, pairs: u32) -> &mut SobolSampler {
        self.rng.start_step(self.segments, pairs);
        &mut self.rng
    }

    /// Reaches the end of the current segment, `distance` from its origin: the throughput
    /// takes the segment's transmittance.
    pub fn cross(&mut self, distance: f32) {
        self.throughput *= self.medium.transmittance(distance);
    }

    /// Samples the BSDF at `surface` (`seen` from the previous vertex) for the next segment,
    /// with the pdfs `pdfs` asks for, lets `remember` update the MIS memory with the sample,
    /// and plays Russian roulette. Returns the sampled lobe's class, or `None` when the
    /// walk ends.
    pub fn scatter(
        &mut self,
        scene: &Scene,
        surface: &SurfaceHit,
        seen: &FixedOutgoing,
        (mode, pdfs): (TransportMode, Pdfs),
        remember: impl FnOnce(&mut M, &BsdfSample),
    ) -> Option<LobeKind> {
        let (u_lobe, u_dir) = (self.rng.uniform(), self.rng.uniform2());
        let sample = seen.sample(u_lobe, u_dir, mode, pdfs)?;
        remember(&mut self.mis, &sample);
        self.roulette.scattered(&sample, mode);
        // β ← β · f·|cos| / p
        let throughput = self.throughput * (sample.f_cos / sample.pdf_fwd);
        if !self.survives(throughput, Sampler::uniform) {
            return None;
        }
        self.advance(surface.spawn(sample.wi), sample.wi);
        self.medium = self.medium.toward(scene, &surface.point, sample.wi);
        Some(sample.lobe)
    }

    /// Takes the `throughput` of a scattering and plays Russian roulette on it; returns
    /// whether the walk survives. `number` takes roulette's number from the walk's numbers,
    /// only where there is a game to play.
    #[inline]
    pub fn survives(
        &mut self,
        throughput: Vec3,
        number: impl FnOnce(&mut SobolSampler) -> f32,
    ) -> bool {
        self.throughput = throughput;
        let rng = &mut self.rng;
        self.roulette
            .survives(self.segments, &mut self.throughput, || number(rng))
    }

    /// Starts the next segment, from `origin` along `direction` (unit).
    #[inline]
    pub fn advance(&mut self, origin: Vec3, direction: Vec3) {
        self.origin = origin;
        self.direction = direction;
        self.segments += 1;
    }
}

/// A path that makes a [`Walk`] (the path tracer's and the VCM family's camera and light
/// paths), for the code their vertices share.
pub(crate) trait Walker {
    /// What its MIS weights remember of the walk.
    type Mis;
    /// The walk.
    fn walk(&self) -> &Walk<Self::Mis>;
    /// The walk, to change.
    fn walk_mut(&mut self) -> &mut Walk<Self::Mis>;
}

/// [`Walker`] for a path type whose walk is its field `walk`.
macro_rules! walker {
    ($path:ty, $mis:ty) => {
        impl $crate::walk::Walker for $path {
            type Mis = $mis;
            #[inline(always)]
            fn walk(&self) -> &$crate::walk::Walk<$mis> {
                &self.walk
            }
            #[inline(always)]
            fn walk_mut(&mut self) -> &mut $crate::walk::Walk<$mis> {
                &mut self.walk
            }
        }
    };
}
pub(crate) use walker;
