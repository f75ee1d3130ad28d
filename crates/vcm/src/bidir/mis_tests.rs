//! MIS partition of unity: for one path, the weights that the integrator's techniques give it
//! (emission hit, light sample, every camera–light vertex connection, the light tracing splat
//! and merging at every inner vertex) sum to one.

use vcm_scene::sampling::Rng;

use crate::Algorithm;
use crate::bidir::mis_paths::MisTestPath;

#[test]
fn the_weights_of_every_technique_sum_to_one() {
    let mut rng = Rng::new(2024, 0);
    for k in 2..=6 {
        for _ in 0..200 {
            let path = MisTestPath::random(k, &mut rng);
            for algorithm in [Algorithm::Bpt, Algorithm::Bpm, Algorithm::Vcm] {
                let weights = path.weights(algorithm);
                let sum: f32 = weights.iter().sum();
                assert!(
                    (sum - 1.0).abs() < 1e-3,
                    "{algorithm:?}, {k} segments: weights {weights:?} sum to {sum}"
                );
                assert!(weights.iter().all(|w| (0.0..=1.0).contains(w)));
            }
        }
    }
}
