//! An equirectangular image of the sky's radiance, looked up by direction and sampled in
//! proportion to its brightness over the sphere.
//!
//! Mapping (glTF axes, +Y up): a direction at polar angle θ from +Y and azimuth φ =
//! atan2(z, x) sits at u = ½ + φ / 2π, v = θ / π, with v = 0 the image's top row. The
//! image's centre looks along +X, its left quarter along −Z and its right quarter along +Z.

use std::f32::consts::PI;

use glam::{UVec2, Vec2, Vec3};

use super::channel_mean;
use crate::sampling::{ImageDistribution, image_cell};

/// Radiance from every direction as an equirectangular image (linear RGB), piecewise
/// constant over its pixels.
#[derive(Debug)]
pub struct EnvironmentMap {
    size: UVec2,
    texels: Vec<Vec3>,
    /// Pixels in proportion to channel mean × the solid angle they cover (`None`: all black).
    distribution: Option<ImageDistribution>,
    /// Mean radiance over the sphere.
    mean: Vec3,
}

impl EnvironmentMap {
    /// The map of `texels`, row by row from the top; `Err` for a size that does not match
    /// or a texel that is negative or not finite.
    pub fn new(width: u32, height: u32, texels: Vec<Vec3>) -> Result<EnvironmentMap, String> {
        if width == 0 || height == 0 || texels.len() != (width as usize) * (height as usize) {
            return Err(format!(
                "{} texels for a {width} × {height} image",
                texels.len()
            ));
        }
        if let Some(i) = texels
            .iter()
            .position(|t| !t.is_finite() || t.min_element() < 0.0)
        {
            let (x, y) = (i % width as usize, i / width as usize);
            return Err(format!("texel ({x}, {y}) is {}", texels[i]));
        }
        // Each pixel of row y covers the solid angle (2π / W)(cos θ_y − cos θ_y+1).
        let row_solid_angle = |y: usize| {
            let theta = |row: usize| row as f32 / height as f32 * PI;
            2.0 * PI / width as f32 * (theta(y).cos() - theta(y + 1).cos())
        };
        let solid_angles = (0..texels.len()).map(|i| row_solid_angle(i / width as usize));
        let weights: Vec<f32> = texels
            .iter()
            .zip(solid_angles.clone())
            .map(|(t, omega)| channel_mean(*t) * omega)
            .collect();
        let mean = texels
            .iter()
            .zip(solid_angles)
            .map(|(t, omega)| *t * omega)
            .sum::<Vec3>()
            / (4.0 * PI);
        Ok(EnvironmentMap {
            size: UVec2::new(width, height),
            distribution: ImageDistribution::new(width, height, &weights),
            texels,
            mean,
        })
    }

    /// Radiance arriving from the unit `direction` (of the pixel it points at).
    #[inline]
    pub fn radiance(&self, direction: Vec3) -> Vec3 {
        let cell = image_cell(self.size, direction_to_uv(direction));
        self.texels[(cell.y * self.size.x + cell.x) as usize]
    }

    /// The image's width and height in texels.
    pub fn size(&self) -> UVec2 {
        self.size
    }

    /// The texels, row by row from the top (linear RGB radiance factors).
    pub fn texels(&self) -> &[Vec3] {
        &self.texels
    }

    /// The distribution [`sample`](Self::sample) draws texels from (`None` for a black map).
    pub fn distribution(&self) -> Option<&ImageDistribution> {
        self.distribution.as_ref()
    }

    /// Mean radiance over the sphere.
    pub fn mean(&self) -> Vec3 {
        self.mean
    }

    /// A direction toward the sky for two uniform numbers, with its solid-angle pdf; `None`
    /// for a black map.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        let (uv, pdf_uv) = self.distribution.as_ref()?.sample(u);
        let (direction, sin_theta) = uv_to_direction(uv);
        (sin_theta > 0.0).then(|| (direction, solid_angle_pdf(pdf_uv, sin_theta)))
    }

    /// Solid-angle pdf with which [`sample`](Self::sample) picks the unit `direction`.
    #[inline]
    pub fn pdf(&self, direction: Vec3) -> f32 {
        let Some(distribution) = &self.distribution else {
            return 0.0;
        };
        let sin_theta = direction.x.hypot(direction.z);
        if sin_theta <= 0.0 {
            return 0.0;
        }
        solid_angle_pdf(distribution.pdf(direction_to_uv(direction)), sin_theta)
    }
}

