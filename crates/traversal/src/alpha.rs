//! Alpha testing: triangles that are transparent at some points of their surface.

/// Decides whether a candidate intersection with a triangle counts as a hit.
///
/// Triangle ids are the caller's (indices into the slice the backend was built from) and
/// `(u, v)` are barycentrics as in [`HitBatch`](crate::HitBatch). Backends may call
/// [`is_masked`](Self::is_masked) once per triangle at build time and cache the answer.
pub trait AlphaTest: Send + Sync {
    /// Whether triangle `prim` needs [`is_opaque_at`](Self::is_opaque_at); unmasked triangles
    /// are opaque everywhere.
    fn is_masked(&self, prim: u32) -> bool;

    /// Whether masked triangle `prim` is opaque at barycentrics `(u, v)`. Where it is not, rays
    /// pass through it.
    fn is_opaque_at(&self, prim: u32, u: f32, v: f32) -> bool;
}
