//! Materials: the glTF metallic-roughness model with the extensions listed in the scene
//! conventions (specular, transmission, ior, volume, emissive_strength), plus texture lookups.

use glam::{Vec2, Vec3, Vec4, Vec4Swizzles};

use crate::bsdf::BsdfParams;
use crate::texture::{Texture, TextureRef};

/// How a material's alpha is used (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum AlphaMode {
    /// Alpha is ignored.
    #[default]
    Opaque,
    /// Cut-out: the surface is absent where alpha < cutoff.
    Mask {
        /// `alphaCutoff` (glTF default 0.5).
        cutoff: f32,
    },
}

/// A surface material. Factors are linear; textures multiply them (glTF semantics).
#[derive(Clone, Debug)]
pub struct Material {
    /// Name from the file, for messages.
    pub name: String,
    /// `baseColorFactor` (linear RGBA).
    pub base_color: Vec4,
    /// Base color texture (sRGB), multiplies `base_color`.
    pub base_color_texture: Option<TextureRef>,
    /// `metallicFactor`.
    pub metallic: f32,
    /// `roughnessFactor` (perceptual; GGX alpha = roughness²).
    pub roughness: f32,
    /// Metallic-roughness texture: green = roughness, blue = metallic.
    pub metallic_roughness_texture: Option<TextureRef>,
    /// Tangent-space normal map.
    pub normal_texture: Option<TextureRef>,
    /// Normal map `scale` (xy of the tangent-space normal are multiplied by it).
    pub normal_scale: f32,
    /// Emitted radiance: `emissiveFactor · emissiveStrength` (linear RGB, W·sr⁻¹·m⁻² in scene units).
    pub emission: Vec3,
    /// Emissive texture (sRGB), multiplies `emission`.
    pub emissive_texture: Option<TextureRef>,
    /// `KHR_materials_specular.specularFactor` (default 1).
    pub specular: f32,
    /// `KHR_materials_specular.specularTexture`: its alpha multiplies `specular`.
    pub specular_texture: Option<TextureRef>,
    /// `KHR_materials_specular.specularColorFactor` (default white).
    pub specular_color: Vec3,
    /// `KHR_materials_specular.specularColorTexture` (sRGB), multiplies `specular_color`.
    pub specular_color_texture: Option<TextureRef>,
    /// `KHR_materials_transmission.transmissionFactor` (default 0).
    pub transmission: f32,
    /// `KHR_materials_transmission.transmissionTexture`: its red channel multiplies
    /// `transmission`.
    pub transmission_texture: Option<TextureRef>,
    /// `KHR_materials_ior.ior` (default 1.5).
    pub ior: f32,
    /// True unless `KHR_materials_volume.thicknessFactor` > 0 (then the mesh bounds a solid).
    pub thin_walled: bool,
    /// Absorption coefficient σ_a (per scene unit of length, linear RGB) inside the solid a
    /// [volume boundary](Material::bounds_volume) encloses: from `KHR_materials_volume`,
    /// −ln(attenuationColor) / attenuationDistance (Beer–Lambert); zero for a clear solid.
    pub absorption: Vec3,
    /// Alpha usage.
    pub alpha_mode: AlphaMode,
    /// glTF `doubleSided`: one-sided materials are black seen from the back.
    pub double_sided: bool,
}

impl Default for Material {
    /// The glTF default material: white, fully metallic, fully rough (glTF 2.0 §3.9.2).
    fn default() -> Self {
        Material {
            name: "default".into(),
            base_color: Vec4::ONE,
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            emission: Vec3::ZERO,
            emissive_texture: None,
            specular: 1.0,
            specular_texture: None,
            specular_color: Vec3::ONE,
            specular_color_texture: None,
            transmission: 0.0,
            transmission_texture: None,
            ior: 1.5,
            thin_walled: true,
            absorption: Vec3::ZERO,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
        }
    }
}

/// Looks a texture up, or returns white where the material has none.
fn lookup(textures: &[Texture], texture: Option<TextureRef>, uv: Vec2) -> Vec4 {
    texture.map_or(Vec4::ONE, |t| t.sample(textures, uv))
}

/// Coverage alpha at `uv`: `alpha` times the alpha of `texture`.
fn coverage(textures: &[Texture], alpha: f32, texture: Option<TextureRef>, uv: Vec2) -> f32 {
    alpha * lookup(textures, texture, uv).w
}

/// Where the surface of an alpha-masked material is (glTF `alphaMode` MASK): wherever its
/// coverage alpha reaches the cutoff; rays pass through the rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlphaMask {
    /// The base color factor's alpha.
    pub alpha: f32,
    /// The base color texture, whose alpha multiplies `alpha`.
    pub texture: Option<TextureRef>,
    /// `alphaCutoff`: the surface is present where the coverage is at least this.
    pub cutoff: f32,
}

impl AlphaMask {
    /// Whether the surface is present at `uv`.
    pub fn covers(&self, textures: &[Texture], uv: Vec2) -> bool {
        coverage(textures, self.alpha, self.texture, uv) >= self.cutoff
    }
}

impl Material {
    /// A pure Lambertian diffuse material (metallic 0, roughness 1, specular 0).
    pub fn diffuse(name: &str, albedo: Vec3) -> Self {
        Material {
            name: name.into(),
            base_color: albedo.extend(1.0),
            metallic: 0.0,
            specular: 0.0,
            double_sided: true,
            ..Material::default()
        }
    }

    /// Whether the surface is the boundary of a solid that light enters: it transmits and is
    /// not thin-walled.
    pub fn bounds_volume(&self) -> bool {
        self.transmission > 0.0 && !self.thin_walled
    }

