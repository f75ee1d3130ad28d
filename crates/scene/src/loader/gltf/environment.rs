//! `VCM_environment`, this renderer's own document-level extension: a constant world
//! background of radiance `color · strength` from every direction.
//!
//! ```json
//! "extensionsUsed": ["VCM_environment"],
//! "extensions": {"VCM_environment": {"color": [0.8, 0.9, 1.0], "strength": 0.5}}
//! ```

use glam::Vec3;
use gltf::json::Value;

use super::json_number::finite;

/// The extension's name in the document's `extensions`.
pub(super) const EXTENSION: &str = "VCM_environment";

/// The environment radiance of the extension object `value` (`None`, no extension: no
/// environment); `Err` says which property is malformed.
pub(super) fn read(value: Option<&Value>) -> Result<Option<Vec3>, String> {
    let Some(value) = value else {
        return Ok(None);
    };
    if !value.is_object() {
        return Err(format!("{EXTENSION} is not an object"));
    }
    let color = match value.get("color") {
        None => Vec3::ONE,
        Some(color) => color
            .as_array()
            .filter(|channels| channels.len() == 3)
            .and_then(|channels| {
                channels
                    .iter()
                    .map(non_negative)
                    .collect::<Option<Vec<_>>>()
            })
            .map(|rgb| Vec3::from_slice(&rgb))
            .ok_or_else(|| malformed("color", "three finite numbers ≥ 0"))?,
    };
    let strength = match value.get("strength") {
        None => 1.0,
        Some(s) => non_negative(s).ok_or_else(|| malformed("strength", "a finite number ≥ 0"))?,
    };
    Ok(Some(color * strength))
}

fn non_negative(value: &Value) -> Option<f32> {
    finite(value).filter(|x| *x >= 0.0)
}

fn malformed(property: &str, expected: &str) -> String {
    format!("{EXTENSION}: `{property}` must be {expected}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(json: &str) -> Result<Option<Vec3>, String> {
        let value: Value = gltf::json::deserialize::from_str(json).unwrap();
        read(Some(&value))
    }

    #[test]
    fn color_times_strength_with_white_and_one_by_default() {
        assert_eq!(read(None).unwrap(), None);
        assert_eq!(parse("{}").unwrap(), Some(Vec3::ONE));
        let sky = parse(r#"{"color": [0.5, 1, 2], "strength": 3}"#).unwrap();
        assert_eq!(sky, Some(Vec3::new(1.5, 3.0, 6.0)));
    }

    #[test]
    fn malformed_properties_are_named() {
        for (json, property) in [
            (r#"{"color": [1, 1]}"#, "color"),
            (r#"{"color": [1, -1, 1]}"#, "color"),
            (r#"{"color": "blue"}"#, "color"),
            (r#"{"strength": 1e39}"#, "strength"),
            (r#"{"strength": -2}"#, "strength"),
        ] {
            let error = parse(json).unwrap_err();
            assert!(error.contains(&format!("`{property}`")), "{json}: {error}");
        }
        assert!(parse("[]").unwrap_err().contains("not an object"));
    }
}
