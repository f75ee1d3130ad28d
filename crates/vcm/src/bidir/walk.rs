//! What camera and light subpaths share: the random walk from vertex to vertex.

use glam::Vec3;
use vcm_scene::Scene;
use vcm_scene::bsdf::{FixedOutgoing, LobeKind, Pdfs, TransportMode};
use vcm_scene::sampling::{Sampler, SobolSampler};

use super::mis::{MisFactors, SubpathMis};
use crate::medium::Medium;
use crate::roulette::Roulette;
use crate::surface_hit::SurfaceHit;

/// The state of a subpath's random walk between waves.
#[derive(Clone, Debug)]
pub(crate) struct Walk {
    /// The subpath's numbers: its stratified sequence at its sample index.
    pub rng: SobolSampler,
    /// Origin of the current segment.
    pub origin: Vec3,
    /// Unit direction of the current segment.
    pub direction: Vec3,
    /// Product of the sampling weights so far (camera: dimensionless; light: emitted power
    /// over the sampling pdfs), with the transmittances of the segments.
    pub throughput: Vec3,
    /// What the current segment runs through.
    pub medium: Medium,
    /// The recursive MIS quantities.
    pub mis: SubpathMis,
    /// Segments including the current one (the first ray is 1).
    pub segments: u32,
    /// How Russian roulette judges the throughput.
    pub roulette: Roulette,
}

impl Walk {
    /// Moves the subpath's numbers to those of the vertex it has just reached, `pairs` pairs
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
    /// updates the MIS quantities and plays Russian roulette. Returns the sampled lobe's
    /// class, or `None` when the walk ends.
    pub fn scatter(
        &mut self,
        scene: &Scene,
        surface: &SurfaceHit,
        seen: &FixedOutgoing,
        mode: TransportMode,
        factors: &MisFactors,
    ) -> Option<LobeKind> {
        let (u_lobe, u_dir) = (self.rng.uniform(), self.rng.uniform2());
        let sample = seen.sample(u_lobe, u_dir, mode, Pdfs::Both)?;
        self.throughput *= sample.f_cos / sample.pdf_fwd;
        self.mis.scatter(
            surface.cos_geometric(sample.wi),
            sample.pdf_fwd,
            sample.pdf_rev,
            sample.lobe == LobeKind::Specular,
            factors,
        );
        self.roulette.scattered(&sample, mode);
        let rng = &mut self.rng;
        if !self
            .roulette
            .survives(self.segments, &mut self.throughput, || rng.uniform())
        {
            return None;
        }
        self.origin = surface.spawn(sample.wi);
        self.direction = sample.wi;
        self.medium = self.medium.toward(scene, &surface.point, sample.wi);
        self.segments += 1;
        Some(sample.lobe)
    }
}
