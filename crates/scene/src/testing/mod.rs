//! Shared statistical test harness for sampling code (BSDFs, warps, lights).
//!
//! Modelled on pbrt-v4's `bsdfs_test.cpp` and Mitsuba's `chi2` module:
//! * [`chi2_test`]: Pearson chi-square goodness-of-fit test of a direction sampler against
//!   its claimed solid-angle pdf, over a (cos θ, φ) binning of the sphere.
//! * [`integrate_sphere`] / [`integrate_cell`]: adaptive numerical integration of a function
//!   of direction over the sphere or one (cos θ, φ) cell.
//! * [`estimate_mean`]: fixed-seed Monte Carlo mean with its standard error.
//! * [`bsdf_chi2_test`] and [`estimate_albedo`]: the above for a [`Bsdf`](crate::bsdf::Bsdf)
//!   (sampling vs pdf; directional albedo ∫ f_cos dωi by importance sampling).
//! * [`exr_claiming`], [`png_claiming`]: OpenEXR and PNG files whose headers claim a given
//!   size (for size limits).
//! * [`triangle_positions`], [`data_uri`], [`glb`], [`doubling_chain`], [`deep_chain`]: pieces
//!   of glTF files for loader tests.
//!
//! Compiled into every build (not behind a feature), so that the tests of every crate and
//! the library and binaries share one build of `vcm-scene`.

mod bsdf;
mod chi2;
mod estimate;
mod gltf_files;
mod image_headers;
mod integrate;

pub use bsdf::{bsdf_chi2_test, estimate_albedo};
pub use chi2::{Chi2Config, Chi2Result, chi2_test, sidak_significance};
pub use estimate::{Estimate, estimate_mean};
pub use gltf_files::{data_uri, deep_chain, doubling_chain, glb, triangle_positions};
pub use image_headers::{exr_claiming, png_claiming};
pub use integrate::{integrate_cell, integrate_sphere, spherical_direction};
