//! The integration tests of `vcm-scene`: the glTF and OBJ loaders on hand-written documents,
//! third-party models and fuzzing inputs. One module per concern; filter with
//! `cargo test -p vcm-scene --test integration gltf_features::`.
//!
//! One test binary for the whole crate rather than one per file: each binary links the whole
//! crate and its dependencies again (see issue 57).

mod fuzz_regressions;
mod gltf_features;
mod obj_materials;
mod shared_scenes;
