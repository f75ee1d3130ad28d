//! Numbers in the raw JSON of extensions the `gltf` crate does not parse.

use gltf::json::Value;

/// `value` as an `f32` if it is a number that stays finite in single precision.
pub(super) fn finite(value: &Value) -> Option<f32> {
    value.as_f64().map(|x| x as f32).filter(|x| x.is_finite())
}
