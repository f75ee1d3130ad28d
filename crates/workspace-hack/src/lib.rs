//! No code: this crate's dependencies (written by `cargo hakari generate`, see
//! `.config/hakari.toml`) turn on, in every build of every workspace member, the union of the
//! features the whole workspace uses. Without it, `cargo run --release` (the `vcm` binary
//! alone), `cargo test --workspace` (with the viewer, the benchmarks and the dev-dependencies)
//! and maturin (the Python package alone) would each compile some dependencies with other
//! features, and so compile them, and everything built on them, again.
