//! Reading and writing images: linear OpenEXR for results, tone-mapped PNG for viewing, and
//! false-colour error images. Every write goes to a temporary file in the same folder that is
//! renamed over the target, so an interrupted write never leaves a broken image.

use std::io::Seek;
use std::path::{Path, PathBuf};

use exr::prelude::{
    Encoding, Image, LineOrder, ReadChannels, ReadLayers, SpecificChannels, WritableImage,
};
use glam::Vec3;

/// Why an image could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// The EXR file could not be read or written.
    #[error("{path}: {reason}")]
    Exr {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// The PNG file could not be written.
    #[error("{path}: {reason}")]
    Png {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// Renaming the temporary file over the target failed.
    // The I/O error is part of the message, not an error source (see `SceneError::Io`).
    #[error("{path}: cannot replace the file: {reason}")]
    Rename {
        /// The target file.
        path: PathBuf,
        /// The I/O error.
        reason: std::io::Error,
    },
}

/// A linear RGB image (row-major, top row first).
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Linear RGB per pixel.
    pub pixels: Vec<Vec3>,
}

/// [`write_atomically`](crate::atomic_write::write_atomically) with image errors.
fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), ImageError>,
) -> Result<(), ImageError> {
    crate::atomic_write::write_atomically(path, write, |reason| ImageError::Rename {
        path: path.to_path_buf(),
        reason,
    })
}

impl RgbImage {
    /// Writes the image as a 32-bit float RGB OpenEXR file.
    pub fn write_exr(&self, path: &Path) -> Result<(), ImageError> {
        write_atomically(path, |temporary| {
            let channels = SpecificChannels::rgb(|exr::math::Vec2(x, y)| {
                let p: Vec3 = self.pixels[y * self.width + x];
                (p.x, p.y, p.z)
            });
            // Blocks stored in increasing order: with exr's default (unspecified) order its
            // parallel writer stored them as its threads finished, so the same image gave
            // files that differ byte for byte.
            let encoding = Encoding {
                line_order: LineOrder::Increasing,
                ..Encoding::FAST_LOSSLESS
            };
            Image::from_encoded_channels((self.width, self.height), encoding, channels)
                .write()
                .to_file(temporary)
                .map_err(|e| ImageError::Exr {
                    path: path.to_path_buf(),
                    reason: e.to_string(),
                })
        })
    }

    /// Reads the first RGB(A) layer of an OpenEXR file.
    /// Images over [`MAX_TEXELS`](vcm_scene::image_limits::MAX_TEXELS) are refused from
    /// their headers, before anything is allocated for them; the pixels are then read from
    /// the same open file, so the file checked is the file read.
    pub fn read_exr(path: &Path) -> Result<RgbImage, ImageError> {
        let fail = |reason: String| ImageError::Exr {
            path: path.to_path_buf(),
            reason,
        };
        let mut file = std::fs::File::open(path).map_err(|e| fail(e.to_string()))?;
        vcm_scene::image_limits::check_exr_layers(&mut file).map_err(fail)?;
        file.rewind().map_err(|e| fail(e.to_string()))?;
        let image = exr::prelude::read()
            .no_deep_data()
            .largest_resolution_level()
            .rgba_channels(
                |resolution, _| RgbImage {
                    width: resolution.width(),
                    height: resolution.height(),
                    pixels: vec![Vec3::ZERO; resolution.width() * resolution.height()],
                },
                |image: &mut RgbImage, position, (r, g, b, _a): (f32, f32, f32, f32)| {
                    let width = image.width;
                    image.pixels[position.y() * width + position.x()] = Vec3::new(r, g, b);
                },
            )
            .first_valid_layer()
            .all_attributes()
            .from_unbuffered(file)
            .map_err(|e| fail(e.to_string()))?;
        Ok(image.layer_data.channel_data.pixels)
    }

    /// Writes an 8-bit sRGB PNG of the image scaled by `2^exposure` (values clamped to [0, 1]).
    pub fn write_png(&self, path: &Path, exposure: f32) -> Result<(), ImageError> {
        let scale = exposure.exp2();
        let bytes = self
            .pixels
            .iter()
            .flat_map(|p| (*p * scale).to_array())
            .map(linear_to_srgb_byte)
            .collect();
        write_rgb8_png(path, self.width, self.height, bytes)
    }
}

