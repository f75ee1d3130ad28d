//! Error metrics of an image against a reference: RMSE, relMSE and MAE, over all pixels and
//! RGB channels.

use glam::Vec3;

/// Added to ref² in relMSE's denominator so black reference pixels do not dominate.
pub const RELMSE_EPSILON: f64 = 0.01;

/// Errors of an image against a reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorMetrics {
    /// Root mean squared error: √(mean (x − ref)²).
    pub rmse: f64,
    /// Relative mean squared error: mean (x − ref)² / (ref² + 0.01).
    pub relmse: f64,
    /// Mean absolute error: mean |x − ref|.
    pub mae: f64,
}

/// Compares `image` with `reference` (same pixel order). `None` when their sizes differ or
/// they are empty. A non-finite channel in either makes the metrics NaN or infinite: check
/// both with [`non_finite_pixels`] first.
pub fn compare(image: &[Vec3], reference: &[Vec3]) -> Option<ErrorMetrics> {
    if image.len() != reference.len() || image.is_empty() {
        return None;
    }
    let (mut squared, mut relative, mut absolute) = (0.0, 0.0, 0.0);
    for (x, r) in image.iter().zip(reference) {
        for c in 0..3 {
            let (x, r) = (f64::from(x[c]), f64::from(r[c]));
            let d = x - r;
            squared += d * d;
            relative += d * d / (r * r + RELMSE_EPSILON);
            absolute += d.abs();
        }
    }
    let n = (3 * image.len()) as f64;
    Some(ErrorMetrics {
        rmse: (squared / n).sqrt(),
        relmse: relative / n,
        mae: absolute / n,
    })
}

/// The pixels of `pixels` with a NaN or infinite channel.
pub fn non_finite_pixels(pixels: &[Vec3]) -> usize {
    pixels.iter().filter(|p| !p.is_finite()).count()
}

/// Per-pixel relative squared error (mean over channels), for false-colour error images.
pub fn relative_error_per_pixel(image: &[Vec3], reference: &[Vec3]) -> Vec<f64> {
    image
        .iter()
        .zip(reference)
        .map(|(x, r)| {
            (0..3)
                .map(|c| {
                    let (x, r) = (f64::from(x[c]), f64::from(r[c]));
                    (x - r) * (x - r) / (r * r + RELMSE_EPSILON)
                })
                .sum::<f64>()
                / 3.0
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_match_hand_computed_values() {
        let reference = [Vec3::splat(1.0), Vec3::ZERO];
        let image = [Vec3::splat(2.0), Vec3::new(0.1, 0.0, 0.0)];
        let m = compare(&image, &reference).unwrap();
        // Squared errors: 1, 1, 1, 0.01, 0, 0 → mean 3.01 / 6.
        assert!((m.rmse - (3.01f64 / 6.0).sqrt()).abs() < 1e-6);
        // Relative: 1/1.01 three times, 0.01/0.01 once.
        assert!((m.relmse - (3.0 / 1.01 + 1.0) / 6.0).abs() < 1e-6);
        assert!((m.mae - 3.1 / 6.0).abs() < 1e-6);
        assert_eq!(compare(&image, &reference[..1]), None);
        let zero = compare(&reference, &reference).unwrap();
        assert_eq!((zero.rmse, zero.relmse, zero.mae), (0.0, 0.0, 0.0));
        let per_pixel = relative_error_per_pixel(&image, &reference);
        assert!((per_pixel[1] - 1.0 / 3.0).abs() < 1e-6);
    }

    #[test]
    fn non_finite_pixels_are_counted_once_each() {
        let pixels = [
            Vec3::ONE,
            Vec3::new(f32::NAN, 0.0, f32::NAN),
            Vec3::new(0.0, f32::INFINITY, 0.0),
            Vec3::splat(f32::MAX),
        ];
        assert_eq!(non_finite_pixels(&pixels), 2);
        assert_eq!(non_finite_pixels(&pixels[3..]), 0);
    }
}
