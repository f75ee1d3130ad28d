//! Which random numbers each decision at a path vertex takes.
//!
//! Vertex k of a path draws pairs k·P … k·P + P − 1 of its sequence's dimensions
//! ([`SobolSampler::start_step`](vcm_scene::sampling::SobolSampler::start_step)), P being the
//! pairs of its [`Layout`], one pair per decision in the layout's order (a decision that needs
//! one number takes the first of its pair). The paths of a pixel then draw the same stratified
//! pairs for the same decisions. Code that shades one path draws the pairs in order; code that
//! shades SIMD lanes reads the pairs it uses ahead, by their index here
//! ([`SobolSampler::peek_lanes`](vcm_scene::sampling::SobolSampler::peek_lanes)), and then
//! skips each path's sampler past what that path drew.

/// What a vertex spends one pair of numbers on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Draw {
    /// The stream that picks the cached light vertices a camera vertex connects to.
    CachePicks,
    /// A light, picked by power (first number).
    LightPick,
    /// A point on the light.
    LightPoint,
    /// A lobe of the BSDF (first number).
    Lobe,
    /// A direction from the lobe.
    Direction,
    /// Russian roulette (first number).
    Roulette,
}

/// The decisions of one vertex, in the order of their pairs.
pub(crate) struct Layout<const N: usize>([Draw; N]);

impl<const N: usize> Layout<N> {
    /// Pairs of dimensions a vertex draws.
    pub const fn pairs(&self) -> u32 {
        N as u32
    }

    /// Index of the pair of `draw` within a vertex's pairs.
    pub const fn index(&self, draw: Draw) -> u32 {
        let mut i = 0;
        while i < N {
            // `==` is not available to const functions; the discriminants are.
            if self.0[i] as u8 == draw as u8 {
                return i as u32;
            }
            i += 1;
        }
        panic!("the layout has no such draw")
    }

    /// Indices of the pairs of `draws`.
    pub const fn indices<const M: usize>(&self, draws: [Draw; M]) -> [u32; M] {
        let mut indices = [0; M];
        let mut i = 0;
        while i < M {
            indices[i] = self.index(draws[i]);
            i += 1;
        }
        indices
    }
}

/// A path tracer's vertex: a light sample, then the continuation.
pub(crate) const PATH_TRACER: Layout<5> = Layout([
    Draw::LightPick,
    Draw::LightPoint,
    Draw::Lobe,
    Draw::Direction,
    Draw::Roulette,
]);

/// A camera vertex of the VCM family: its connections to cached light vertices, a light
/// sample, then the continuation.
pub(crate) const CAMERA: Layout<6> = Layout([
    Draw::CachePicks,
    Draw::LightPick,
    Draw::LightPoint,
    Draw::Lobe,
    Draw::Direction,
    Draw::Roulette,
]);

/// A light vertex: the continuation.
pub(crate) const LIGHT: Layout<3> = Layout([Draw::Lobe, Draw::Direction, Draw::Roulette]);

/// A light path's start (vertex 0): a light, a point on it and the emitted direction; as
/// many pairs as [`LIGHT`], so that vertex k of every light path starts at pair 3k.
pub(crate) const EMISSION: Layout<3> = Layout([Draw::LightPick, Draw::LightPoint, Draw::Direction]);

const _: () = assert!(EMISSION.pairs() == LIGHT.pairs());

/// The pairs a vertex shaded in lanes reads ahead of its layout, found when the crate is
/// compiled.
pub(crate) struct LaneDraws<const N: usize> {
    /// Pairs of the layout (how far a vertex moves its numbers).
    pub pairs: u32,
    /// The decisions read.
    pub draws: [Draw; N],
    /// The index of each of `draws` in the layout.
    pub indices: [u32; N],
    /// The index of Russian roulette's pair in the layout.
    pub to_roulette: u32,
}

impl<const N: usize> LaneDraws<N> {
    /// `draws` of `layout`.
    const fn of<const L: usize>(layout: &Layout<L>, draws: [Draw; N]) -> LaneDraws<N> {
        LaneDraws {
            pairs: layout.pairs(),
            draws,
            indices: layout.indices(draws),
            to_roulette: layout.index(Draw::Roulette),
        }
    }
}

/// What a plain Lambert vertex in lanes reads of a camera or path tracer layout: one lobe
/// needs no choice.
const LAMBERT_CAMERA_DRAWS: [Draw; 4] = [
    Draw::LightPick,
    Draw::LightPoint,
    Draw::Direction,
    Draw::Roulette,
];

/// A path tracer's plain Lambert vertex in lanes.
pub(crate) const PATH_TRACER_LANES: LaneDraws<4> =
    LaneDraws::of(&PATH_TRACER, LAMBERT_CAMERA_DRAWS);

/// A camera vertex of the VCM family on a plain Lambert surface, in lanes.
pub(crate) const CAMERA_LANES: LaneDraws<4> = LaneDraws::of(&CAMERA, LAMBERT_CAMERA_DRAWS);

/// A light vertex on a plain Lambert surface, in lanes: one lobe needs no choice.
pub(crate) const LIGHT_LANES: LaneDraws<2> =
    LaneDraws::of(&LIGHT, [Draw::Direction, Draw::Roulette]);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indices_follow_the_layouts_order() {
        assert_eq!(PATH_TRACER_LANES.indices, [0, 1, 3, 4]);
        assert_eq!(CAMERA_LANES.indices, [1, 2, 4, 5]);
        assert_eq!(LIGHT_LANES.indices, [1, 2]);
        assert_eq!((CAMERA_LANES.pairs, LIGHT_LANES.to_roulette), (6, 2));
    }
}
