//! The continuation of eight walks: the cosine-weighted sample of the Lambert lobe, the
//! throughput and ray origin it gives, in lanes; then each lane's Russian roulette and next
//! segment through its walk's own [`Walk::survives`] and [`Walk::advance`], the steps that
//! end the general vertex's [`Walk::scatter`] too.

use vcm_scene::bsdf::TransportMode;

use super::VertexNumbers;
use super::surface::{Scattered, Vertex};
use crate::bidir::mis::{MisFactors, SubpathMis};
use crate::lanes::{F32s, Vec3s};
use crate::vertex_numbers::Draw;
use crate::walk::Walk;

/// The sampled next segments of eight walks, before Russian roulette.
pub(crate) struct Continuations {
    /// The sampled directions and their evaluations.
    pub next: Scattered,
    /// β · f·|cos| / p.
    throughput: Vec3s,
    /// The next segments' origins.
    origin: Vec3s,
    /// Roulette's numbers, computed ahead; a walk takes its own only where it plays.
    roulette: F32s,
    /// The index of roulette's pair in the vertices' layout.
    to_roulette: u32,
}

impl Continuations {
    /// Samples the Lambert lobes at `vertex` in `mode` (`reverse`: with the reverse pdf)
    /// with the direction numbers of `numbers`, for walks with throughput `throughput`
    /// (roulette's numbers taken from `numbers` too).
    #[inline(always)]
    pub fn sample<const N: usize>(
        vertex: &Vertex,
        throughput: Vec3s,
        numbers: &VertexNumbers<N>,
        (mode, reverse): (TransportMode, bool),
    ) -> Continuations {
        let next = vertex.sample(numbers.pair(Draw::Direction), mode, reverse);
        Continuations {
            // β ← β · f·|cos| / p
            throughput: throughput.mul(next.eval.f_cos.div(next.eval.pdf)),
            origin: vertex.spawn(next.wi),
            roulette: numbers.first(Draw::Roulette),
            to_roulette: numbers.lane_draws.to_roulette,
            next,
        }
    }

    /// VCM's quantities `mis` updated for the scatterings at `vertex`, and d_VC as it is
    /// without the merges there ([`SubpathMis::scatter`]; the Lambert lobe is never
    /// specular).
    #[inline(always)]
    pub fn scattered_mis(
        &self,
        vertex: &Vertex,
        mis: &SubpathMis<F32s>,
        factors: &MisFactors<F32s>,
    ) -> (SubpathMis<F32s>, F32s) {
        let (eval, mut next_mis) = (&self.next.eval, *mis);
        let cos_out = vertex.cos_geometric(self.next.wi);
        let d_vc_beside_light = next_mis.scatter(cos_out, eval.pdf, eval.pdf_rev, false, factors);
        (next_mis, d_vc_beside_light)
    }

    /// Continues lane `lane`'s walk: moves its numbers to roulette's pair (past those its
    /// vertex drew), and where the lane's sample is valid the walk remembers `mis`, plays
    /// Russian roulette and, if it survives, starts the next segment. Returns whether the
    /// walk goes on.
    #[inline]
    pub fn go_on<M>(&self, lane: usize, walk: &mut Walk<M>, mis: M) -> bool {
        walk.rng.skip(self.to_roulette);
        if !self.next.valid.get(lane) {
            return false;
        }
        walk.mis = mis;
        let number = self.roulette.0[lane];
        let survives = walk.survives(self.throughput.lane(lane), |rng| {
            rng.skip(1);
            number
        });
        if survives {
            walk.advance(self.origin.lane(lane), self.next.wi.lane(lane));
        }
        survives
    }
}