    /// BSDF parameters at texture coordinates `uv`.
    pub fn bsdf_params(&self, textures: &[Texture], uv: Vec2) -> BsdfParams {
        let base = self.base_color * lookup(textures, self.base_color_texture, uv);
        let mr = lookup(textures, self.metallic_roughness_texture, uv);
        let specular = self.specular * lookup(textures, self.specular_texture, uv).w;
        let specular_color =
            self.specular_color * lookup(textures, self.specular_color_texture, uv).xyz();
        let transmission = self.transmission * lookup(textures, self.transmission_texture, uv).x;
        BsdfParams {
            base_color: base.xyz(),
            metallic: (self.metallic * mr.z).clamp(0.0, 1.0),
            roughness: (self.roughness * mr.y).clamp(0.0, 1.0),
            specular: specular.clamp(0.0, 1.0),
            specular_color: specular_color.max(Vec3::ZERO),
            transmission: transmission.clamp(0.0, 1.0),
            ior: self.ior,
            thin_walled: self.thin_walled,
        }
    }

    /// The BSDF parameters when no texture changes them (the same at every `uv`), `None` for
    /// a material with a texture that does.
    pub fn uniform_bsdf_params(&self) -> Option<BsdfParams> {
        (!self.has_bsdf_textures()).then(|| self.bsdf_params(&[], Vec2::ZERO))
    }

    /// Every texture slot, the base color's first.
    pub fn textures_mut(&mut self) -> [&mut Option<TextureRef>; 7] {
        [
            &mut self.base_color_texture,
            &mut self.metallic_roughness_texture,
            &mut self.normal_texture,
            &mut self.emissive_texture,
            &mut self.specular_texture,
            &mut self.specular_color_texture,
            &mut self.transmission_texture,
        ]
    }

    /// Whether a texture changes the BSDF parameters from point to point.
    pub fn has_bsdf_textures(&self) -> bool {
        [
            self.base_color_texture,
            self.metallic_roughness_texture,
            self.specular_texture,
            self.specular_color_texture,
            self.transmission_texture,
        ]
        .iter()
        .any(Option::is_some)
    }

    /// Emitted radiance at `uv` (zero for non-emitters).
    pub fn emission_at(&self, textures: &[Texture], uv: Vec2) -> Vec3 {
        self.emission * lookup(textures, self.emissive_texture, uv).xyz()
    }

    /// True when the material emits light anywhere.
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// Coverage alpha at `uv`: base color alpha times the base color texture's alpha.
    pub fn alpha_at(&self, textures: &[Texture], uv: Vec2) -> f32 {
        coverage(textures, self.base_color.w, self.base_color_texture, uv)
    }

    /// For alpha-masked materials: whether the surface is present at `uv`.
    pub fn is_opaque_at(&self, textures: &[Texture], uv: Vec2) -> bool {
        self.alpha_mask()
            .is_none_or(|mask| mask.covers(textures, uv))
    }

    /// The cut-out of an alpha-masked material (`None`: the surface is present everywhere).
    pub fn alpha_mask(&self) -> Option<AlphaMask> {
        match self.alpha_mode {
            AlphaMode::Opaque => None,
            AlphaMode::Mask { cutoff } => Some(AlphaMask {
                alpha: self.base_color.w,
                texture: self.base_color_texture,
                cutoff,
            }),
        }
    }

    /// The tangent-space normal from the normal map at `uv` (z up), or `None` without a map.
    pub fn tangent_space_normal(&self, textures: &[Texture], uv: Vec2) -> Option<Vec3> {
        let t = self.normal_texture?;
        let c = t.sample(textures, uv).xyz() * 2.0 - Vec3::ONE;
        let n = Vec3::new(c.x * self.normal_scale, c.y * self.normal_scale, c.z);
        n.try_normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::ColorEncoding;

    fn masked(cutoff: f32) -> (Material, Vec<Texture>) {
        // Left texel alpha 0.2, right texel alpha 0.8 (alpha is never sRGB-decoded).
        let texels = vec![[255, 255, 255, 51], [255, 255, 255, 204]];
        let texture = Texture::new("mask".into(), 2, 1, texels, ColorEncoding::Srgb).unwrap();
        let material = Material {
            base_color_texture: Some(TextureRef::new(0)),
            alpha_mode: AlphaMode::Mask { cutoff },
            ..Material::default()
        };
        (material, vec![texture])
    }

    #[test]
    fn alpha_mask_cuts_where_alpha_is_below_the_cutoff() {
        let (material, textures) = masked(0.5);
        assert!(!material.is_opaque_at(&textures, Vec2::new(0.25, 0.5)));
        assert!(material.is_opaque_at(&textures, Vec2::new(0.75, 0.5)));
        let (low, textures) = masked(0.1);
        assert!(low.is_opaque_at(&textures, Vec2::new(0.25, 0.5)));
        let opaque = Material {
            alpha_mode: AlphaMode::Opaque,
            ..low
        };
        assert!(opaque.is_opaque_at(&textures, Vec2::new(0.25, 0.5)));
    }

    #[test]
    fn textures_multiply_factors() {
        let (mut material, textures) = masked(0.5);
        material.base_color = Vec4::new(0.5, 0.25, 1.0, 1.0);
        material.metallic = 0.0;
        let params = material.bsdf_params(&textures, Vec2::new(0.75, 0.5));
        assert_eq!(params.base_color, Vec3::new(0.5, 0.25, 1.0));
        assert!((material.alpha_at(&textures, Vec2::new(0.75, 0.5)) - 0.8).abs() < 1e-6);
    }
}
