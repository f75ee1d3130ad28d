//! [`ShadingPlan`]: the per-hit work a scene needs, chosen from its [`SceneFeatures`].

use crate::decision::Decision;
use crate::features::SceneFeatures;

/// What [`crate::Scene::surface_point`] and [`crate::Scene::emission_on_hit`] do at every hit.
/// Each part left out would have no effect on the scene it was planned for, so a render with
/// the plan equals one with [`ShadingPlan::FULL`] bit for bit, and costs less.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShadingPlan {
    /// Interpolate texture coordinates at hits (else they are left at zero: no material
    /// samples a texture).
    pub texture_coordinates: bool,
    /// Look up normal maps and interpolate vertex tangents (else: interpolated vertex normals).
    pub normal_maps: bool,
    /// Look up the emitter behind every hit triangle (else: no triangle emits, no hit finds
    /// emission).
    pub emitter_lookups: bool,
}

impl ShadingPlan {
    /// Every part runs, whatever the scene contains (for comparisons).
    pub const FULL: ShadingPlan = ShadingPlan {
        texture_coordinates: true,
        normal_maps: true,
        emitter_lookups: true,
    };

    /// The parts a scene with `features` needs.
    pub fn for_features(features: &SceneFeatures) -> ShadingPlan {
        ShadingPlan {
            texture_coordinates: features.textures,
            normal_maps: features.normal_maps,
            emitter_lookups: features.lights.area > 0,
        }
    }

    /// Each part and why it runs or is left out, for a scene with `features`.
    pub fn decisions(&self, features: &SceneFeatures) -> Vec<Decision> {
        let lights = &features.lights;
        let no_emitters = if lights.only_delta() {
            "only point, spot and directional lights: no path can hit a light, and the \
             emission-hit technique is left out with the lookup"
        } else {
            "no emissive triangles"
        };
        vec![
            decide(
                "texture coordinates and lookups",
                (self.texture_coordinates, features.textures),
                "some material samples a texture",
                "no material samples a texture",
            ),
            decide(
                "normal maps and tangents",
                (self.normal_maps, features.normal_maps),
                "some material has a normal map",
                "no material has a normal map",
            ),
            decide(
                "emitter lookup at hits",
                (self.emitter_lookups, lights.area > 0),
                "the scene has emissive triangles",
                no_emitters,
            ),
        ]
    }
}

/// The decision for `part` from (whether it runs, whether the scene needs it).
pub fn decide(
    part: &'static str,
    (runs, needed): (bool, bool),
    because: &str,
    otherwise: &str,
) -> Decision {
    match (runs, needed) {
        (false, _) => Decision::left_out(part, otherwise),
        (true, true) => Decision::runs(part, because),
        (true, false) => Decision::runs(part, format!("{otherwise}, but pruning is off")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mesh;
    use crate::light::{Light, PointLight};
    use glam::Vec3;

    #[test]
    fn a_scene_without_textures_normal_maps_or_emitters_plans_none_of_them() {
        let point = Light::Point(PointLight {
            position: Vec3::ZERO,
            intensity: Vec3::ONE,
        });
        let features = SceneFeatures::of(&Mesh::default(), &[], &[], &[point]);
        let plan = ShadingPlan::for_features(&features);
        assert!(!plan.texture_coordinates && !plan.normal_maps && !plan.emitter_lookups);
        let decisions = plan.decisions(&features);
        assert!(decisions.iter().all(|d| !d.runs));
        assert!(
            decisions[2]
                .reason
                .contains("only point, spot and directional lights")
        );
        let full = ShadingPlan::FULL.decisions(&features);
        assert!(
            full.iter()
                .all(|d| d.runs && d.reason.ends_with("but pruning is off"))
        );
    }
}
