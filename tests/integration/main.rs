//! The integration tests of `vcm-rs`: the `vcm` command line run as a separate process, and the
//! committed scenes. One module per concern; filter with `cargo test --test integration cli::`.
//!
//! One test binary for the whole package rather than one per file: each binary links the whole
//! stack, so every extra file in `tests/` would add a link to `cargo test` (see issue 57).

mod algorithm_choice;
mod cli;
mod command;
mod experiment;
mod gpu_backend;
#[cfg(target_os = "linux")]
mod hostile;
mod mitsuba_crosscheck;
mod render_state;
mod scenes;
