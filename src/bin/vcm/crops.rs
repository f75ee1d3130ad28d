//! Crops for an experiment's report: one square of every run's image and of its false-colour
//! error, the same square for all runs of a scene, enlarged so that its noise can be seen
//! side by side.

use anyhow::bail;

/// Side of a crop once enlarged, at least, in pixels.
const SHOWN_SIDE: usize = 128;

/// A square of an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crop {
    /// Column and row of the top left pixel.
    pub x: usize,
    pub y: usize,
    /// Side in pixels.
    pub size: usize,
}

impl Crop {
    /// `[x, y, size]` from an experiment file, if it lies inside a `width` × `height` image.
    pub fn inside(
        corner_and_side: [usize; 3],
        width: usize,
        height: usize,
    ) -> anyhow::Result<Crop> {
        let [x, y, size] = corner_and_side;
        if size == 0 || x.saturating_add(size) > width || y.saturating_add(size) > height {
            bail!("the crop [{x}, {y}, {size}] does not lie inside the {width}×{height} image");
        }
        Ok(Crop { x, y, size })
    }

    /// The square of a quarter of the image's shorter side (at least 8 pixels, at most the
    /// side) over which `errors` (one per pixel, row by row) sum to the most, its corner
    /// tried every eighth of the side; the first in row order where two sum alike. A
    /// non-finite error counts as 10⁶.
    pub fn worst(errors: &[f64], width: usize, height: usize) -> Crop {
        let size = (width.min(height) / 4).max(8).min(width.min(height));
        let sums = SummedArea::new(errors, width, height);
        let step = (size / 8).max(1);
        let mut best = (f64::NEG_INFINITY, Crop { x: 0, y: 0, size });
        for y in (0..=height - size).step_by(step) {
            for x in (0..=width - size).step_by(step) {
                let sum = sums.square(x, y, size);
                if sum > best.0 {
                    best = (sum, Crop { x, y, size });
                }
            }
        }
        best.1
    }

    /// How many times each pixel is repeated per axis to show the crop: its side becomes
    /// at least `SHOWN_SIDE`.
    pub fn scale(&self) -> usize {
        SHOWN_SIDE.div_ceil(self.size).max(1)
    }

    /// The crop's values out of a row-major image `width` wide, each repeated `scale()` times
    /// per axis: a square `size · scale()` on a side.
    pub fn cut<T: Copy>(&self, values: &[T], width: usize) -> Vec<T> {
        let scale = self.scale();
        let side = self.size * scale;
        let mut out = Vec::with_capacity(side * side);
        for row in 0..side {
            let y = self.y + row / scale;
            for column in 0..side {
                out.push(values[y * width + self.x + column / scale]);
            }
        }
        out
    }
}

/// Sums over rectangles of a row-major image in constant time: `table[y][x]` is the sum of
/// the values above and left of (x, y).
struct SummedArea {
    table: Vec<f64>,
    stride: usize,
}

impl SummedArea {
    fn new(values: &[f64], width: usize, height: usize) -> SummedArea {
        let stride = width + 1;
        let mut table = vec![0.0; stride * (height + 1)];
        for y in 0..height {
            let mut row = 0.0;
            for x in 0..width {
                let value = values[y * width + x];
                row += if value.is_finite() { value } else { 1e6 };
                // S(x+1, y+1) = S(x+1, y) + Σ of row y up to x.
                table[(y + 1) * stride + x + 1] = table[y * stride + x + 1] + row;
            }
        }
        SummedArea { table, stride }
    }

    /// The sum over the square with top left corner (x, y) and side `size`:
    /// S(x+s, y+s) − S(x, y+s) − S(x+s, y) + S(x, y).
    fn square(&self, x: usize, y: usize, size: usize) -> f64 {
        let at = |x: usize, y: usize| self.table[y * self.stride + x];
        at(x + size, y + size) - at(x, y + size) - at(x + size, y) + at(x, y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_worst_square_is_where_the_errors_are() {
        let (width, height) = (64, 48);
        let mut errors = vec![0.01; width * height];
        // A patch of large errors around (40, 30).
        for y in 28..34 {
            for x in 38..44 {
                errors[y * width + x] = 1.0;
            }
        }
        let crop = Crop::worst(&errors, width, height);
        assert_eq!(crop.size, 12);
        assert!(crop.x <= 38 && crop.x + crop.size >= 44, "{crop:?}");
        assert!(crop.y <= 28 && crop.y + crop.size >= 34, "{crop:?}");
        // Non-finite errors weigh most.
        errors[5 * width + 5] = f64::NAN;
        let crop = Crop::worst(&errors, width, height);
        assert!(crop.x <= 5 && crop.y <= 5, "{crop:?}");
    }

    #[test]
    fn a_small_image_is_cropped_whole_and_crops_are_enlarged() {
        let crop = Crop::worst(&[0.0; 6 * 5], 6, 5);
        assert_eq!(
            crop,
            Crop {
                x: 0,
                y: 0,
                size: 5
            }
        );
        assert_eq!(crop.scale(), 26);
        let values: Vec<usize> = (0..16).collect();
        let crop = Crop::inside([1, 2, 2], 4, 4).unwrap();
        let cut = crop.cut(&values, 4);
        let side = 2 * crop.scale();
        assert_eq!(cut.len(), side * side);
        assert_eq!(cut[0], 9);
        assert_eq!(cut[side - 1], 10);
        assert_eq!(cut[side * side - 1], 14);
    }

    #[test]
    fn a_crop_outside_the_image_is_refused() {
        assert!(Crop::inside([60, 0, 8], 64, 48).is_err());
        assert!(Crop::inside([0, 0, 0], 64, 48).is_err());
        assert!(Crop::inside([usize::MAX, 0, 8], 64, 48).is_err());
        assert!(Crop::inside([56, 40, 8], 64, 48).is_ok());
    }
}
