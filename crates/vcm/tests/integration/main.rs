//! The integration tests of `vcm`: every integrator against analytic values, against each
//! other and against itself (determinism, pruning), on scenes built in code (`common`) and on
//! the committed scenes. One module per concern, `stiff` the suite of scenes at the edges of
//! floating point; filter with `cargo test -p vcm --test integration furnace::` or `stiff::`.
//!
//! One test binary for the whole crate rather than one per file: each binary links the whole
//! stack again (see issue 57).

mod common;

mod absorption;
mod algorithms_agree;
mod api;
mod area_light;
mod cornell_convergence;
mod determinism;
mod environment;
mod furnace;
mod lambert_lanes;
mod merge_radius;
mod pruning;
mod punctual_lights;
mod sds_caustic;
mod stiff;
mod stop;
mod vertex_colors;
