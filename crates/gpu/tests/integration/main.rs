//! The integration tests of `vcm-gpu`: the GPU path tracer against the CPU's. They skip
//! without a graphics adapter unless `VCM_REQUIRE_GPU=1` (lavapipe is one). One test binary
//! for the whole crate (see issue 57).

mod common;

mod agreement;
mod failure;
