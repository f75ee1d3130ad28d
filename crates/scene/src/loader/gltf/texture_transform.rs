//! `KHR_texture_transform` on a texture reference, read from the extension's JSON object
//! (the same for every kind of reference, normal textures included).

use glam::Vec2;
use gltf::json::Value;

use super::extension_json::{finite, malformed};
use crate::texture::UvTransform;

/// The extension's name in a texture reference's `extensions`.
pub(super) const EXTENSION: &str = "KHR_texture_transform";

/// A texture reference's `KHR_texture_transform`.
#[derive(Debug, PartialEq)]
pub(super) struct TextureTransform {
    /// The map of the texture coordinates.
    pub uv: UvTransform,
    /// The UV set that overrides the reference's own `texCoord`, if the extension names one.
    pub tex_coord: Option<u32>,
}

impl TextureTransform {
    /// The transform of the extension object `value` (`None`, no extension: the identity);
    /// `Err` says which property is malformed.
    pub fn read(value: Option<&Value>) -> Result<TextureTransform, String> {
        let Some(value) = value else {
            return Ok(TextureTransform {
                uv: UvTransform::IDENTITY,
                tex_coord: None,
            });
        };
        if !value.is_object() {
            return Err(format!("{EXTENSION} is not an object"));
        }
        let offset = pair(value, "offset", Vec2::ZERO)?;
        let scale = pair(value, "scale", Vec2::ONE)?;
        let rotation = match value.get("rotation") {
            None => 0.0,
            Some(v) => {
                finite(v).ok_or_else(|| malformed(EXTENSION, "rotation", "a finite number"))?
            }
        };
        let tex_coord = match value.get("texCoord") {
            None => None,
            Some(v) => Some(
                v.as_u64()
                    .and_then(|n| u32::try_from(n).ok())
                    .ok_or_else(|| malformed(EXTENSION, "texCoord", "a non-negative integer"))?,
            ),
        };
        Ok(TextureTransform {
            uv: UvTransform::from_offset_rotation_scale(offset, rotation, scale),
            tex_coord,
        })
    }
}

/// Property `name` of the JSON object `object` as two finite numbers, `default` when it is
/// absent.
fn pair(object: &Value, name: &str, default: Vec2) -> Result<Vec2, String> {
    let Some(value) = object.get(name) else {
        return Ok(default);
    };
    match value.as_array().map(Vec::as_slice) {
        Some([x, y]) => finite(x)
            .zip(finite(y))
            .map(|(x, y)| Vec2::new(x, y))
            .ok_or_else(|| malformed(EXTENSION, name, "two finite numbers")),
        _ => Err(malformed(EXTENSION, name, "two finite numbers")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(json: &str) -> Result<TextureTransform, String> {
        let value: Value = gltf::json::deserialize::from_str(json).unwrap();
        TextureTransform::read(Some(&value))
    }

    #[test]
    fn absent_properties_take_the_defaults() {
        let empty = read("{}").unwrap();
        assert_eq!(empty.uv, UvTransform::IDENTITY);
        assert_eq!(empty.tex_coord, None);
        assert_eq!(TextureTransform::read(None).unwrap(), empty);
    }

    #[test]
    fn properties_are_read() {
        let t = read(r#"{"offset": [0.25, 0.5], "scale": [2, 3], "texCoord": 1}"#).unwrap();
        assert_eq!(t.uv.apply(Vec2::new(1.0, 1.0)), Vec2::new(2.25, 3.5));
        assert_eq!(t.tex_coord, Some(1));
    }

    #[test]
    fn malformed_properties_are_named() {
        for (json, property) in [
            (r#"{"offset": [1]}"#, "offset"),
            (r#"{"scale": "big"}"#, "scale"),
            (r#"{"scale": [1, 1e39]}"#, "scale"),
            (r#"{"rotation": [0]}"#, "rotation"),
            (r#"{"texCoord": -1}"#, "texCoord"),
        ] {
            let error = read(json).unwrap_err();
            assert!(error.contains(&format!("`{property}`")), "{json}: {error}");
        }
        assert!(read("[]").unwrap_err().contains("not an object"));
    }
}
