//! A closest hit turned into a surface point that rays can be spawned from.

use glam::Vec3;
use vcm_scene::Scene;
use vcm_scene::mesh::SurfacePoint;
use vcm_traversal::HitBatch;

use crate::ray_offset::{barycentric_error, offset_ray_origin};

/// A closest hit of a ray.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Hit {
    /// Triangle index.
    pub triangle: u32,
    /// Barycentric weight of the triangle's second corner.
    pub u: f32,
    /// Barycentric weight of the triangle's third corner.
    pub v: f32,
    /// Distance along the (unit) ray direction, scene units.
    pub t: f32,
}

impl Hit {
    /// Ray `i`'s hit in `hits`, `None` when it missed.
    pub fn from_batch(hits: &HitBatch, i: usize) -> Option<Hit> {
        hits.is_hit(i).then(|| Hit {
            triangle: hits.prim[i],
            u: hits.u[i],
            v: hits.v[i],
            t: hits.t[i],
        })
    }
}

/// A point on a triangle with the error bound of its computed position.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SurfaceHit {
    /// Position, normals, texture coordinates and material.
    pub point: SurfacePoint,
    /// Per-axis absolute error bound of `point.position`.
    error: Vec3,
}

impl SurfaceHit {
    /// The point at barycentrics (u, v) of `triangle`.
    pub fn new(scene: &Scene, triangle: u32, u: f32, v: f32) -> SurfaceHit {
        let corners = scene.mesh.corners(triangle as usize);
        SurfaceHit {
            point: scene.surface_point(triangle, u, v),
            error: barycentric_error(&corners, Vec3::new(1.0 - u - v, u, v)),
        }
    }

    /// The point where `hit` met the scene.
    #[inline]
    pub fn at(scene: &Scene, hit: Hit) -> SurfaceHit {
        SurfaceHit::new(scene, hit.triangle, hit.u, hit.v)
    }

    /// Origin for a ray leaving the surface in direction `w`: offset to `w`'s side by the
    /// position's error bound.
    pub fn spawn(&self, w: Vec3) -> Vec3 {
        offset_ray_origin(
            self.point.position,
            self.error,
            self.point.geometric_normal,
            w,
        )
    }

    /// |cos| between `w` (unit) and the geometric normal: the factor that converts solid-angle
    /// densities at the other end of a segment along `w` to area densities here.
    pub fn cos_geometric(&self, w: Vec3) -> f32 {
        self.point.geometric_normal.dot(w).abs()
    }
}