/// The sRGB transfer function (IEC 61966-2-1) of a clamped linear value, as a byte.
pub fn linear_to_srgb_byte(linear: f32) -> u8 {
    let c = if linear.is_finite() {
        linear.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let encoded = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (encoded * 255.0 + 0.5) as u8
}

/// Writes 8-bit RGB bytes (`width` × `height` pixels, row by row from the top left) as a
/// PNG, atomically.
pub fn write_rgb8_png(
    path: &Path,
    width: usize,
    height: usize,
    bytes: Vec<u8>,
) -> Result<(), ImageError> {
    let png_error = |reason: String| ImageError::Png {
        path: path.to_path_buf(),
        reason,
    };
    let buffer = image::RgbImage::from_raw(width as u32, height as u32, bytes)
        .ok_or_else(|| png_error("pixel count does not match the size".into()))?;
    write_atomically(path, |temporary| {
        buffer
            .save_with_format(temporary, image::ImageFormat::Png)
            .map_err(|e| png_error(e.to_string()))
    })
}

/// Writes a false-colour PNG of per-pixel errors: log10 of the error mapped from 10^-4 (dark
/// blue) through green and yellow to 10^0 and above (red).
pub fn write_error_png(
    path: &Path,
    width: usize,
    height: usize,
    errors: &[f64],
) -> Result<(), ImageError> {
    let bytes = errors.iter().flat_map(|&e| false_colour(e)).collect();
    write_rgb8_png(path, width, height, bytes)
}

/// Maps an error to a colour on a blue–cyan–green–yellow–red ramp over 10^-4 … 10^0.
fn false_colour(error: f64) -> [u8; 3] {
    let t = if error > 0.0 && error.is_finite() {
        ((error.log10() + 4.0) / 4.0).clamp(0.0, 1.0)
    } else if error.is_nan() || error == f64::INFINITY {
        1.0
    } else {
        0.0
    };
    let stops = [
        [0.05, 0.05, 0.4],
        [0.0, 0.6, 0.9],
        [0.1, 0.8, 0.2],
        [0.95, 0.9, 0.1],
        [0.9, 0.1, 0.05],
    ];
    let x = t * (stops.len() - 1) as f64;
    let i = (x.floor() as usize).min(stops.len() - 2);
    let f = x - i as f64;
    std::array::from_fn(|c| ((stops[i][c] * (1.0 - f) + stops[i + 1][c] * f) * 255.0).round() as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trip_is_exact_and_leaves_no_temporary_files() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("image.exr");
        let image = RgbImage {
            width: 3,
            height: 2,
            pixels: (0..6)
                .map(|i| Vec3::new(i as f32, 0.5, 1e-3 * i as f32))
                .collect(),
        };
        image.write_exr(&path).unwrap();
        assert_eq!(RgbImage::read_exr(&path).unwrap(), image);
        image.write_png(&dir.path().join("image.png"), 0.0).unwrap();
        let files: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(files.len(), 2, "temporary files left behind");
    }

    /// The same image gives the same file, byte for byte: its blocks are stored in increasing
    /// order (in exr's default order, its parallel writer stored them as its threads finished).
    #[test]
    fn the_same_image_gives_the_same_file() {
        let dir = tempfile::tempdir().unwrap();
        let (width, height) = (512, 1024);
        let image = RgbImage {
            width,
            height,
            pixels: (0..width * height)
                .map(|i| Vec3::splat((i as f32 * 0.618).fract()) + Vec3::new(0.0, 1.0, 2.0))
                .collect(),
        };
        let files: Vec<Vec<u8>> = (0..4)
            .map(|i| {
                let path = dir.path().join(format!("{i}.exr"));
                image.write_exr(&path).unwrap();
                std::fs::read(path).unwrap()
            })
            .collect();
        assert!(files.iter().all(|file| *file == files[0]));
        let meta = exr::meta::MetaData::read_from_buffered(&files[0][..], false).unwrap();
        assert_eq!(meta.headers[0].line_order, LineOrder::Increasing);
    }

    #[test]
    fn an_exr_claiming_too_many_pixels_is_refused_before_allocating() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("huge.exr");
        std::fs::write(&path, vcm_scene::testing::exr_claiming(40000, 40000)).unwrap();
        let message = RgbImage::read_exr(&path).unwrap_err().to_string();
        assert!(
            message.contains("huge.exr") && message.contains("40000 × 40000 texels"),
            "{message}"
        );
    }

    #[test]
    fn failed_writes_are_errors_naming_the_file() {
        let image = RgbImage {
            width: 1,
            height: 1,
            pixels: vec![Vec3::ONE],
        };
        let path = Path::new("/nonexistent-folder/out.exr");
        let message = image.write_exr(path).unwrap_err().to_string();
        assert!(message.contains("out.exr"), "{message}");
        assert!(RgbImage::read_exr(path).is_err());
    }

    #[test]
    fn srgb_encoding_and_false_colours() {
        assert_eq!(linear_to_srgb_byte(0.0), 0);
        assert_eq!(linear_to_srgb_byte(1.0), 255);
        // sRGB 128/255 decodes to linear 0.21586; encoding it again gives 128.
        assert_eq!(linear_to_srgb_byte(0.21586), 128);
        assert_eq!(linear_to_srgb_byte(f32::NAN), 0);
        assert_ne!(false_colour(1e-4), false_colour(1.0));
        assert_eq!(false_colour(10.0), false_colour(1.0));
    }
}
