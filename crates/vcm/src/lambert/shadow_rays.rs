//! Shadow rays of eight vertices at once, taken apart into each lane's [`ShadowRay`].

use crate::lanes::{Mask, Vec3s};
use crate::path_state::ShadowRay;
use crate::shadow::segment_to;

/// A shadow ray per lane, where one is queued: from `origin` to `target` (or, toward a
/// distant light, unbounded along `target`), adding `contribution` where nothing blocks it.
pub(crate) struct ShadowLanes {
    /// Lanes that queue their ray.
    pub queued: Mask,
    /// The rays' origins, offset off the vertices' surfaces.
    pub origin: Vec3s,
    /// The rays' ends; in the `distant` lanes, their unit directions.
    pub target: Vec3s,
    /// Lanes whose ray goes toward a distant light, without end.
    pub distant: Mask,
    /// What each unblocked ray adds.
    pub contribution: Vec3s,
}

impl ShadowLanes {
    /// Lane `lane`'s shadow ray, if it queued one.
    #[inline]
    pub fn ray(&self, lane: usize) -> Option<ShadowRay> {
        self.queued.get(lane).then(|| {
            let origin = self.origin.lane(lane);
            let (direction, tmax) = if self.distant.get(lane) {
                (self.target.lane(lane), f32::INFINITY)
            } else {
                segment_to(origin, self.target.lane(lane))
            };
            ShadowRay {
                origin,
                direction,
                tmax,
                contribution: self.contribution.lane(lane),
            }
        })
    }
}
