//! The first iteration's merge radius r₀: a fraction of the scene's size, or a number of
//! pixel footprints at the surfaces the camera sees.
//!
//! A fraction of the bounding sphere knows nothing of the image: the same fraction is a
//! tenth of a pixel in a close-up and many pixels where the camera sees a small part of a
//! large scene, and it stays the same when the resolution doubles. Merging's bias is a blur
//! of about r₀ at the merging vertex, and its variance falls as r₀ grows, so the footprint of
//! a pixel is the natural unit (SeeSharp sizes its radii so): `Pixels(k)` makes r₀ k times
//! the median footprint radius of one pixel at the first surfaces of a grid of camera rays.
//! It is the default, at [`DEFAULT_RADIUS_PIXELS`]: on the scenes in `scenes/` (whose bounding
//! sphere has radius √3) that is the old default fraction at 512 pixels, and it stays two
//! pixels at any resolution and any scale of scene.

use std::fmt;
use std::str::FromStr;

use glam::Vec2;
use vcm_scene::{Projection, Scene};
use vcm_traversal::{HitBatch, RayBatch, Traversal};

/// Initial merge radius as a fraction of the scene's bounding-sphere radius where the unit
/// is the scene's and no number is given, and where no camera ray measures a footprint.
pub const DEFAULT_RADIUS_FRACTION: f32 = 0.003;

/// Default initial merge radius, in pixel footprints.
pub const DEFAULT_RADIUS_PIXELS: f32 = 2.0;

/// Camera rays per image side that measure the pixel footprint (a grid of this many
/// squared rays through the image).
const FOOTPRINT_GRID: u32 = 32;

/// How the first iteration's merge radius r₀ is chosen; later iterations shrink it by
/// `alpha`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MergeRadius {
    /// This fraction of the scene's bounding-sphere radius (written as a plain number,
    /// `0.003`).
    SceneFraction(f32),
    /// This many pixel footprints: the median, over a grid of camera rays, of the radius of
    /// the disk one pixel covers on a surface facing the ray at its first hit (written with
    /// a unit, `2px`).
    Pixels(f32),
}

impl Default for MergeRadius {
    fn default() -> MergeRadius {
        MergeRadius::Pixels(DEFAULT_RADIUS_PIXELS)
    }
}

impl fmt::Display for MergeRadius {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MergeRadius::SceneFraction(fraction) => write!(f, "{fraction}"),
            MergeRadius::Pixels(pixels) => write!(f, "{pixels}px"),
        }
    }
}

impl FromStr for MergeRadius {
    type Err = String;

    /// `0.003` (a fraction of the scene's radius) or `2px` (pixel footprints); the number
    /// must be positive and finite.
    fn from_str(text: &str) -> Result<MergeRadius, String> {
        let (number, pixels) = match text.trim().strip_suffix("px") {
            Some(number) => (number, true),
            None => (text.trim(), false),
        };
        let value: f32 = number.trim().parse().map_err(|_| {
            format!(
                "'{text}' is not a merge radius: a fraction of the scene's radius (0.003) or \
                 pixel footprints (2px)"
            )
        })?;
        let radius = if pixels {
            MergeRadius::Pixels(value)
        } else {
            MergeRadius::SceneFraction(value)
        };
        radius.validated()
    }
}

impl MergeRadius {
    /// The radius if its number is positive and finite, else why not.
    pub fn validated(self) -> Result<MergeRadius, String> {
        let (MergeRadius::SceneFraction(value) | MergeRadius::Pixels(value)) = self;
        if value.is_finite() && value > 0.0 {
            Ok(self)
        } else {
            Err(format!(
                "the merge radius must be a positive number (asked for {self})"
            ))
        }
    }

