//! Random numbers and sample warps.
//!
//! * [`Rng`]: PCG32 generator with keyed stream construction ([`Rng::from_key`]).
//! * Warps from the unit square to directions, disks and triangles, each with its pdf
//!   (solid-angle pdfs are per steradian, area pdfs per unit area).
//! * [`Distribution1D`]: discrete distribution for power-proportional selection.
//! * [`ImageDistribution`]: piecewise-constant density over an image (environment maps).
//! * [`power_heuristic`]: multiple importance sampling weight.

mod distribution;
mod image_distribution;
mod rng;
mod warps;

pub use distribution::Distribution1D;
pub use image_distribution::{ImageDistribution, image_cell};
pub use rng::Rng;
pub use warps::{
    cosine_hemisphere_pdf, power_heuristic, sample_concentric_disk, sample_cosine_hemisphere,
    sample_uniform_cone, sample_uniform_sphere, sample_uniform_triangle, uniform_cone_pdf,
    uniform_sphere_pdf,
};
