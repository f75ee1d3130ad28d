//! Shared test helpers: seeded random draws (the project's PCG32 from `vcm_scene`), mesh
//! generators and a brute-force f64 reference.

use glam::{DVec3, Vec3};
use vcm_scene::sampling::sample_uniform_sphere;
pub use vcm_scene::sampling::{Rng, Sampler};
use vcm_traversal::{HitBatch, NO_HIT, RayBatch};

/// The draws the tests need, on top of [`Rng`]'s uniforms.
pub trait RngExt {
    /// Uniform in [lo, hi).
    fn range(&mut self, lo: f32, hi: f32) -> f32;
    /// Uniform in `0..n`.
    fn below(&mut self, n: usize) -> usize;
    /// Uniform in the cube [lo, hi)³.
    fn point_in_box(&mut self, lo: f32, hi: f32) -> Vec3;
    /// Uniform on the unit sphere.
    fn unit_vector(&mut self) -> Vec3;
}

impl RngExt for Rng {
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.uniform()
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next_u32() as usize) % n
    }

    fn point_in_box(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }

    fn unit_vector(&mut self) -> Vec3 {
        sample_uniform_sphere(self.uniform2())
    }
}

/// `count` random triangles with vertices in a cube of side `extent`, of varied sizes.
pub fn triangle_soup(rng: &mut Rng, count: usize, extent: f32) -> Vec<[Vec3; 3]> {
    (0..count)
        .map(|_| {
            let center = rng.point_in_box(0.0, extent);
            let size = extent * 0.2 * rng.uniform().powi(2);
            [0; 3].map(|_| center + rng.unit_vector() * size)
        })
        .collect()
}

/// A height field over the unit square with `n × n` quads, sharing all edges.
pub fn height_field(rng: &mut Rng, n: usize) -> Vec<[Vec3; 3]> {
    let heights: Vec<f32> = (0..(n + 1) * (n + 1))
        .map(|_| rng.range(0.0, 0.05))
        .collect();
    let p = |i: usize, j: usize| {
        Vec3::new(
            i as f32 / n as f32,
            heights[i * (n + 1) + j],
            j as f32 / n as f32,
        )
    };
    let mut tris = Vec::new();
    for i in 0..n {
        for j in 0..n {
            tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    tris
}

/// Relative tolerance on `t` when comparing with the reference.
const REL_TOL: f64 = 1e-4;

/// Barycentric margin below which a reference hit counts as grazing an edge.
const EDGE_EPS: f64 = 1e-5;

fn tolerance(t: f64) -> f64 {
    REL_TOL * t.abs().max(1e-3)
}

/// An intersection found by the f64 reference.
#[derive(Clone, Copy, Debug)]
pub struct RefHit {
    pub prim: u32,
    pub t: f64,
    /// Clearly inside the triangle and clearly inside `[tmin, tmax)`: the backend must not
    /// miss it. Other hits graze an edge or a bound, where f32 and f64 may disagree.
    pub definite: bool,
}

/// All intersections of a ray with `t` in `[tmin, tmax)` up to tolerance, found in f64
/// (Möller–Trumbore), including near misses within `EDGE_EPS` of an edge.
pub fn reference_hits(tris: &[[Vec3; 3]], o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Vec<RefHit> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let (tmin, tmax) = (f64::from(tmin), f64::from(tmax));
    let mut hits = Vec::new();
    for (prim, tri) in tris.iter().enumerate() {
        let [p0, p1, p2] = tri.map(|p| p.as_dvec3());
        let (e1, e2) = (p1 - p0, p2 - p0);
        let pv = d.cross(e2);
        let det = e1.dot(pv);
        if det == 0.0 {
            continue;
        }
        let s = o - p0;
        let u = s.dot(pv) / det;
        let q = s.cross(e1);
        let v = d.dot(q) / det;
        let t = e2.dot(q) / det;
        let margin = u.min(v).min(1.0 - u - v);
        let tol = tolerance(t);
        if margin >= -EDGE_EPS && t >= tmin - tol && t < tmax + tol {
            hits.push(RefHit {
                prim: prim as u32,
                t,
                definite: margin > EDGE_EPS && t >= tmin + tol && t < tmax - tol,
            });
        }
    }
    hits
}

/// Outcome of comparing one backend answer with the reference.
#[derive(Debug, PartialEq, Eq)]
pub enum Agreement {
    /// Same primitive (or both miss).
    Exact,
    /// A different primitive tied with the reference's closest within tolerance, or a
    /// grazing hit or miss the reference cannot decide.
    Tie,
}

/// Checks the backend's answer `(t, prim)` for ray `i` against the f64 reference.
pub fn check_against_reference(
    tris: &[[Vec3; 3]],
    rays: &RayBatch,
    i: usize,
    t: f32,
    prim: u32,
) -> Result<Agreement, String> {
    let refs = reference_hits(
        tris,
        rays.origin(i),
        rays.direction(i),
        rays.tmin[i],
        rays.tmax[i],
    );
    let closest_definite = refs
        .iter()
        .filter(|h| h.definite)
        .min_by(|a, b| a.t.total_cmp(&b.t));
    if prim == NO_HIT {
        return match closest_definite {
            None if refs.is_empty() => Ok(Agreement::Exact),
            None => Ok(Agreement::Tie),
            Some(h) => Err(format!("ray {i}: backend missed, reference hit {h:?}")),
        };
    }
    let t = f64::from(t);
    let Some(reported) = refs.iter().find(|h| h.prim == prim) else {
        return Err(format!(
            "ray {i}: backend hit prim {prim} at {t}, reference has no such hit: {refs:?}"
        ));
    };
    if (reported.t - t).abs() > tolerance(t) {
        return Err(format!(
            "ray {i}: prim {prim} at t {t}, reference t {}",
            reported.t
        ));
    }
    match closest_definite {
        Some(h) if h.t < t - tolerance(t) => Err(format!(
            "ray {i}: backend hit prim {prim} at {t}, reference has a closer hit {h:?}"
        )),
        Some(h) if h.prim == prim => Ok(Agreement::Exact),
        None if refs.len() == 1 => Ok(Agreement::Exact),
        _ => Ok(Agreement::Tie),
    }
}

/// Checks a whole batch against the reference, returning the number of ties.
pub fn assert_matches_reference(tris: &[[Vec3; 3]], rays: &RayBatch, hits: &HitBatch) -> usize {
    let mut ties = 0;
    for i in 0..rays.len() {
        match check_against_reference(tris, rays, i, hits.t[i], hits.prim[i]) {
            Ok(Agreement::Exact) => {}
            Ok(Agreement::Tie) => ties += 1,
            Err(message) => panic!("{message}"),
        }
    }
    ties
}

/// The point at barycentrics `(u, v)` of `tri`, in f64.
pub fn point_at(tri: &[Vec3; 3], u: f32, v: f32) -> DVec3 {
    let [p0, p1, p2] = tri.map(|p| p.as_dvec3());
    p0 * f64::from(1.0 - u - v) + p1 * f64::from(u) + p2 * f64::from(v)
}
