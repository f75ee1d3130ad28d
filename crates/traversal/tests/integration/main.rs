//! The integration tests of `vcm-traversal`: the CPU backend against a brute-force reference,
//! the backend-independent contract, alpha testing and the batch API. One module per concern;
//! filter with `cargo test -p vcm-traversal --test integration reference::`.
//!
//! One test binary for the whole crate rather than one per file: each binary links the whole
//! crate and its dependencies again (see issue 57).

mod common;

mod alpha;
mod api;
mod edge_cases;
mod reference;