/// A density over image coordinates as a density over directions at polar angle θ: the
/// map's Jacobian is 2π² sin θ.
fn solid_angle_pdf(pdf_uv: f32, sin_theta: f32) -> f32 {
    pdf_uv / (2.0 * PI * PI * sin_theta)
}

/// Image coordinates of the unit `direction` (see the module documentation).
fn direction_to_uv(direction: Vec3) -> Vec2 {
    let u = 0.5 + direction.z.atan2(direction.x) / (2.0 * PI);
    let v = direction.y.clamp(-1.0, 1.0).acos() / PI;
    Vec2::new(u, v)
}

/// The direction at image coordinates `uv`, and the sine of its polar angle.
fn uv_to_direction(uv: Vec2) -> (Vec3, f32) {
    let phi = (uv.x - 0.5) * 2.0 * PI;
    let (sin_theta, cos_theta) = (uv.y * PI).sin_cos();
    let (sin_phi, cos_phi) = phi.sin_cos();
    (
        Vec3::new(sin_theta * cos_phi, cos_theta, sin_theta * sin_phi),
        sin_theta,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, Sampler};

    /// A 16 × 8 map, dark but for a bright band and one very bright pixel.
    fn sky() -> EnvironmentMap {
        let (w, h) = (16, 8);
        let texels = (0..w * h)
            .map(|i| match (i % w, i / w) {
                (5, 2) => Vec3::new(40.0, 30.0, 20.0),
                (_, 3) => Vec3::new(1.0, 2.0, 3.0),
                _ => Vec3::splat(0.1),
            })
            .collect();
        EnvironmentMap::new(w, h, texels).unwrap()
    }

    #[test]
    fn the_axes_map_as_documented() {
        let uv = |d: Vec3| direction_to_uv(d.normalize());
        assert!((uv(Vec3::X) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!((uv(-Vec3::Z) - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!((uv(Vec3::Z) - Vec2::new(0.75, 0.5)).length() < 1e-6);
        assert!(uv(Vec3::Y).y < 1e-6 && uv(-Vec3::Y).y > 1.0 - 1e-6);
        for uv in [
            Vec2::new(0.1, 0.3),
            Vec2::new(0.8, 0.9),
            Vec2::new(0.5, 0.02),
        ] {
            let (d, _) = uv_to_direction(uv);
            assert!((direction_to_uv(d) - uv).length() < 1e-5, "{uv}");
        }
    }

    /// Sampling integrates the map: the mean of L(ω) / pdf(ω) is 4π × its mean radiance,
    /// and every sample's pdf is the one `pdf` gives for its direction.
    #[test]
    fn sampling_integrates_the_map_with_consistent_pdfs() {
        let map = sky();
        let mut rng = Rng::new(8, 0);
        let n = 100_000;
        let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let (d, pdf) = map.sample(rng.uniform2()).unwrap();
            assert!((d.length() - 1.0).abs() < 1e-5);
            let rel = (map.pdf(d) - pdf).abs() / pdf;
            assert!(rel < 1e-3, "{d}: pdf {pdf} vs {}", map.pdf(d));
            let x = f64::from(channel_mean(map.radiance(d)) / pdf);
            sum += x;
            sum_sq += x * x;
        }
        let mean = sum / f64::from(n);
        let se = ((sum_sq / f64::from(n) - mean * mean) / f64::from(n)).sqrt();
        let expected = 4.0 * std::f64::consts::PI * f64::from(channel_mean(map.mean()));
        // The density is uniform in (u, v) within a pixel, not in solid angle, so L / pdf
        // varies a little within a pixel: a real spread, measured by `se`.
        assert!(
            (mean - expected).abs() < 4.0 * se + 1e-9,
            "{mean} ± {se} vs {expected}"
        );
    }

    #[test]
    fn bad_texels_are_errors() {
        assert!(EnvironmentMap::new(2, 1, vec![Vec3::ONE]).is_err());
        let nan = EnvironmentMap::new(2, 1, vec![Vec3::ONE, Vec3::NAN]).unwrap_err();
        assert!(nan.contains("(1, 0)"), "{nan}");
        assert!(EnvironmentMap::new(1, 1, vec![-Vec3::ONE]).is_err());
        let black = EnvironmentMap::new(1, 1, vec![Vec3::ZERO]).unwrap();
        assert!(black.sample(Vec2::splat(0.5)).is_none() && black.pdf(Vec3::X) == 0.0);
    }
}
