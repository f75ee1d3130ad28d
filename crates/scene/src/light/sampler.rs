//! Power-proportional light selection and the triangle → area light lookup.

use super::Light;
use crate::sampling::Distribution1D;
use crate::texture::Texture;

/// Chooses lights in proportion to their power and finds the light behind an emissive
/// triangle, and the environment.
#[derive(Clone, Debug)]
pub struct LightSampler {
    distribution: Option<Distribution1D>,
    light_of_triangle: Vec<u32>,
    environment: Option<usize>,
}

/// Marks a triangle that is not an area light.
const NOT_A_LIGHT: u32 = u32::MAX;

impl LightSampler {
    /// Builds the selection distribution over `lights` for a mesh of `triangle_count` triangles.
    pub fn new(lights: &[Light], textures: &[Texture], triangle_count: usize) -> Self {
        let powers: Vec<f32> = lights.iter().map(|l| l.power(textures)).collect();
        let mut light_of_triangle = vec![NOT_A_LIGHT; triangle_count];
        for (i, light) in lights.iter().enumerate() {
            if let Light::Area(area) = light {
                light_of_triangle[area.triangle as usize] = i as u32;
            }
        }
        LightSampler {
            distribution: Distribution1D::new(&powers),
            light_of_triangle,
            environment: lights
                .iter()
                .position(|l| matches!(l, Light::Environment(_))),
        }
    }

    /// Picks a light with probability proportional to power: (light index, probability).
    /// `None` when the scene has no light with positive power.
    #[inline]
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        self.distribution.as_ref().map(|d| d.sample(u))
    }

    /// Per light, the smallest number in [0, 1) that [`sample`](Self::sample) maps to it or
    /// a later light (see [`Distribution1D::first_numbers`]); empty without lights to pick.
    pub fn first_numbers(&self) -> Vec<f32> {
        self.distribution
            .as_ref()
            .map_or_else(Vec::new, Distribution1D::first_numbers)
    }

    /// Probability of picking light `index`.
    #[inline]
    pub fn pmf(&self, index: usize) -> f32 {
        self.distribution.as_ref().map_or(0.0, |d| d.pmf(index))
    }

    /// The environment light (the first, if there are several), if any.
    #[inline]
    pub fn environment(&self) -> Option<usize> {
        self.environment
    }

    /// The area light behind triangle `triangle`, if it emits.
    #[inline]
    pub fn light_of_triangle(&self, triangle: u32) -> Option<usize> {
        let light = *self.light_of_triangle.get(triangle as usize)?;
        (light != NOT_A_LIGHT).then_some(light as usize)
    }
}
