//! Compile-time selection of alpha testing, so opaque scenes carry no alpha code.

use super::triangle::Candidate;
use crate::alpha::AlphaTest;

/// Decides whether a candidate intersection with a leaf-order triangle counts.
pub(crate) trait HitFilter: Sync {
    /// Whether the candidate on leaf triangle `leaf` is a hit.
    fn accepts(&self, leaf: usize, candidate: &Candidate) -> bool;
}

/// Every candidate is a hit.
pub(crate) struct Opaque;

impl HitFilter for Opaque {
    #[inline(always)]
    fn accepts(&self, _leaf: usize, _candidate: &Candidate) -> bool {
        true
    }
}

/// Consults an [`AlphaTest`] for triangles it marked as masked.
pub(crate) struct Masked<'a> {
    /// The caller's alpha test.
    pub alpha: &'a dyn AlphaTest,
    /// Per leaf-order triangle, the cached [`AlphaTest::is_masked`].
    pub masked: &'a [bool],
    /// Per leaf-order triangle, the caller's id.
    pub ids: &'a [u32],
}

impl HitFilter for Masked<'_> {
    #[inline(always)]
    fn accepts(&self, leaf: usize, candidate: &Candidate) -> bool {
        if !self.masked[leaf] {
            return true;
        }
        let (u, v) = candidate.barycentrics();
        self.alpha.is_opaque_at(self.ids[leaf], u, v)
    }
}
