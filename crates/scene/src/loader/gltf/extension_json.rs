//! Reading the raw JSON of extensions the `gltf` crate does not parse: numbers, and the
//! message for a malformed property.

use gltf::json::Value;

/// `value` as an `f32` if it is a number that stays finite in single precision.
pub(super) fn finite(value: &Value) -> Option<f32> {
    value.as_f64().map(|x| x as f32).filter(|x| x.is_finite())
}

/// The error for property `property` of extension `extension`, which is not `expected`.
pub(super) fn malformed(extension: &str, property: &str, expected: &str) -> String {
    format!("{extension}: `{property}` must be {expected}")
}
