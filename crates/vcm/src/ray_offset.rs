//! Spawning rays from surface points without self-intersection, at any scene scale.
//!
//! A hit point computed in floating point lies within a small box around the true point on the
//! surface. Offsetting the origin along the geometric normal by the box's extent along that
//! normal, and rounding the result away from the surface, puts it strictly on the side the ray
//! leaves toward (Pharr, Jakob & Humphreys, *PBR* 4th ed., §6.8.4–6.8.6, `OffsetRayOrigin`).
//! Both the error bound and the offset are relative to the coordinates' magnitude, so nothing
//! depends on the scene's units.

use glam::Vec3;

use crate::lanes::{F32s, Vec3s};

/// Unit roundoff of `f32`: half the distance from 1 to the next float, 2⁻²⁴.
const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// γ(n) = n·ε / (1 − n·ε) (Higham 2002, §3.1; *PBR* 4th ed. eq. 6.31): bounds the relative
/// error of n chained floating-point operations.
pub fn gamma(n: u32) -> f32 {
    let ne = n as f32 * MACHINE_EPSILON;
    ne / (1.0 - ne)
}

/// Absolute error bound (scene units, the same on every axis) of a point computed as
/// `b.x · p0 + b.y · p1 + b.z · p2` from barycentrics `b`: γ(7) · max over axes of
/// (|b0·p0| + |b1·p1| + |b2·p2|).
///
/// pbrt-v4 keeps this bound per axis (*PBR* 4th ed. eq. 6.33) and relies on its triangle test
/// rejecting t ≤ δt, a conservative bound on the error of t. The traversal backends here accept
/// any t ≥ tmin without such a bound, so the offset must also cover the test's own rounding,
/// which is relative to all coordinates: on a plane with exact coordinates along one axis
/// (z = 0, say) the per-axis bound is zero there, and a grazing ray from the un-moved point can
/// re-hit its triangle. Using the largest axis's bound on every axis covers that case.
pub fn barycentric_error(corners: &[Vec3; 3], b: Vec3) -> Vec3 {
    let sum = (corners[0] * b.x).abs() + (corners[1] * b.y).abs() + (corners[2] * b.z).abs();
    Vec3::splat(sum.max_element() * gamma(7))
}

/// Moves `p` (with per-axis error bound `p_error`) off its surface of unit geometric normal
/// `n_g`, to the side that direction `w` points into: by d = |n_g|·p_error along ±n_g, then
/// each moved coordinate one float further away (*PBR* 4th ed. §6.8.6).
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n_g: Vec3, w: Vec3) -> Vec3 {
    let d = n_g.abs().dot(p_error);
    let offset = if w.dot(n_g) < 0.0 { -d * n_g } else { d * n_g };
    let moved = p + offset;
    Vec3::from_array(std::array::from_fn(|axis| {
        step_toward(moved[axis], offset[axis])
    }))
}

/// [`offset_ray_origin`] in each lane: the same operations, bit for bit.
#[inline(always)]
pub(crate) fn offset_ray_origins(p: Vec3s, p_error: Vec3s, n_g: Vec3s, w: Vec3s) -> Vec3s {
    let d = n_g.abs().dot(p_error);
    let offset = w
        .dot(n_g)
        .lt(F32s::splat(0.0))
        .select3(n_g.scale(-d), n_g.scale(d));
    let moved = p + offset;
    let step = |x: F32s, o: F32s| F32s::from_fn(|lane| step_toward(x.0[lane], o.0[lane]));
    Vec3s {
        x: step(moved.x, offset.x),
        y: step(moved.y, offset.y),
        z: step(moved.z, offset.z),
    }
}

