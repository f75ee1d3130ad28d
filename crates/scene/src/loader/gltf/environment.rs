//! `VCM_environment`, this renderer's own document-level extension: a world background of
//! radiance `color · strength` from every direction, times an equirectangular image's (OpenEXR
//! or Radiance HDR) if `image` names one (a URI relative to the glTF file, as images are).
//!
//! ```json
//! "extensionsUsed": ["VCM_environment"],
//! "extensions": {"VCM_environment": {"color": [0.8, 0.9, 1.0], "strength": 0.5,
//!                                    "image": "sky.exr"}}
//! ```

use std::io::Cursor;

use glam::Vec3;
use gltf::json::Value;

use super::extension_json::{finite, malformed};
use crate::image_limits::{check_exr_file, check_image_size};
use crate::light::EnvironmentMap;
use crate::loader::files::{Length, ReadError, SceneFolder};
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

/// The first bytes of every OpenEXR file.
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// The first bytes of every Radiance HDR (RGBE) file: `#?RADIANCE` or `#?RGBE`.
const RADIANCE_MAGIC: &[u8] = b"#?";

/// Reads the image at `uri` (in `folder`) as an environment map: OpenEXR or Radiance HDR,
/// told apart by their first bytes (not by the name); errors name the image and the problem.
pub(super) fn load_map(folder: &SceneFolder, uri: &str) -> Result<EnvironmentMap, ReadError> {
    let fail = |reason: String| ReadError::Failed(format!("{EXTENSION} image '{uri}': {reason}"));
    let bytes = read_uri(folder, uri, Length::Whole).map_err(|e| match e {
        ReadError::Failed(reason) => fail(reason),
        outside => outside,
    })?;
    let (width, height, texels) = if bytes.starts_with(&EXR_MAGIC) {
        read_exr(bytes)
    } else if bytes.starts_with(RADIANCE_MAGIC) {
        read_radiance(bytes)
    } else {
        Err("neither an OpenEXR nor a Radiance HDR image".to_string())
    }
    .map_err(fail)?;
    let size = |n: usize| u32::try_from(n).map_err(|_| fail("too large".into()));
    EnvironmentMap::new(size(width)?, size(height)?, texels).map_err(fail)
}

/// Width, height and linear RGB texels (rows from the top) of an OpenEXR file's first
/// layer.
fn read_exr(bytes: Vec<u8>) -> Result<(usize, usize, Vec<Vec3>), String> {
    use exr::prelude::{ReadChannels, ReadLayers};
    check_exr_file(&bytes)?;
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
        .map_err(|e| e.to_string())?;
    Ok(image.layer_data.channel_data.pixels)
}

/// Width, height and linear RGB texels (rows from the top) of a Radiance HDR file.
fn read_radiance(bytes: Vec<u8>) -> Result<(usize, usize, Vec<Vec3>), String> {
    // Strict decoding accepts only a `#?RADIANCE` first line; Mitsuba and others write
    // `#?RGBE`, which the lenient decoder skips as a comment.
    let decoding = |e: image::ImageError| format!("Radiance HDR: {e}");
    let length = bytes.len();
    let decoder =
        image::codecs::hdr::HdrDecoder::new_nonstrict(Cursor::new(bytes)).map_err(decoding)?;
    let (width, height) = image::ImageDecoder::dimensions(&decoder);
    let (width, height) = (width as usize, height as usize);
    check_image_size(width, height, length)?;
    let image = image::DynamicImage::from_decoder(decoder).map_err(decoding)?;
    let texels = image
        .into_rgb32f()
        .pixels()
        .map(|p| Vec3::from(p.0))
        .collect();
    Ok((width, height, texels))
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
