//! Absorption inside solids (glTF `KHR_materials_volume` attenuation): the Beer–Lambert
//! transmittance of the path segments that run through them.
//!
//! A path is inside a solid between crossing its boundary inwards and crossing it back out.
//! Solids are taken not to nest, and the camera and the lights to be outside them: a segment
//! leaving a [volume boundary](vcm_scene::material::Material::bounds_volume) behind it
//! (against its geometric normal) runs inside that solid, one leaving it in front runs
//! outside every solid, and one leaving any other surface runs where the path arrived from.
//! Absorption only scales contributions; no pdf changes, so MIS weights do not see it.

use glam::Vec3;
use vcm_scene::Scene;
use vcm_scene::mesh::SurfacePoint;

/// What a segment runs through: its absorption coefficient σ_a per scene unit (linear RGB),
/// zero outside every solid.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Medium {
    absorption: Vec3,
}

impl Medium {
    /// Outside every solid, where the camera and the lights are.
    pub const OUTSIDE: Medium = Medium {
        absorption: Vec3::ZERO,
    };

    /// The medium of a segment leaving `point` in direction `w`, for a path that reached
    /// `point` through `self`.
    #[inline]
    pub fn toward(self, scene: &Scene, point: &SurfacePoint, w: Vec3) -> Medium {
        if !scene.features.absorbing_volumes {
            return self;
        }
        let material = &scene.materials[point.material as usize];
        if !material.bounds_volume() {
            self
        } else if w.dot(point.geometric_normal) < 0.0 {
            Medium {
                absorption: material.absorption,
            }
        } else {
            Medium::OUTSIDE
        }
    }

    /// The fraction of light, per channel, that crosses `distance` scene units of the medium
    /// (an infinite distance keeps only the channels it does not absorb).
    #[inline]
    pub fn transmittance(self, distance: f32) -> Vec3 {
        let sigma = self.absorption;
        if sigma == Vec3::ZERO {
            return Vec3::ONE;
        }
        Vec3::select(
            sigma.cmpeq(Vec3::ZERO),
            Vec3::ONE,
            (-sigma * distance).exp(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transmittance_is_beer_lambert_per_channel() {
        let medium = Medium {
            absorption: Vec3::new(0.0, 1.0, 2.0),
        };
        let t = medium.transmittance(0.5);
        assert_eq!(t.x, 1.0);
        assert!((t.y - (-0.5f32).exp()).abs() < 1e-6);
        assert!((t.z - (-1.0f32).exp()).abs() < 1e-6);
        assert_eq!(
            medium.transmittance(f32::INFINITY),
            Vec3::new(1.0, 0.0, 0.0)
        );
        assert_eq!(Medium::OUTSIDE.transmittance(f32::INFINITY), Vec3::ONE);
    }
}