/// `x` moved to the next float above it when `o` > 0, below it when `o` < 0, and left as it
/// is when `o` is zero or NaN or `x` is not finite: `next_up` / `next_down` without branches
/// on the signs, which are as likely one way as the other here. Finite floats read as
/// sign-magnitude integers are ordered like the numbers they stand for, ±0 both being 0.
#[inline(always)]
fn step_toward(x: f32, o: f32) -> f32 {
    let step = i32::from(o > 0.0) - i32::from(o < 0.0);
    let bits = x.to_bits() as i32;
    let magnitude = bits & i32::MAX;
    let ordinal = if bits < 0 { -magnitude } else { magnitude };
    let moved = ordinal + step;
    let moved_bits = if moved < 0 {
        moved.unsigned_abs() | 0x8000_0000
    } else {
        moved as u32
    };
    if step != 0 && x.is_finite() {
        f32::from_bits(moved_bits)
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec3, Vec2};
    use vcm_scene::sampling::{Rng, Sampler, sample_uniform_triangle};
    use vcm_traversal::{CpuBvh, CpuBvhOptions, RayBatch, Traversal};

    /// Triangles of size `scale`: a slanted one translated by 3·`scale` (coordinates larger
    /// than the triangle) and one in the plane z = 0 (exact z coordinates).
    fn triangles(scale: f32) -> [[Vec3; 3]; 2] {
        let slanted = [
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(1.3, -0.4, 0.9),
            Vec3::new(-0.2, 1.1, -0.7),
        ]
        .map(|c| (c + Vec3::splat(3.0)) * scale);
        let flat = [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        ]
        .map(|c| c * scale);
        [slanted, flat]
    }

    /// Signed distance (in f64) of `p` from the plane of `tri`, positive on the normal's side.
    fn signed_distance(tri: &[Vec3; 3], p: Vec3) -> f64 {
        let [a, b, c] = tri.map(Vec3::as_dvec3);
        let n: DVec3 = (b - a).cross(c - a).normalize();
        (p.as_dvec3() - a).dot(n)
    }

    #[test]
    fn step_toward_moves_like_next_up_and_next_down() {
        let mut rng = Rng::from_key(&[5]);
        let random = (0..1000).map(|_| f32::from_bits(rng.uniform().to_bits() ^ 0x1234_5678));
        let special = [
            0.0,
            -0.0,
            f32::from_bits(1),
            -f32::from_bits(1),
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1.0,
            -1.0,
            f32::MAX,
            f32::MIN,
        ];
        for x in special.into_iter().chain(random).filter(|x| x.is_finite()) {
            // ±0 compare equal: stepping from the smallest subnormal toward zero may give
            // either zero.
            assert_eq!(step_toward(x, 3.0), x.next_up(), "{x:e} up");
            assert_eq!(step_toward(x, -1e-30), x.next_down(), "{x:e} down");
            assert_eq!(step_toward(x, 0.0).to_bits(), x.to_bits(), "{x:e} stays");
            assert_eq!(step_toward(x, f32::NAN).to_bits(), x.to_bits(), "{x:e} NaN");
        }
        for x in [f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(step_toward(x, 1.0), x);
            assert_eq!(step_toward(x, -1.0), x);
        }
        assert!(step_toward(f32::NAN, 1.0).is_nan());
    }

    #[test]
    fn gamma_matches_its_definition() {
        let e = 2f64.powi(-24);
        assert!((gamma(7) as f64 - 7.0 * e / (1.0 - 7.0 * e)).abs() < 1e-12);
    }

    #[test]
    fn offset_points_lie_on_the_side_of_the_outgoing_direction_at_all_scales() {
        let mut rng = Rng::from_key(&[7]);
        for exponent in -4..=5 {
            let scale = 10f32.powi(exponent);
            for tri in triangles(scale) {
                let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
                for _ in 0..2000 {
                    let b = sample_uniform_triangle(rng.uniform2());
                    let p = tri[0] * b.x + tri[1] * b.y + tri[2] * b.z;
                    let error = barycentric_error(&tri, b);
                    for w in [n + Vec3::X * 0.3, -n + Vec3::Y * 0.2] {
                        let q = offset_ray_origin(p, error, n, w);
                        let side = signed_distance(&tri, q).signum();
                        assert_eq!(side, w.dot(n).signum() as f64, "scale {scale}, b {b}");
                        // The offset stays tiny relative to the scene.
                        assert!((q - p).length() < 1e-5 * scale * 10.0, "scale {scale}");
                    }
                }
            }
        }
    }

    /// A point on a triangle: the point, its barycentrics and the unit normal.
    struct SurfacePoint {
        point: Vec3,
        barycentrics: Vec3,
        normal: Vec3,
    }

    /// For every test triangle at scales 10⁻⁴ … 10⁵, 2000 rays from `ray` at random points of
    /// the triangle, traced against the lone triangle: asserts that none is occluded by it.
    fn assert_triangle_never_blocks(
        seed: u64,
        mut ray: impl FnMut(&[Vec3; 3], &SurfacePoint, f32, &mut Rng) -> (Vec3, Vec3, f32),
    ) {
        let mut rng = Rng::from_key(&[seed]);
        for exponent in -4..=5 {
            let scale = 10f32.powi(exponent);
            for tri in triangles(scale) {
                let normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
                let bvh = CpuBvh::new(&[tri], CpuBvhOptions::default()).unwrap();
                let mut rays = RayBatch::default();
                for _ in 0..2000 {
                    let barycentrics = sample_uniform_triangle(rng.uniform2());
                    let point =
                        tri[0] * barycentrics.x + tri[1] * barycentrics.y + tri[2] * barycentrics.z;
                    let surface = SurfacePoint {
                        point,
                        barycentrics,
                        normal,
                    };
                    let (origin, direction, tmax) = ray(&tri, &surface, scale, &mut rng);
                    rays.push(origin, direction, 0.0, tmax);
                }
                let mut occluded = Vec::new();
                bvh.occluded(&rays, &mut occluded);
                let blocked = occluded.iter().filter(|&&o| o).count();
                assert_eq!(blocked, 0, "scale {scale}, triangle {tri:?}");
            }
        }
    }

    #[test]
    fn rays_leaving_an_offset_origin_do_not_hit_their_own_triangle() {
        assert_triangle_never_blocks(11, |tri, surface, _, rng| {
            // Grazing and steep directions on both sides.
            let tangent = (tri[1] - tri[0]).normalize();
            let Vec2 { x: lift, y: sign } = rng.uniform2();
            let side = if sign < 0.5 {
                -surface.normal
            } else {
                surface.normal
            };
            let w = (tangent + side * (1e-4 + lift)).normalize();
            let error = barycentric_error(tri, surface.barycentrics);
            let origin = offset_ray_origin(surface.point, error, surface.normal, w);
            (origin, w, f32::INFINITY)
        });
    }

    #[test]
    fn segments_to_offset_points_are_not_blocked_by_their_triangle_at_any_scale() {
        assert_triangle_never_blocks(13, |tri, surface, scale, rng| {
            // Shadow rays arriving from grazing to steep, from near and far.
            let Vec2 { x: lift, y: reach } = rng.uniform2();
            let p = surface.point;
            let away = ((tri[1] - tri[0]).normalize() + surface.normal * (1e-4 + lift)).normalize();
            let origin = p + away * scale * (1e-3 + 10.0 * reach);
            let error = barycentric_error(tri, surface.barycentrics);
            let target = offset_ray_origin(p, error, surface.normal, origin - p);
            let (direction, tmax) = crate::shadow::segment_to(origin, target);
            (origin, direction, tmax)
        });
    }
}
