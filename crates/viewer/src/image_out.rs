//! The displayed image: tone mapping of the running mean for the screen, and saving it as a
//! linear EXR plus a tone-mapped PNG (both written through a temporary file and renamed).

use std::path::{Path, PathBuf};

use eframe::egui::ColorImage;
use glam::Vec3;
use vcm::image_io::{ImageError, RgbImage, linear_to_srgb_byte};

/// 8-bit sRGB of `mean` (a `width` × `height` image) scaled by 2^`exposure`: the same mapping
/// as the PNGs of `vcm render`.
pub fn tone_map((width, height): (u32, u32), mean: &[Vec3], exposure: f32) -> ColorImage {
    let scale = exposure.exp2();
    let bytes: Vec<u8> = mean
        .iter()
        .flat_map(|p| (*p * scale).to_array())
        .map(linear_to_srgb_byte)
        .collect();
    ColorImage::from_rgb([width as usize, height as usize], &bytes)
}

/// Writes `mean` as `<path>.exr` (linear radiance) and `<path>.png` (tone mapped with
/// `exposure`), whatever extension `path` has; returns the two paths.
pub fn save(
    path: &Path,
    (width, height): (u32, u32),
    mean: &[Vec3],
    exposure: f32,
) -> Result<[PathBuf; 2], ImageError> {
    let image = RgbImage {
        width: width as usize,
        height: height as usize,
        pixels: mean.to_vec(),
    };
    let exr = path.with_extension("exr");
    let png = path.with_extension("png");
    image.write_exr(&exr)?;
    image.write_png(&png, exposure)?;
    Ok([exr, png])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mean() -> Vec<Vec3> {
        vec![
            Vec3::new(0.0, 0.25, 1.0),
            Vec3::new(4.0, f32::NAN, 0.5),
            Vec3::splat(0.125),
            Vec3::new(0.01, 0.02, 0.03),
        ]
    }

    #[test]
    fn tone_mapping_matches_the_saved_png() {
        let dir = tempfile::tempdir().unwrap();
        let [exr, png] = save(&dir.path().join("shot.png"), (2, 2), &mean(), 1.0).unwrap();
        assert_eq!(exr, dir.path().join("shot.exr"));
        let shown = tone_map((2, 2), &mean(), 1.0);
        let saved = image::open(&png).unwrap().to_rgb8();
        assert_eq!(saved.dimensions(), (2, 2));
        for (shown, saved) in shown.pixels.iter().zip(saved.pixels()) {
            assert_eq!([shown.r(), shown.g(), shown.b()], saved.0);
        }
        // 0.25 · 2¹ = 0.5 linear is 188 in sRGB; 4 · 2 clamps to white; NaN is black.
        assert_eq!(shown.pixels[0].g(), 188);
        assert_eq!(shown.pixels[1].r(), 255);
        assert_eq!(shown.pixels[1].g(), 0);
    }

    #[test]
    fn the_exr_holds_the_linear_mean() {
        let dir = tempfile::tempdir().unwrap();
        let mean = vec![Vec3::new(0.5, 2.0, 1e3), Vec3::ZERO];
        let [exr, _] = save(&dir.path().join("shot"), (2, 1), &mean, 0.0).unwrap();
        let read = RgbImage::read_exr(&exr).unwrap();
        assert_eq!((read.width, read.height), (2, 1));
        assert_eq!(read.pixels, mean);
    }

    #[test]
    fn an_unwritable_folder_is_an_error_naming_the_file() {
        let missing = Path::new("/nonexistent-folder/shot.exr");
        let error = save(missing, (1, 1), &[Vec3::ONE], 0.0).unwrap_err();
        assert!(
            error.to_string().contains("/nonexistent-folder/shot.exr"),
            "{error}"
        );
    }
}
