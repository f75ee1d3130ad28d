//! `vcm compare`: error metrics between two EXR images and a false-colour error image.

use std::path::{Path, PathBuf};

use anyhow::bail;
use glam::Vec3;
use vcm::image_io::{RgbImage, write_error_png};
use vcm::metrics::{compare, non_finite_pixels, relative_error_per_pixel};

use crate::render::check_outputs;

/// Arguments of `vcm compare`.
#[derive(clap::Args)]
pub struct CompareArgs {
    /// The image to judge (EXR).
    image: PathBuf,
    /// The reference (EXR).
    reference: PathBuf,
    /// Write a false-colour PNG of the per-pixel relative squared error.
    #[arg(long)]
    diff: Option<PathBuf>,
}

/// Fails when `pixels`, read from `path`, hold a NaN or infinite channel: metrics over them
/// would be NaN or infinite, whatever the other pixels.
pub fn check_finite(path: &Path, pixels: &[Vec3]) -> anyhow::Result<()> {
    let count = non_finite_pixels(pixels);
    if count > 0 {
        bail!(
            "{}: {count} of {} pixels are not finite (NaN or infinite); the error metrics \
             need finite pixels",
            path.display(),
            pixels.len()
        );
    }
    Ok(())
}

/// Prints RMSE, relMSE and MAE of `image` against `reference`.
pub fn run(args: &CompareArgs) -> anyhow::Result<()> {
    if let Some(diff) = &args.diff {
        let outputs = [("the error image", diff.clone())];
        check_outputs(&outputs, &[&args.image, &args.reference])?;
    }
    let image = RgbImage::read_exr(&args.image)?;
    let reference = RgbImage::read_exr(&args.reference)?;
    if (image.width, image.height) != (reference.width, reference.height) {
        bail!(
            "{} is {}×{} but {} is {}×{}",
            args.image.display(),
            image.width,
            image.height,
            args.reference.display(),
            reference.width,
            reference.height
        );
    }
    for (path, pixels) in [(&args.image, &image), (&args.reference, &reference)] {
        check_finite(path, &pixels.pixels)?;
    }
    let m = compare(&image.pixels, &reference.pixels)
        .ok_or_else(|| anyhow::anyhow!("{}: the image is empty", args.image.display()))?;
    say!(
        "rmse {:.6e}\nrelmse {:.6e}\nmae {:.6e}",
        m.rmse,
        m.relmse,
        m.mae
    );
    if let Some(diff) = &args.diff {
        let errors = relative_error_per_pixel(&image.pixels, &reference.pixels);
        write_error_png(diff, image.width, image.height, &errors)?;
        say!("wrote {}", diff.display());
    }
    Ok(())
}
