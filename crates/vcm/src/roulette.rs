//! Russian roulette, shared by camera and light paths.
//!
//! A path goes on with probability q = min(1, max channel of its throughput), the throughput
//! made dimensionless (relative to the path's start) and freed of refraction's radiance
//! scaling (1/η² per crossing into a denser medium, which is not a loss). The survivors'
//! throughput is divided by q, so it stays near 1 where it used to fall, and never grows
//! where nothing is lost: along lossless chains (perfect mirrors, glass) q is 1. A cap below 1
//! would multiply the weight by 1/cap at every lossless bounce, and inside glass, where total
//! internal reflection keeps some paths for hundreds of bounces, that tail has infinite
//! variance (the sample mean of a furnace with an IOR-3 sphere stayed 5% low after 1000
//! frames). Chains that never lose anything may also never end (a closed mirror box): after
//! [`CAPPED_AFTER_SEGMENTS`] segments q is capped at [`CAPPED_CONTINUATION`], which ends every
//! path without bias.

use glam::Vec3;
use vcm_scene::bsdf::{BsdfSample, TransportMode};

/// Segments after which Russian roulette starts.
const ROULETTE_AFTER_SEGMENTS: u32 = 3;

/// Segments after which the continuation probability is capped, so that every path ends.
const CAPPED_AFTER_SEGMENTS: u32 = 1024;

/// The continuation probability's cap after [`CAPPED_AFTER_SEGMENTS`].
const CAPPED_CONTINUATION: f32 = 0.95;

/// What Russian roulette knows of a path besides its throughput and length: the factor that
/// makes the throughput dimensionless and undoes refraction's radiance scaling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Roulette {
    scale: f32,
}

impl Roulette {
    /// For a path whose throughput starts at 1 (camera paths).
    pub const UNIT: Roulette = Roulette { scale: 1.0 };

    /// For a path whose throughput starts at `throughput` (light paths: emitted power over
    /// the sampling pdfs), so that the light's units do not matter.
    pub fn relative_to(throughput: Vec3) -> Roulette {
        Roulette {
            scale: 1.0 / throughput.max_element(),
        }
    }

    /// Follows a scattering by `sample` of a path carrying `mode`: radiance refracted from
    /// a medium into one η times denser is scaled by 1/η², which roulette undoes.
    pub fn scattered(&mut self, sample: &BsdfSample, mode: TransportMode) {
        if mode == TransportMode::Radiance {
            self.scale *= sample.eta * sample.eta;
        }
    }

    /// The probability of going on after `segments` segments with `throughput`, or `None`
    /// while the path is too short for roulette or goes on surely.
    pub fn continuation_probability(&self, segments: u32, throughput: Vec3) -> Option<f32> {
        if segments < ROULETTE_AFTER_SEGMENTS {
            return None;
        }
        let cap = if segments < CAPPED_AFTER_SEGMENTS {
            1.0
        } else {
            CAPPED_CONTINUATION
        };
        let continuation = (throughput.max_element() * self.scale).min(cap);
        (continuation < 1.0).then_some(continuation)
    }

    /// Plays roulette after `segments` segments: returns whether the path goes on, and if so
    /// divides `throughput` by the continuation probability. `uniform` gives the random
    /// number in [0, 1), drawn only when there is a game to play.
    pub fn survives(
        &self,
        segments: u32,
        throughput: &mut Vec3,
        uniform: impl FnOnce() -> f32,
    ) -> bool {
        let Some(continuation) = self.continuation_probability(segments, *throughput) else {
            return true;
        };
        if uniform() >= continuation {
            return false;
        }
        *throughput /= continuation;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vcm_scene::bsdf::LobeKind;

    fn refraction(eta: f32) -> BsdfSample {
        BsdfSample {
            wi: Vec3::NEG_Z,
            f_cos: Vec3::splat(1.0 / (eta * eta)),
            pdf_fwd: 1.0,
            pdf_rev: 1.0,
            lobe: LobeKind::Specular,
            transmitted: true,
            eta,
        }
    }

    #[test]
    fn short_paths_and_lossless_chains_go_on_surely() {
        let roulette = Roulette::UNIT;
        assert_eq!(roulette.continuation_probability(2, Vec3::splat(0.1)), None);
        assert_eq!(roulette.continuation_probability(3, Vec3::ONE), None);
        assert_eq!(roulette.continuation_probability(1023, Vec3::ONE), None);
        assert_eq!(
            roulette.continuation_probability(3, Vec3::new(0.2, 0.5, 0.1)),
            Some(0.5)
        );
    }

    #[test]
    fn every_long_path_meets_the_cap() {
        let roulette = Roulette::UNIT;
        let capped = Some(CAPPED_CONTINUATION);
        assert_eq!(roulette.continuation_probability(1024, Vec3::ONE), capped);
        assert_eq!(
            roulette.continuation_probability(10_000, Vec3::splat(5.0)),
            capped
        );
    }

    #[test]
    fn radiance_refracted_into_glass_is_not_a_loss() {
        let mut roulette = Roulette::UNIT;
        let sample = refraction(3.0);
        roulette.scattered(&sample, TransportMode::Radiance);
        assert_eq!(roulette.continuation_probability(10, sample.f_cos), None);
        let mut importance = Roulette::UNIT;
        importance.scattered(&sample, TransportMode::Importance);
        assert_eq!(importance, Roulette::UNIT);
    }

    #[test]
    fn light_paths_are_judged_relative_to_their_emission() {
        let roulette = Roulette::relative_to(Vec3::new(40.0, 80.0, 20.0));
        let continuation = roulette.continuation_probability(5, Vec3::new(20.0, 40.0, 10.0));
        assert_eq!(continuation, Some(0.5));
    }

    #[test]
    fn survivors_carry_the_lost_probability() {
        let roulette = Roulette::UNIT;
        let mut throughput = Vec3::splat(0.25);
        assert!(roulette.survives(4, &mut throughput, || 0.2));
        assert_eq!(throughput, Vec3::ONE);
        let mut throughput = Vec3::splat(0.25);
        assert!(!roulette.survives(4, &mut throughput, || 0.3));
        let mut throughput = Vec3::ONE;
        let never = || -> f32 { panic!("no game, no random number") };
        assert!(roulette.survives(4, &mut throughput, never));
    }
}
