//! [`BidirPlan`]: which parts of a VCM-family frame run, after leaving out what the scene does
//! not need.

use vcm_scene::features::NEAR_SPECULAR_ROUGHNESS;
use vcm_scene::shading_plan::decide;
use vcm_scene::{Decision, SceneFeatures};

use super::Algorithm;
use super::mis::MisFactors;

/// The parts of a frame that run for one algorithm on one scene.
///
/// With pruning, a scene without diffuse or glossy surfaces traces no light paths (no vertex
/// would be stored or splatted), and VCM on a scene without specular or near-specular
/// surfaces merges nothing and builds no hash grid: every path then has a vertex that
/// connections sample, and VCM runs with BPT's techniques and weights (the same expectation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BidirPlan {
    /// Light vertices are kept in the cache (for connections or merging).
    pub cache: bool,
    /// Light vertices are connected to the camera.
    pub splats: bool,
    /// Camera vertices take light samples and connect to cached light vertices.
    pub connects: bool,
    /// Camera vertices merge with cached light vertices through the hash grid.
    pub merges: bool,
}

impl BidirPlan {
    /// The plan of `algorithm` on a scene with `features`; `prune: false` runs every part the
    /// algorithm has.
    pub fn new(algorithm: Algorithm, features: &SceneFeatures, prune: bool) -> BidirPlan {
        let light_vertices = !prune || features.materials.non_specular();
        let cache = algorithm.caches() && light_vertices;
        let merging_needed =
            !prune || algorithm != Algorithm::Vcm || features.materials.specular_or_near();
        BidirPlan {
            cache,
            splats: algorithm.splats() && light_vertices,
            connects: algorithm.connects(),
            merges: algorithm.merges() && cache && merging_needed,
        }
    }

    /// Whether light paths are traced at all.
    pub fn light_paths(&self) -> bool {
        self.cache || self.splats
    }

    /// The MIS factors of an iteration that merges within `radius` and traces `light_paths`
    /// light paths: [η_VCM where merging, 1/η_VCM where connecting and merging, 1/η_VCM where
    /// merging, 1 where connecting] (`MisFactors`).
    pub fn mis_factors(&self, radius: f32, light_paths: f32) -> [f32; 4] {
        let f = MisFactors::new(self.connects, self.merges, radius, light_paths);
        [f.merge, f.connect, f.hit, f.connections]
    }

    /// The fewest segments a light vertex that merges lies from its light (a grid holds only
    /// those, as `MisFactors::shortest_merged` says).
    pub fn shortest_merged(&self) -> u32 {
        MisFactors::new(self.connects, self.merges, 1.0, 1.0).shortest_merged()
    }

