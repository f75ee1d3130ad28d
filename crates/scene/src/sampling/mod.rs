//! Random numbers and sample warps.
//!
//! * [`Sampler`]: where an estimator's uniform numbers come from: [`Rng`], a PCG32
//!   generator with keyed stream construction ([`Rng::from_key`]), or [`SobolSampler`],
//!   randomized quasi-Monte Carlo points stratified across the samples of a pixel.
//! * Warps from the unit square to directions, disks and triangles, each with its pdf
//!   (solid-angle pdfs are per steradian, area pdfs per unit area).
//! * [`Distribution1D`]: discrete distribution for power-proportional selection.
//! * [`ImageDistribution`]: piecewise-constant density over an image (environment maps).
//! * [`power_heuristic`]: multiple importance sampling weight.

use glam::Vec2;

mod distribution;
mod image_distribution;
mod rng;
mod sobol;
mod warps;

pub use distribution::Distribution1D;
pub use image_distribution::{ImageDistribution, image_cell};
pub use rng::Rng;
pub use sobol::{SampleSequence, SobolSampler};

/// A source of numbers uniform on [0, 1), each independent of the others drawn for the same
/// sample.
pub trait Sampler {
    /// One number in [0, 1).
    fn uniform(&mut self) -> f32;

    /// Two numbers in [0, 1)², meant to be used together (a point on a light, a direction).
    #[inline]
    fn uniform2(&mut self) -> Vec2 {
        let x = self.uniform();
        Vec2::new(x, self.uniform())
    }
}

pub use warps::{
    cosine_hemisphere_pdf, power_heuristic, sample_concentric_disk, sample_cosine_hemisphere,
    sample_uniform_cone, sample_uniform_sphere, sample_uniform_triangle, sin_cos_octant,
    uniform_cone_pdf, uniform_sphere_pdf,
};
