//! Triangles in leaf order and the watertight ray/triangle test (Woop, Benthin, Wald 2013).
//!
//! Möller–Trumbore evaluates the edge shared by two triangles with different expressions in
//! each, so a ray through the edge can miss both. Here every vertex is transformed into a
//! ray-aligned frame independently of the triangle it belongs to and the edge functions are
//! 2D cross products of transformed vertices, so the two triangles sharing an edge compute
//! the same value with opposite signs and no ray slips between them.

use glam::{DVec3, Vec3, Vec3A, Vec3Swizzles};

use super::ray::PreparedRay;

/// A triangle stored transposed: `axes[a]` holds coordinate `a` of the three vertices
/// (lanes 0, 1, 2), so the test can fetch the permuted axes with one load each.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LeafTriangle {
    axes: [Vec3A; 3],
}

/// An accepted ray/triangle intersection before barycentrics are normalised.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Candidate {
    /// Ray parameter of the intersection.
    pub t: f32,
    /// Scaled barycentric weights of the second and third vertices.
    weights: [f32; 2],
    /// Normalisation: the sum of the three scaled weights.
    det: f32,
}

impl Candidate {
    /// Barycentrics `(u, v)`: hit point = `(1 − u − v)·p0 + u·p1 + v·p2`.
    #[inline(always)]
    pub fn barycentrics(&self) -> (f32, f32) {
        let inv_det = 1.0 / self.det;
        (self.weights[0] * inv_det, self.weights[1] * inv_det)
    }
}

impl LeafTriangle {
    /// Stores the triangle with vertices `p0, p1, p2`.
    pub fn new([p0, p1, p2]: [Vec3; 3]) -> Self {
        Self {
            axes: [
                Vec3A::new(p0.x, p1.x, p2.x),
                Vec3A::new(p0.y, p1.y, p2.y),
                Vec3A::new(p0.z, p1.z, p2.z),
            ],
        }
    }

    /// Intersects the ray with the triangle, accepting `t` in `[ray.tmin, tmax)`.
    #[inline(always)]
    pub fn intersect(&self, ray: &PreparedRay, tmax: f32) -> Option<Candidate> {
        let [kx, ky, kz] = ray.axes;
        let [sx, sy, sz] = ray.shear;
        let [ox, oy, oz] = ray.origin_permuted;
        // Vertices relative to the origin in the permuted frame, then sheared onto +z.
        let z = self.axes[kz] - Vec3A::splat(oz);
        let x = self.axes[kx] - Vec3A::splat(ox) - Vec3A::splat(sx) * z;
        let y = self.axes[ky] - Vec3A::splat(oy) - Vec3A::splat(sy) * z;
        // Edge functions: lane 0 is the edge opposite p0, lane 1 opposite p1, lane 2 opposite p2.
        let mut edges = x.zxy() * y.yzx() - y.zxy() * x.yzx();
        if edges.cmpeq(Vec3A::ZERO).any() {
            edges = edges_f64(x, y);
        }
        let negative = edges.cmplt(Vec3A::ZERO).any();
        let positive = edges.cmpgt(Vec3A::ZERO).any();
        if negative && positive {
            return None;
        }
        let det = edges.x + edges.y + edges.z;
        if det == 0.0 {
            return None;
        }
        let t = edges.dot(z * sz) / det;
        (t >= ray.tmin && t < tmax).then_some(Candidate {
            t,
            weights: [edges.y, edges.z],
            det,
        })
    }
}

/// Recomputes the edge functions in double precision, where the products are exact; only
/// needed when a single-precision edge function is exactly zero (ray through an edge or
/// vertex) and its sign is therefore unreliable.
#[cold]
fn edges_f64(x: Vec3A, y: Vec3A) -> Vec3A {
    let (x, y) = (DVec3::from(Vec3::from(x)), DVec3::from(Vec3::from(y)));
    let edges = x.zxy() * y.yzx() - y.zxy() * x.yzx();
    edges.as_vec3().into()
}
