//! Orthonormal shading frame.

use glam::Vec3;

/// Right-handed orthonormal basis (`x × y = z`); `z` is the normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent.
    pub x: Vec3,
    /// Second tangent (bitangent).
    pub y: Vec3,
    /// Normal.
    pub z: Vec3,
}

impl Frame {
    /// Frame around the unit vector `n`, with tangents from the branchless construction of
    /// Duff et al. 2017, "Building an Orthonormal Basis, Revisited" (JCGT 6(1)).
    pub fn from_z(n: Vec3) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Frame {
            x: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            y: Vec3::new(b, sign + n.y * n.y * a, -n.y),
            z: n,
        }
    }

    /// Frame with normal `n` (unit) and first tangent the Gram-Schmidt orthogonalization of
    /// `tangent` against `n`. Falls back to [`Frame::from_z`] when `tangent` is (nearly)
    /// parallel to `n`, zero or not finite.
    pub fn from_xz(tangent: Vec3, n: Vec3) -> Frame {
        let t = tangent - n * n.dot(tangent);
        let len2 = t.length_squared();
        if !(len2 > 1e-12 && len2.is_finite()) {
            return Frame::from_z(n);
        }
        let x = t / len2.sqrt();
        Frame {
            x,
            y: n.cross(x),
            z: n,
        }
    }

    /// Coordinates of the world vector `v` in this frame.
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }

    /// World vector of the local coordinates `v`.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, Sampler, sample_uniform_sphere};

    fn assert_orthonormal(f: &Frame) {
        for (a, b) in [(f.x, f.y), (f.y, f.z), (f.z, f.x)] {
            assert!(a.dot(b).abs() < 1e-5);
        }
        for v in [f.x, f.y, f.z] {
            assert!((v.length() - 1.0).abs() < 1e-5);
        }
        assert!((f.x.cross(f.y) - f.z).length() < 1e-5, "not right-handed");
    }

    #[test]
    fn from_z_is_orthonormal_everywhere() {
        let mut rng = Rng::new(3, 3);
        let special = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            -Vec3::Y,
            Vec3::new(0.0, 0.0, -0.0),
        ];
        for n in special.into_iter().filter(|n| n.length() > 0.5) {
            assert_orthonormal(&Frame::from_z(n));
        }
        for _ in 0..10_000 {
            let n = sample_uniform_sphere(rng.uniform2());
            let f = Frame::from_z(n);
            assert_orthonormal(&f);
            let v = sample_uniform_sphere(rng.uniform2());
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
            assert!((f.to_local(n) - Vec3::Z).length() < 1e-5);
        }
    }

    #[test]
    fn from_xz_keeps_tangent_direction() {
        let n = Vec3::new(0.3, -0.4, 0.866).normalize();
        let f = Frame::from_xz(Vec3::new(1.0, 0.2, 0.0), n);
        assert_orthonormal(&f);
        assert!(f.x.dot(Vec3::new(1.0, 0.2, 0.0)) > 0.0);
        assert_eq!(f.z, n);
        // Degenerate tangents fall back to the branchless frame.
        assert_eq!(Frame::from_xz(n * 2.0, n), Frame::from_z(n));
        assert_eq!(Frame::from_xz(Vec3::NAN, n), Frame::from_z(n));
    }
}
