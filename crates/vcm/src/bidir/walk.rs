//! What camera and light subpaths share: the random walk from vertex to vertex.

use glam::Vec3;
use vcm_scene::bsdf::{FixedOutgoing, LobeKind, Pdfs, TransportMode};
use vcm_scene::sampling::Rng;

use super::mis::{MisFactors, SubpathMis};
use crate::roulette::continuation_probability;
use crate::surface_hit::SurfaceHit;

/// The state of a subpath's random walk between waves.
#[derive(Clone, Debug)]
pub(crate) struct Walk {
    /// The subpath's own random stream.
    pub rng: Rng,
    /// Origin of the current segment.
    pub origin: Vec3,
    /// Unit direction of the current segment.
    pub direction: Vec3,
    /// Product of the sampling weights so far (camera: dimensionless; light: emitted power
    /// over the sampling pdfs).
    pub throughput: Vec3,
    /// The recursive MIS quantities.
    pub mis: SubpathMis,
    /// Segments including the current one (the first ray is 1).
    pub segments: u32,
}

impl Walk {
    /// Samples the BSDF at `surface` (`seen` from the previous vertex) for the next segment,
    /// updates the MIS quantities and applies Russian roulette on the throughput times
    /// `roulette_scale` (which makes it dimensionless). Returns the sampled lobe's class, or
    /// `None` when the walk ends.
    pub fn scatter(
        &mut self,
        surface: &SurfaceHit,
        seen: &FixedOutgoing,
        mode: TransportMode,
        factors: &MisFactors,
        roulette_scale: f32,
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
        let relative = self.throughput * roulette_scale;
        if let Some(continuation) = continuation_probability(self.segments, relative) {
            if self.rng.uniform() >= continuation {
                return None;
            }
            self.throughput /= continuation;
        }
        self.origin = surface.spawn(sample.wi);
        self.direction = sample.wi;
        self.segments += 1;
        Some(sample.lobe)
    }
}
