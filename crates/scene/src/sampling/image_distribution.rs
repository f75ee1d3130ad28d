//! A piecewise-constant density over the unit square, proportional to the weights of an
//! image's pixels: a row by its total weight, then a pixel of that row by its own.

use glam::{UVec2, Vec2};

use super::Distribution1D;

/// Samples points of [0, 1)² with a density constant over each of `width` × `height` cells
/// and proportional to the cell's weight (row 0 at v = 0).
#[derive(Clone, Debug)]
pub struct ImageDistribution {
    size: UVec2,
    rows: Distribution1D,
    /// Per row, its pixels' distribution (`None` for a row of zero weight).
    columns: Vec<Option<Distribution1D>>,
}

impl ImageDistribution {
    /// The distribution of `weights`, row by row (`width` × `height` of them). `None` when
    /// no weight is positive and finite or the size does not match.
    pub fn new(width: u32, height: u32, weights: &[f32]) -> Option<ImageDistribution> {
        if width == 0 || weights.len() != (width * height) as usize {
            return None;
        }
        let columns: Vec<Option<Distribution1D>> = weights
            .chunks_exact(width as usize)
            .map(Distribution1D::new)
            .collect();
        let row_weights: Vec<f32> = columns
            .iter()
            .map(|c| c.as_ref().map_or(0.0, |c| c.total() as f32))
            .collect();
        Some(ImageDistribution {
            size: UVec2::new(width, height),
            rows: Distribution1D::new(&row_weights)?,
            columns,
        })
    }

    /// A point of [0, 1)² for two uniform numbers, and its density.
    #[inline]
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (row, row_pmf, v_in_row) = self.rows.sample_remapped(u.y);
        let columns = self.columns[row]
            .as_ref()
            .expect("a row with positive weight has a column distribution");
        let (column, column_pmf, u_in_column) = columns.sample_remapped(u.x);
        let cell = Vec2::new(column as f32 + u_in_column, row as f32 + v_in_row);
        let point = (cell / self.size.as_vec2()).min(Vec2::splat(1.0 - f32::EPSILON / 2.0));
        (point, row_pmf * column_pmf * self.cells())
    }

    /// The image's width and height in cells.
    pub fn size(&self) -> UVec2 {
        self.size
    }

    /// The distribution of the rows (by their total weight).
    pub fn rows(&self) -> &Distribution1D {
        &self.rows
    }

    /// Per row, the distribution of its cells (`None` for a row without weight).
    pub fn columns(&self) -> &[Option<Distribution1D>] {
        &self.columns
    }

    /// The density at `point` of [0, 1]².
    #[inline]
    pub fn pdf(&self, point: Vec2) -> f32 {
        let cell = self.cell_of(point);
        let row_pmf = self.rows.pmf(cell.y as usize);
        let column_pmf = self.columns[cell.y as usize]
            .as_ref()
            .map_or(0.0, |c| c.pmf(cell.x as usize));
        row_pmf * column_pmf * self.cells()
    }

    /// The cell holding `point` of [0, 1]² (edges clamped in).
    #[inline]
    pub fn cell_of(&self, point: Vec2) -> UVec2 {
        image_cell(self.size, point)
    }

    fn cells(&self) -> f32 {
        (self.size.x * self.size.y) as f32
    }
}

/// The pixel of an image of `size` pixels holding `point` of [0, 1]² (edges clamped in).
#[inline]
pub fn image_cell(size: UVec2, point: Vec2) -> UVec2 {
    (point * size.as_vec2()).as_uvec2().min(size - UVec2::ONE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, Sampler};

    #[test]
    fn samples_follow_the_weights_and_report_their_density() {
        // 3 × 2 cells; one is empty, one row holds 3/4 of the weight.
        let weights = [1.0, 0.0, 2.0, 4.0, 3.0, 2.0];
        let d = ImageDistribution::new(3, 2, &weights).unwrap();
        let total: f32 = weights.iter().sum();
        let mut counts = [0u32; 6];
        let mut rng = Rng::new(4, 0);
        let n = 120_000;
        for _ in 0..n {
            let (p, pdf) = d.sample(rng.uniform2());
            assert!(p.cmpge(Vec2::ZERO).all() && p.cmplt(Vec2::ONE).all(), "{p}");
            assert_eq!(pdf, d.pdf(p));
            let cell = d.cell_of(p);
            counts[(cell.y * 3 + cell.x) as usize] += 1;
        }
        for (i, &w) in weights.iter().enumerate() {
            let expected = f64::from(w / total) * f64::from(n);
            let sigma = expected.max(1.0).sqrt();
            let got = f64::from(counts[i]);
            assert!(
                (got - expected).abs() < 5.0 * sigma,
                "cell {i}: {got} vs {expected}"
            );
            // Density = probability / cell area (1/6).
            let centre =
                Vec2::new((i % 3) as f32 + 0.5, (i / 3) as f32 + 0.5) / Vec2::new(3.0, 2.0);
            assert!((d.pdf(centre) - 6.0 * w / total).abs() < 1e-5);
        }
        assert!(ImageDistribution::new(2, 2, &[0.0; 4]).is_none());
        assert!(ImageDistribution::new(2, 2, &[1.0; 3]).is_none());
    }
}
