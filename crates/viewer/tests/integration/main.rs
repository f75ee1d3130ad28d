//! The integration tests of `vcm-viewer`, which run the viewer as a separate process: its
//! errors before a window opens, a screenshot and a resumed render state under Xvfb. Filter with
//! `cargo test -p vcm-viewer --test integration screenshot::`.
//!
//! One test binary for the whole crate rather than one per file: each binary links the whole
//! stack again (see issue 57).

mod exit_errors;
mod resume;
mod screenshot;
