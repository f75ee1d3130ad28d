//! `vcm compare`: error metrics between two EXR images and a false-colour error image.

use std::path::PathBuf;

use anyhow::bail;
use vcm::image_io::{RgbImage, write_error_png};
use vcm::metrics::{compare, relative_error_per_pixel};

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
