//! The backend-independent traversal interface: synchronous queries and a submit/wait pair.

use crate::batch::{HitBatch, RayBatch};

/// Ray queries against a fixed set of triangles.
///
/// Contract shared by every backend:
/// - Primitive ids are the indices of the triangles in the slice the backend was built from.
/// - A ray `i` only reports intersections with `t` in `[tmin[i], tmax[i])`.
/// - Barycentrics follow [`HitBatch`]: hit point = `(1 − u − v)·p0 + u·p1 + v·p2`.
/// - Triangles are double-sided; rays that hit a triangle exactly edge-on (in its plane) miss it.
/// - Rays with a non-finite origin or direction, a zero direction or a NaN bound miss.
/// - With an alpha test, masked triangles are transparent wherever
///   [`AlphaTest::is_opaque_at`](crate::AlphaTest::is_opaque_at) is false, for both queries.
/// - Among several intersections at exactly the same `t` (shared edges, coplanar overlaps)
///   the closest-hit query reports the triangle with the smallest id, so the answer does not
///   depend on the traversal order. (Backends may round `t` differently in the last bits, so
///   two backends can still disagree on such ties.)
pub trait Traversal: Send + Sync {
    /// Finds the closest hit of every ray. `hits` is resized to `rays.len()` and every entry
    /// is overwritten.
    fn intersect(&self, rays: &RayBatch, hits: &mut HitBatch);

    /// Tests every ray for any hit, stopping at the first one found. `occluded` is resized to
    /// `rays.len()` and entry `i` is set to whether ray `i` hits anything.
    fn occluded(&self, rays: &RayBatch, occluded: &mut Vec<bool>);

    /// Starts `job` and returns a handle to collect it with. Backends that run asynchronously
    /// (e.g. on a GPU) return before the work is done so the caller can overlap other work;
    /// the default runs the job eagerly on the calling thread.
    fn submit(&self, mut job: TraversalJob) -> Box<dyn PendingTraversal + '_> {
        job.run(self);
        Box::new(CompletedTraversal(job))
    }

    /// Whether [`submit`](Self::submit) returns before the traversal is done and does only
    /// light work on the calling thread (handing the rays to another device), so that a
    /// scheduler may submit from a thread of its own rather than from a worker of its pool.
    /// The default, false, fits backends whose `submit` traverses on the calling thread.
    fn submits_asynchronously(&self) -> bool {
        false
    }

    /// Why the backend cannot trace any more, if it cannot (a GPU device lost or in error):
    /// from then on its queries report every ray as missing and unoccluded, so a caller drops
    /// what it traced since it last checked. `None` (the default) for backends that cannot
    /// fail.
    fn failure(&self) -> Option<String> {
        None
    }
}

/// A query that owns its rays and its output buffer, so it can be in flight on another
/// device while the caller keeps working.
#[derive(Clone, Debug)]
pub enum TraversalJob {
    /// A closest-hit query, see [`Traversal::intersect`].
    Intersect {
        /// The rays to trace.
        rays: RayBatch,
        /// Receives one hit per ray.
        hits: HitBatch,
    },
    /// An occlusion query, see [`Traversal::occluded`].
    Occluded {
        /// The rays to test.
        rays: RayBatch,
        /// Receives one flag per ray.
        occluded: Vec<bool>,
    },
}

impl TraversalJob {
    /// Runs the job synchronously on `traversal`, filling its output buffer.
    pub fn run<T: Traversal + ?Sized>(&mut self, traversal: &T) {
        match self {
            Self::Intersect { rays, hits } => traversal.intersect(rays, hits),
            Self::Occluded { rays, occluded } => traversal.occluded(rays, occluded),
        }
    }

    /// The job's rays.
    pub fn rays(&self) -> &RayBatch {
        match self {
            Self::Intersect { rays, .. } | Self::Occluded { rays, .. } => rays,
        }
    }
}

/// A submitted [`TraversalJob`] that has not been collected yet.
pub trait PendingTraversal: Send {
    /// Blocks until the job is done and returns it with its output buffer filled.
    fn wait(self: Box<Self>) -> TraversalJob;
}

/// A job that already finished when it was submitted; what [`Traversal::submit`] returns by
/// default.
#[derive(Debug)]
pub struct CompletedTraversal(pub TraversalJob);

impl PendingTraversal for CompletedTraversal {
    fn wait(self: Box<Self>) -> TraversalJob {
        self.0
    }
}
