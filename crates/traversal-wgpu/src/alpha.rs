//! Alpha masks the GPU can evaluate itself: per masked triangle its texture coordinates, an
//! alpha factor and cutoff, and the alpha channel of its texture, looked up bilinearly with
//! glTF wrap modes, or as the nearest texel (the scene's CPU lookup, in single precision).

use bytemuck::{Pod, Zeroable};
use glam::Vec2;

/// How texture coordinates outside [0, 1] map onto texels (glTF `wrapS` / `wrapT`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// Tile.
    #[default]
    Repeat = 0,
    /// Tile, mirroring every other copy.
    MirroredRepeat = 1,
    /// Clamp to the edge texels.
    ClampToEdge = 2,
}

/// How a lookup between texel centers is filtered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Filter {
    /// Interpolates the four nearest texels.
    #[default]
    Bilinear = 0,
    /// The texel the point falls in.
    Nearest = 1,
}

/// The alpha channel of a texture.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AlphaTexture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Wrap mode along u and along v.
    pub wrap: [Wrap; 2],
    /// Filtering between texel centers.
    pub filter: Filter,
    /// Row-major alpha values, `width × height`, 0 = transparent and 255 = opaque.
    pub alpha: Vec<u8>,
}

/// An alpha-masked triangle: opaque where `alpha_factor × texture alpha ≥ cutoff`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaskedTriangle {
    /// Texture coordinates of the three vertices.
    pub uvs: [Vec2; 3],
    /// Index into [`AlphaMasks::textures`], or `None` for a constant alpha.
    pub texture: Option<u32>,
    /// Multiplies the texture's alpha (glTF `baseColorFactor.a`).
    pub alpha_factor: f32,
    /// Alpha below this is transparent (glTF `alphaCutoff`).
    pub cutoff: f32,
}

/// The alpha masks of a scene, indexed like its triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AlphaMasks {
    /// Textures referenced by [`MaskedTriangle::texture`].
    pub textures: Vec<AlphaTexture>,
    /// Per triangle id, its mask, or `None` for an opaque triangle.
    pub triangles: Vec<Option<MaskedTriangle>>,
}

/// `MaskedTriangle` as `alpha_masks.wgsl` reads it.
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GpuMask {
    uvs: [[f32; 2]; 3],
    alpha_factor: f32,
    cutoff: f32,
    texture: u32,
    _pad: u32,
}

/// `AlphaTexture`'s placement in the packed texel array.
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GpuTexture {
    /// First texel.
    offset: u32,
    width: u32,
    height: u32,
    /// Wrap along u in bits 0–7, along v in bits 8–15, the filter in bits 16–23.
    sampler: u32,
}

/// Marks an opaque leaf triangle in the per-leaf mask index, and "no texture".
pub(crate) const NONE: u32 = u32::MAX;

/// The masks as GPU buffers: per leaf-order triangle a mask index, the masks, the texture
/// table and the alpha values packed four to a word.
pub(crate) struct PackedMasks {
    pub leaf_masks: Vec<u32>,
    pub masks: Vec<GpuMask>,
    pub textures: Vec<GpuTexture>,
    pub texels: Vec<u32>,
}

impl AlphaMasks {
    /// Whether any triangle is masked.
    pub fn any(&self) -> bool {
        self.triangles.iter().any(Option::is_some)
    }

    /// Packs the masks for leaf order `ids` (leaf position → triangle id).
    pub(crate) fn pack(&self, ids: &[u32]) -> PackedMasks {
        let mut masks = Vec::new();
        let leaf_masks = ids
            .iter()
            .map(
                |&id| match self.triangles.get(id as usize).copied().flatten() {
                    None => NONE,
                    Some(mask) => {
                        masks.push(GpuMask {
                            uvs: mask.uvs.map(|uv| uv.to_array()),
                            alpha_factor: mask.alpha_factor,
                            cutoff: mask.cutoff,
                            texture: mask.texture.unwrap_or(NONE),
                            _pad: 0,
                        });
                        (masks.len() - 1) as u32
                    }
                },
            )
            .collect();
        let mut texels = Vec::new();
        let textures = self
            .textures
            .iter()
            .map(|texture| {
                let offset = texels.len() as u32;
                texels.extend_from_slice(&texture.alpha);
                GpuTexture {
                    offset,
                    width: texture.width,
                    height: texture.height,
                    sampler: texture.wrap[0] as u32
                        | (texture.wrap[1] as u32) << 8
                        | (texture.filter as u32) << 16,
                }
            })
            .collect();
        let texels = texels
            .chunks(4)
            .map(|c| {
                c.iter()
                    .rev()
                    .fold(0u32, |word, &a| word << 8 | u32::from(a))
            })
            .collect();
        PackedMasks {
            leaf_masks,
            masks,
            textures,
            texels,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_keeps_leaf_order_and_texel_bytes() {
        let masks = AlphaMasks {
            textures: vec![AlphaTexture {
                width: 5,
                height: 1,
                wrap: [Wrap::ClampToEdge, Wrap::MirroredRepeat],
                filter: Filter::Nearest,
                alpha: vec![1, 2, 3, 4, 5],
            }],
            triangles: vec![
                None,
                Some(MaskedTriangle {
                    uvs: [Vec2::ZERO, Vec2::X, Vec2::Y],
                    texture: Some(0),
                    alpha_factor: 0.5,
                    cutoff: 0.25,
                }),
            ],
        };
        let packed = masks.pack(&[1, 0]);
        assert_eq!(packed.leaf_masks, [0, NONE]);
        assert_eq!(packed.masks.len(), 1);
        assert_eq!(packed.texels, [0x0403_0201, 0x05]);
        assert_eq!(packed.textures[0].sampler, 2 | 1 << 8 | 1 << 16);
    }
}
