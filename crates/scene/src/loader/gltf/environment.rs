//! `VCM_environment`, this renderer's own document-level extension: a world background of
//! radiance `color · strength` from every direction, times an equirectangular OpenEXR image's
//! if `image` names one (a URI relative to the glTF file, as images are).
//!
//! ```json
//! "extensionsUsed": ["VCM_environment"],
//! "extensions": {"VCM_environment": {"color": [0.8, 0.9, 1.0], "strength": 0.5,
//!                                    "image": "sky.exr"}}
//! ```

use std::io::Cursor;
use std::path::Path;

use glam::Vec3;
use gltf::json::Value;

use super::extension_json::{finite, malformed};
use crate::light::EnvironmentMap;
use crate::loader::uri::read_uri;

/// The extension's name in the document's `extensions`.
pub(super) const EXTENSION: &str = "VCM_environment";

/// What the extension object asks for.
#[derive(Debug, PartialEq)]
pub(super) struct Environment {
    /// `color · strength`.
    pub radiance: Vec3,
    /// The URI of the equirectangular image, if any.
    pub image: Option<String>,
}

/// The environment of the extension object `value` (`None`, no extension: no environment);
/// `Err` says which property is malformed.
pub(super) fn read(value: Option<&Value>) -> Result<Option<Environment>, String> {
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
            .ok_or_else(|| malformed(EXTENSION, "color", "three finite numbers ≥ 0"))?,
    };
    let strength = match value.get("strength") {
        None => 1.0,
        Some(s) => non_negative(s)
            .ok_or_else(|| malformed(EXTENSION, "strength", "a finite number ≥ 0"))?,
    };
    let image = match value.get("image") {
        None => None,
        Some(uri) => Some(
            uri.as_str()
                .ok_or_else(|| malformed(EXTENSION, "image", "a URI string"))?
                .to_string(),
        ),
    };
    Ok(Some(Environment {
        radiance: color * strength,
        image,
    }))
}

/// Reads the OpenEXR image at `uri` (relative to `base`) as an environment map; errors name
/// the image and the problem.
pub(super) fn load_map(base: &Path, uri: &str) -> Result<EnvironmentMap, String> {
    use exr::prelude::{ReadChannels, ReadLayers};
    let fail = |reason: String| format!("{EXTENSION} image '{uri}': {reason}");
    let bytes = read_uri(base, uri).map_err(fail)?;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |resolution: exr::math::Vec2<usize>, _: &exr::image::RgbaChannels| {
                let (width, height) = (resolution.width(), resolution.height());
                (width, height, vec![Vec3::ZERO; width * height])
            },
            |(width, _, texels): &mut (usize, usize, Vec<Vec3>),
             position: exr::math::Vec2<usize>,
             (r, g, b, _): (f32, f32, f32, f32)| {
                texels[position.y() * *width + position.x()] = Vec3::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| fail(e.to_string()))?;
    let (width, height, texels) = image.layer_data.channel_data.pixels;
    let size = |n: usize| u32::try_from(n).map_err(|_| fail("too large".into()));
    EnvironmentMap::new(size(width)?, size(height)?, texels).map_err(fail)
}

fn non_negative(value: &Value) -> Option<f32> {
    finite(value).filter(|x| *x >= 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(json: &str) -> Result<Option<Environment>, String> {
        let value: Value = gltf::json::deserialize::from_str(json).unwrap();
        read(Some(&value))
    }

    #[test]
    fn color_times_strength_with_white_and_one_by_default() {
        assert_eq!(read(None).unwrap(), None);
        let plain = parse("{}").unwrap().unwrap();
        assert_eq!((plain.radiance, plain.image), (Vec3::ONE, None));
        let sky = parse(r#"{"color": [0.5, 1, 2], "strength": 3, "image": "sky.exr"}"#);
        let sky = sky.unwrap().unwrap();
        assert_eq!(sky.radiance, Vec3::new(1.5, 3.0, 6.0));
        assert_eq!(sky.image.as_deref(), Some("sky.exr"));
    }

    #[test]
    fn malformed_properties_are_named() {
        for (json, property) in [
            (r#"{"color": [1, 1]}"#, "color"),
            (r#"{"color": [1, -1, 1]}"#, "color"),
            (r#"{"color": "blue"}"#, "color"),
            (r#"{"strength": 1e39}"#, "strength"),
            (r#"{"strength": -2}"#, "strength"),
            (r#"{"image": 3}"#, "image"),
        ] {
            let error = parse(json).unwrap_err();
            assert!(error.contains(&format!("`{property}`")), "{json}: {error}");
        }
        assert!(parse("[]").unwrap_err().contains("not an object"));
    }
}
