//! `SceneFeatures`: what a scene contains, so integrators and pipelines can leave out the rest.

use std::fmt;

use glam::Vec3;

use crate::light::Light;
use crate::material::{AlphaMode, Material};
use crate::mesh::{Bounds, Mesh};
use crate::texture::{Texture, TextureRef};

/// BSDF classes present in the scene's materials (only materials some triangle uses count).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MaterialClasses {
    /// Some material has a Lambertian diffuse lobe.
    pub diffuse: bool,
    /// Some material has a glossy (rough microfacet) lobe.
    pub glossy: bool,
    /// Some material has a delta (perfectly specular) lobe: mirrors, smooth glass or coats.
    pub specular: bool,
    /// Some glossy lobe is near-specular: roughness below [`NEAR_SPECULAR_ROUGHNESS`].
    pub near_specular: bool,
    /// Some material transmits light (transmission > 0).
    pub transmission: bool,
}

/// Glossy lobes with a smaller roughness (GGX α = roughness² below 0.04) are near-specular:
/// connections sample paths through them with high variance, so merging is kept for them.
pub const NEAR_SPECULAR_ROUGHNESS: f32 = 0.2;

impl MaterialClasses {
    /// Some surface has a diffuse or glossy lobe (one that connections can sample).
    pub fn non_specular(&self) -> bool {
        self.diffuse || self.glossy
    }

    /// Some surface is specular or near-specular: paths through it may have no vertex that
    /// connections sample well, which only merging finds (specular–diffuse–specular chains).
    pub fn specular_or_near(&self) -> bool {
        self.specular || self.near_specular
    }
}

/// Counts of each light type.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LightCounts {
    /// Emissive triangles.
    pub area: usize,
    /// Point lights.
    pub point: usize,
    /// Spot lights.
    pub spot: usize,
    /// Directional lights.
    pub directional: usize,
    /// Environment lights (0 or 1).
    pub environment: usize,
}

impl LightCounts {
    /// True when every light is a delta light (no path can hit a light).
    pub fn only_delta(&self) -> bool {
        self.area == 0 && self.environment == 0 && (self.point + self.spot + self.directional) > 0
    }
}

/// What a scene contains and needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneFeatures {
    /// Number of triangles.
    pub triangles: usize,
    /// Bounding box of the geometry.
    pub bounds: Bounds,
    /// BSDF classes in use.
    pub materials: MaterialClasses,
    /// Light counts.
    pub lights: LightCounts,
    /// Some used material samples a texture.
    pub textures: bool,
    /// Some used material is alpha-masked (cut-out).
    pub alpha_masks: bool,
    /// Some used material has a normal map.
    pub normal_maps: bool,
    /// Some vertex has a color other than white (glTF `COLOR_0`).
    pub vertex_colors: bool,
    /// Some used material bounds a solid that absorbs ([`Material::absorption`]).
    pub absorbing_volumes: bool,
}

/// The range of a texture channel's values (0..=1), or the full range without a texture.
fn channel_range(textures: &[Texture], texture: Option<TextureRef>, channel: usize) -> (f32, f32) {
    let Some(t) = texture else { return (1.0, 1.0) };
    let tex = &textures[t.index];
    let mut range = (f32::INFINITY, f32::NEG_INFINITY);
    for y in 0..tex.height() {
        for x in 0..tex.width() {
            let v = tex.texel(x, y)[channel];
            range = (range.0.min(v), range.1.max(v));
        }
    }
    range
}

impl MaterialClasses {
    fn add(&mut self, m: &Material, textures: &[Texture]) {
        let (metal_lo, metal_hi) = channel_range(textures, m.metallic_roughness_texture, 2);
        let (rough_lo, rough_hi) = channel_range(textures, m.metallic_roughness_texture, 1);
        let (trans_lo, trans_hi) = channel_range(textures, m.transmission_texture, 0);
        let (_, layer_hi) = channel_range(textures, m.specular_texture, 3);
        let metallic = (m.metallic * metal_lo, m.metallic * metal_hi);
        let roughness = (m.roughness * rough_lo, m.roughness * rough_hi);
        let dielectric_weight = 1.0 - metallic.0;
        let transmission = dielectric_weight * m.transmission * trans_hi;
        let diffuse = dielectric_weight * (1.0 - m.transmission * trans_lo);
        // Specular-type lobes: the conductor, the dielectric interface, the coat over diffuse.
        let has_specular_lobe =
            metallic.1 > 0.0 || transmission > 0.0 || m.specular * layer_hi > 0.0;
        self.diffuse |= diffuse > 0.0;
        self.transmission |= transmission > 0.0;
        if has_specular_lobe {
            // Roughness 0 makes the lobes perfect (delta) reflectors, any other GGX.
            self.specular |= roughness.0 <= 0.0;
            self.glossy |= roughness.1 > 0.0;
            self.near_specular |= roughness.1 > 0.0 && roughness.0 < NEAR_SPECULAR_ROUGHNESS;
        }
    }
}