    /// r₀ in world units for `scene` seen through `projection` onto a `size` image (pixels),
    /// and how it was found (for the integrator's decisions). A footprint that no camera
    /// ray measures (they all leave the scene) falls back to the default fraction of the
    /// scene's radius.
    pub fn initial(
        self,
        scene: &Scene,
        traversal: &dyn Traversal,
        (projection, size): (&Projection, Vec2),
    ) -> (f32, String) {
        let scene_radius = scene.features.bounds.radius();
        let fraction = |fraction: f32| {
            let why = format!("{fraction} of the scene's radius {scene_radius}");
            (fraction * scene_radius, why)
        };
        match self {
            MergeRadius::SceneFraction(f) => fraction(f),
            MergeRadius::Pixels(pixels) => {
                match pixel_footprint(scene, traversal, (projection, size)) {
                    Some(footprint) => (
                        pixels * footprint,
                        format!(
                            "{pixels} × a pixel's footprint radius {footprint} (the median at \
                             the first hits of {FOOTPRINT_GRID}² camera rays)"
                        ),
                    ),
                    None => {
                        let (r, why) = fraction(DEFAULT_RADIUS_FRACTION);
                        (r, format!("no camera ray hits the scene: {why}"))
                    }
                }
            }
        }
    }
}

/// The merge radius of iteration `iteration` (from 0) of a render whose first is `r0` and
/// whose radius shrinks with exponent `alpha`: r₀ · (iteration + 1)^((α − 1) / 2).
pub fn merge_radius(r0: f32, alpha: f32, iteration: u64) -> f32 {
    let exponent = 0.5 * (alpha - 1.0);
    r0 * ((iteration as f32) + 1.0).powf(exponent)
}

/// The median radius of a pixel's footprint at the first hits of a grid of camera rays
/// through the centres of pixels of a `size` image, or `None` when no ray hits. A pixel θ
/// off the axis spans the solid angle Ω = A cos³θ (A: its area on the image plane at unit
/// distance); at distance t it covers t² Ω of a surface facing the ray, a disk of radius
/// t √(Ω / π).
fn pixel_footprint(
    scene: &Scene,
    traversal: &dyn Traversal,
    (projection, size): (&Projection, Vec2),
) -> Option<f32> {
    let camera = &scene.camera;
    let cells = Vec2::splat(FOOTPRINT_GRID as f32);
    let mut rays = RayBatch::with_capacity((FOOTPRINT_GRID * FOOTPRINT_GRID) as usize);
    for y in 0..FOOTPRINT_GRID {
        for x in 0..FOOTPRINT_GRID {
            // The centre of the pixel under the centre of grid cell (x, y).
            let cell = (Vec2::new(x as f32, y as f32) + 0.5) / cells;
            let raster = (cell * size).floor() + 0.5;
            rays.push(
                camera.position,
                projection.direction(raster),
                0.0,
                f32::INFINITY,
            );
        }
    }
    let mut hits = HitBatch::with_capacity(rays.len());
    traversal.intersect(&rays, &mut hits);
    let pixel_area = projection.pixel_area();
    let mut footprints: Vec<f32> = (0..rays.len())
        .filter(|&i| hits.is_hit(i))
        .map(|i| {
            let cos = camera.forward.dot(rays.direction(i));
            // r = t √(A cos³θ / π)
            hits.t[i] * (pixel_area * cos * cos * cos / std::f32::consts::PI).sqrt()
        })
        .filter(|r| r.is_finite() && *r > 0.0)
        .collect();
    if footprints.is_empty() {
        return None;
    }
    let middle = footprints.len() / 2;
    Some(*footprints.select_nth_unstable_by(middle, f32::total_cmp).1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radii_read_and_write_the_same_text() {
        for radius in [MergeRadius::SceneFraction(0.003), MergeRadius::Pixels(2.5)] {
            assert_eq!(radius.to_string().parse::<MergeRadius>(), Ok(radius));
        }
        assert_eq!("2px".parse(), Ok(MergeRadius::Pixels(2.0)));
        assert_eq!(" 1.5 px".parse(), Ok(MergeRadius::Pixels(1.5)));
        assert_eq!("0.01".parse(), Ok(MergeRadius::SceneFraction(0.01)));
    }

    #[test]
    fn bad_radii_are_refused_with_the_text() {
        for text in ["", "px", "two", "2 pixels", "0", "-1px", "inf", "NaNpx"] {
            let error = text.parse::<MergeRadius>().unwrap_err();
            assert!(error.contains("merge radius"), "{text}: {error}");
        }
    }
}
