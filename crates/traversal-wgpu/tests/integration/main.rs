//! The integration tests of `vcm-traversal-wgpu`: the GPU backend against the
//! backend-independent contract and against the CPU backend. They skip without a graphics
//! adapter unless `VCM_REQUIRE_GPU=1`. Filter with
//! `cargo test -p vcm-traversal-wgpu --test integration parity::`.
//!
//! One test binary for the whole crate rather than one per file: each binary links the whole
//! crate and its dependencies again (see issue 57).

mod common;

mod api;
mod parity;