impl SceneFeatures {
    /// Inspects the used materials, the textures and the lights.
    pub fn of(mesh: &Mesh, materials: &[Material], textures: &[Texture], lights: &[Light]) -> Self {
        let mut used = vec![false; materials.len()];
        for &m in &mesh.material_ids {
            used[m as usize] = true;
        }
        let mut features = SceneFeatures {
            triangles: mesh.triangle_count(),
            bounds: mesh.bounds(),
            materials: MaterialClasses::default(),
            lights: LightCounts::default(),
            textures: false,
            alpha_masks: false,
            normal_maps: false,
            vertex_colors: mesh.colors.iter().any(|&c| c != Vec3::ONE),
            absorbing_volumes: false,
        };
        for material in materials
            .iter()
            .zip(&used)
            .filter(|(_, u)| **u)
            .map(|(m, _)| m)
        {
            features.materials.add(material, textures);
            features.textures |= material.has_bsdf_textures()
                || material.normal_texture.is_some()
                || material.emissive_texture.is_some();
            features.alpha_masks |= matches!(material.alpha_mode, AlphaMode::Mask { .. });
            features.normal_maps |= material.normal_texture.is_some();
            features.absorbing_volumes |=
                material.bounds_volume() && material.absorption != Vec3::ZERO;
        }
        for light in lights {
            let counts = &mut features.lights;
            match light {
                Light::Area(_) => counts.area += 1,
                Light::Point(_) => counts.point += 1,
                Light::Spot(_) => counts.spot += 1,
                Light::Directional(_) => counts.directional += 1,
                Light::Environment(_) => counts.environment += 1,
            }
        }
        features
    }
}

impl fmt::Display for SceneFeatures {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = &self.materials;
        let l = &self.lights;
        writeln!(f, "triangles: {}", self.triangles)?;
        writeln!(f, "bounds: {} .. {}", self.bounds.min, self.bounds.max)?;
        writeln!(
            f,
            "materials: diffuse {}, glossy {} (near-specular {}), specular {}, transmission {}",
            m.diffuse, m.glossy, m.near_specular, m.specular, m.transmission
        )?;
        writeln!(
            f,
            "lights: {} area, {} point, {} spot, {} directional, {} environment",
            l.area, l.point, l.spot, l.directional, l.environment
        )?;
        write!(
            f,
            "textures {}, alpha masks {}, normal maps {}, vertex colors {}, absorbing volumes {}",
            self.textures,
            self.alpha_masks,
            self.normal_maps,
            self.vertex_colors,
            self.absorbing_volumes
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn classes(material: Material) -> MaterialClasses {
        let mut classes = MaterialClasses::default();
        classes.add(&material, &[]);
        classes
    }

    fn metal(roughness: f32) -> Material {
        Material {
            metallic: 1.0,
            roughness,
            ..Material::default()
        }
    }

    #[test]
    fn lobes_below_the_near_specular_roughness_are_near_specular() {
        let just_below = classes(metal(NEAR_SPECULAR_ROUGHNESS * 0.99));
        assert!(just_below.glossy && just_below.near_specular && !just_below.specular);
        assert!(just_below.specular_or_near() && just_below.non_specular());
        let just_above = classes(metal(NEAR_SPECULAR_ROUGHNESS * 1.01));
        assert!(just_above.glossy && !just_above.near_specular);
        assert!(!just_above.specular_or_near());
        let mirror = classes(metal(0.0));
        assert!(mirror.specular && !mirror.near_specular && !mirror.non_specular());
        // Any roughness above 0 is a GGX lobe, however polished.
        let polished = classes(metal(0.005));
        assert!(polished.glossy && polished.near_specular && !polished.specular);
        let diffuse = classes(Material::diffuse("white", Vec3::ONE));
        assert!(diffuse.diffuse && !diffuse.specular_or_near());
    }
}
