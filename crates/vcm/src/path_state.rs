//! The state one camera path carries from wave to wave.

use glam::Vec3;
use vcm_scene::sampling::SobolSampler;
use vcm_traversal::RayBatch;

use crate::medium::Medium;
use crate::roulette::Roulette;
use crate::walk::Walk;

/// How the direction of a path's current segment was chosen, which decides the MIS weight of
/// emission found at its end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum SegmentOrigin {
    /// The camera ray or a delta BSDF lobe: light sampling cannot produce this segment, so
    /// emission found at its end gets full weight.
    Deterministic,
    /// A non-delta BSDF sample drawn with this solid-angle pdf (sr⁻¹).
    Bsdf {
        /// Solid-angle pdf of the sampled direction.
        pdf_w: f32,
    },
}

/// A shadow ray waiting for its occlusion test, with the contribution it adds when unoccluded.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ShadowRay {
    /// Ray origin, offset off the receiving surface.
    pub origin: Vec3,
    /// Ray direction; not necessarily unit (for finite lights it reaches the light at t = 1).
    pub direction: Vec3,
    /// Exclusive upper bound of the ray parameter.
    pub tmax: f32,
    /// MIS-weighted radiance (RGB) added to the path's pixel when the ray is unoccluded.
    pub contribution: Vec3,
}

impl ShadowRay {
    /// Refills `batch` with `shadows`, in order, for one occlusion query.
    pub fn fill_batch<'a>(batch: &mut RayBatch, shadows: impl Iterator<Item = &'a ShadowRay>) {
        batch.refill(shadows.map(|s| (s.origin, s.direction, 0.0, s.tmax)));
    }
}

/// One camera path (thesis Fig. 4.4, without the bidirectional MIS quantities).
#[derive(Clone, Debug)]
pub(crate) struct PathState {
    /// The pixel the path started from (`y · width + x`).
    pub pixel: u32,
    /// Which of the frame's samples of that pixel it is (from 0).
    pub sample: u32,
    /// The random walk, remembering how its current segment was sampled.
    pub walk: Walk<SegmentOrigin>,
    /// Radiance gathered so far (RGB), added to the film when the path ends.
    pub radiance: Vec3,
    /// The shadow ray queued by the last shading step, if any.
    pub shadow: Option<ShadowRay>,
    /// False once the path has ended (missed, absorbed, terminated or reached `max_depth`).
    pub alive: bool,
}

crate::walk::walker!(PathState, SegmentOrigin);

impl PathState {
    /// A path at the camera, its pixel's numbers `rng`: unit throughput, no radiance yet.
    pub fn new(
        pixel: u32,
        sample: u32,
        rng: SobolSampler,
        origin: Vec3,
        direction: Vec3,
    ) -> PathState {
        PathState {
            pixel,
            sample,
            walk: Walk {
                rng,
                origin,
                direction,
                throughput: Vec3::ONE,
                medium: Medium::OUTSIDE,
                mis: SegmentOrigin::Deterministic,
                segments: 1,
                roulette: Roulette::UNIT,
            },
            radiance: Vec3::ZERO,
            shadow: None,
            alive: true,
        }
    }
}