    /// Each part and why it runs or is left out, for `algorithm` on a scene with `features`.
    pub fn decisions(&self, algorithm: Algorithm, features: &SceneFeatures) -> Vec<Decision> {
        let name = algorithm.name();
        let full = BidirPlan::new(algorithm, features, false);
        let needed = BidirPlan::new(algorithm, features, true);
        let no_vertices = "no diffuse or glossy surface: light paths would store and splat nothing";
        let explain = |part, pick: fn(&BidirPlan) -> bool, because: &str, absent: &str| {
            let otherwise = if !pick(&full) {
                format!("{name} {absent}")
            } else if !features.materials.non_specular() {
                no_vertices.to_string()
            } else {
                format!(
                    "no specular or near-specular surface (roughness ≥ {NEAR_SPECULAR_ROUGHNESS} \
                     everywhere): every path has a vertex that connections sample, so {name} \
                     runs with the techniques and weights of bpt"
                )
            };
            decide(part, (pick(self), pick(&needed)), because, &otherwise)
        };
        let merging = if algorithm == Algorithm::Vcm {
            "the scene has specular or near-specular surfaces, whose caustics only merging samples well"
        } else {
            "merging is what the algorithm does"
        };
        vec![
            explain(
                "light paths",
                BidirPlan::light_paths,
                "their vertices are cached or splatted",
                "neither caches nor splats light vertices",
            ),
            explain(
                "light vertex cache",
                |p| p.cache,
                "camera vertices connect to it or merge with it",
                "neither connects nor merges",
            ),
            explain(
                "light tracing splats",
                |p| p.splats,
                "light vertices connect to the camera",
                "does not connect light vertices to the camera",
            ),
            explain(
                "merging and hash grid",
                |p| p.merges,
                merging,
                "does not merge",
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vcm_scene::features::MaterialClasses;

    const ALGORITHMS: [Algorithm; 5] = [
        Algorithm::LightTracing,
        Algorithm::Bpt,
        Algorithm::Ppm,
        Algorithm::Bpm,
        Algorithm::Vcm,
    ];

    fn features(materials: MaterialClasses) -> SceneFeatures {
        let mesh = vcm_scene::Mesh::default();
        let mut features = SceneFeatures::of(&mesh, &[], &[], &[]);
        features.materials = materials;
        features
    }

    const DIFFUSE: MaterialClasses = MaterialClasses {
        diffuse: true,
        glossy: false,
        specular: false,
        near_specular: false,
        transmission: false,
    };

    #[test]
    fn without_pruning_every_part_of_the_algorithm_runs() {
        for algorithm in ALGORITHMS {
            let plan = BidirPlan::new(algorithm, &features(MaterialClasses::default()), false);
            assert_eq!(plan.cache, algorithm.caches(), "{algorithm:?}");
            assert_eq!(plan.splats, algorithm.splats(), "{algorithm:?}");
            assert_eq!(plan.connects, algorithm.connects(), "{algorithm:?}");
            assert_eq!(plan.merges, algorithm.merges(), "{algorithm:?}");
        }
    }

    #[test]
    fn vcm_merges_only_where_specular_or_near_specular_surfaces_are() {
        let diffuse = features(DIFFUSE);
        let plan = BidirPlan::new(Algorithm::Vcm, &diffuse, true);
        assert!(plan.cache && plan.connects && plan.splats && !plan.merges);
        assert_eq!(plan, BidirPlan::new(Algorithm::Bpt, &diffuse, true));
        for classes in [
            MaterialClasses {
                specular: true,
                ..DIFFUSE
            },
            MaterialClasses {
                glossy: true,
                near_specular: true,
                ..DIFFUSE
            },
        ] {
            assert!(BidirPlan::new(Algorithm::Vcm, &features(classes), true).merges);
        }
        // Photon mapping merges by definition, whatever the surfaces.
        for algorithm in [Algorithm::Ppm, Algorithm::Bpm] {
            assert!(BidirPlan::new(algorithm, &diffuse, true).merges);
        }
    }

    #[test]
    fn without_diffuse_or_glossy_surfaces_no_light_path_is_traced() {
        let mirrors = features(MaterialClasses {
            specular: true,
            ..MaterialClasses::default()
        });
        for algorithm in ALGORITHMS {
            let plan = BidirPlan::new(algorithm, &mirrors, true);
            assert!(!plan.light_paths() && !plan.merges, "{algorithm:?}");
            assert_eq!(plan.connects, algorithm.connects());
        }
    }

    #[test]
    fn decisions_name_each_part_and_the_reason() {
        let diffuse = features(DIFFUSE);
        let pruned = BidirPlan::new(Algorithm::Vcm, &diffuse, true);
        let decisions = pruned.decisions(Algorithm::Vcm, &diffuse);
        let merging = decisions
            .iter()
            .find(|d| d.part == "merging and hash grid")
            .unwrap();
        assert!(
            !merging.runs
                && merging
                    .reason
                    .contains("runs with the techniques and weights of bpt")
        );
        let full = BidirPlan::new(Algorithm::Vcm, &diffuse, false);
        let merging = full.decisions(Algorithm::Vcm, &diffuse).swap_remove(3);
        assert!(merging.runs && merging.reason.ends_with("but pruning is off"));
        let lt = BidirPlan::new(Algorithm::LightTracing, &diffuse, true);
        let cache = lt
            .decisions(Algorithm::LightTracing, &diffuse)
            .swap_remove(1);
        assert_eq!(
            cache.to_string(),
            "light vertex cache: left out (lt neither connects nor merges)"
        );
    }
}
