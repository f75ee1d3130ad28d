//! Textures: 8-bit RGBA texels, decoded to linear on lookup, bilinear or nearest-texel
//! filtering and glTF wrap modes.

use std::sync::Arc;

use glam::{Vec2, Vec4};

/// How texture coordinates outside [0, 1] are mapped (glTF sampler `wrapS` / `wrapT`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WrapMode {
    /// Tile the texture (glTF default).
    #[default]
    Repeat,
    /// Tile the texture, mirroring every other copy.
    MirroredRepeat,
    /// Clamp to the edge texels.
    ClampToEdge,
}

impl WrapMode {
    /// Maps an integer texel coordinate onto `0..size`.
    fn apply(self, i: i64, size: u32) -> u32 {
        let n = i64::from(size);
        let wrapped = match self {
            WrapMode::Repeat => i.rem_euclid(n),
            WrapMode::ClampToEdge => i.clamp(0, n - 1),
            WrapMode::MirroredRepeat => {
                let period = i.rem_euclid(2 * n);
                if period < n {
                    period
                } else {
                    2 * n - 1 - period
                }
            }
        };
        wrapped as u32
    }
}

/// How a lookup between texel centers is filtered (glTF sampler filters, mipmapping aside:
/// a path tracer looks up one point per sample).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Filter {
    /// Interpolates the four nearest texels.
    #[default]
    Bilinear,
    /// The texel the point falls in.
    Nearest,
}

/// How the stored 8-bit values are interpreted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorEncoding {
    /// sRGB-encoded color (base color, emissive): decoded to linear on lookup; alpha stays linear.
    Srgb,
    /// Linear data (metallic-roughness, normal maps, masks).
    Linear,
}

/// An RGBA image with a sampler. Lookups return linear values in [0, 1].
#[derive(Clone, Debug)]
pub struct Texture {
    /// A name for messages (the image URI or the glTF image name).
    pub name: String,
    width: u32,
    height: u32,
    /// Shared by the textures of one image (which differ in encoding or sampler only).
    texels: Arc<[[u8; 4]]>,
    encoding: ColorEncoding,
    /// Mean linear RGBA over all texels, computed once.
    average: std::sync::OnceLock<Vec4>,
    /// Wrap mode along u.
    pub wrap_u: WrapMode,
    /// Wrap mode along v.
    pub wrap_v: WrapMode,
    /// Filtering between texel centers.
    pub filter: Filter,
}

/// Lookup table from an sRGB-encoded byte to linear intensity (IEC 61966-2-1).
pub fn srgb_to_linear_table() -> &'static [f32; 256] {
    static TABLE: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| {
            let c = i as f32 / 255.0;
            if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            }
        })
    })
}

impl Texture {
    /// Wraps decoded RGBA8 texels (row 0 is the top of the image, as glTF's UV origin is top-left).
    ///
    /// Returns `None` when the size does not match the texel count or is zero.
    pub fn new(
        name: String,
        width: u32,
        height: u32,
        texels: Vec<[u8; 4]>,
        encoding: ColorEncoding,
    ) -> Option<Self> {
        let valid = width > 0 && height > 0 && texels.len() == width as usize * height as usize;
        valid.then_some(Texture {
            name,
            width,
            height,
            texels: texels.into(),
            encoding,
            average: std::sync::OnceLock::new(),
            wrap_u: WrapMode::Repeat,
            wrap_v: WrapMode::Repeat,
            filter: Filter::Bilinear,
        })
    }

    /// Converts a decoded image, choosing how its values are interpreted.
    pub fn from_image(name: String, image: image::DynamicImage, encoding: ColorEncoding) -> Self {
        let rgba = image.into_rgba8();
        let (width, height) = rgba.dimensions();
        let texels = rgba.pixels().map(|p| p.0).collect();
        Texture::new(name, width, height, texels, encoding)
            .expect("an RGBA8 image buffer always holds width*height texels")
    }

    /// The same texels under another name and encoding, with the default sampler, sharing
    /// their memory: for the textures of one image.
    pub fn sharing_texels(&self, name: String, encoding: ColorEncoding) -> Texture {
        Texture {
            name,
            width: self.width,
            height: self.height,
            texels: Arc::clone(&self.texels),
            encoding,
            average: std::sync::OnceLock::new(),
            wrap_u: WrapMode::Repeat,
            wrap_v: WrapMode::Repeat,
            filter: Filter::Bilinear,
        }
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// How the texels are interpreted.
    pub fn encoding(&self) -> ColorEncoding {
        self.encoding
    }

    /// The texels as stored, RGBA8, row by row from the top.
    pub fn texels(&self) -> &[[u8; 4]] {
        &self.texels
    }

    /// One texel as linear RGBA.
    pub fn texel(&self, x: u32, y: u32) -> Vec4 {
        let [r, g, b, a] = self.texels[(y * self.width + x) as usize];
        let alpha = f32::from(a) / 255.0;
        match self.encoding {
            ColorEncoding::Linear => {
                Vec4::new(f32::from(r), f32::from(g), f32::from(b), f32::from(a)) / 255.0
            }
            ColorEncoding::Srgb => {
                let table = srgb_to_linear_table();
                Vec4::new(
                    table[r as usize],
                    table[g as usize],
                    table[b as usize],
                    alpha,
                )
            }
        }
    }

    /// Filtered lookup at texture coordinates `uv` (glTF convention: (0,0) is the top-left
    /// corner of the image), in linear values, with the texture's [`Filter`] and wrap modes.
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        if !uv.is_finite() {
            return self.texel(0, 0);
        }
        let x = f64::from(uv.x) * f64::from(self.width);
        let y = f64::from(uv.y) * f64::from(self.height);
        match self.filter {
            Filter::Bilinear => self.bilinear(x - 0.5, y - 0.5),
            Filter::Nearest => self.wrapped_texel(x.floor() as i64, y.floor() as i64),
        }
    }

    /// The texel at integer coordinates (`x`, `y`), wrapped into the image. Coordinates far
    /// outside it saturate in the callers' i64 casts; wrapping keeps them in range.
    fn wrapped_texel(&self, x: i64, y: i64) -> Vec4 {
        self.texel(
            self.wrap_u.apply(x, self.width),
            self.wrap_v.apply(y, self.height),
        )
    }

    /// Bilinear interpolation at texel-space (`x`, `y`), texel centers at integers.
    fn bilinear(&self, x: f64, y: f64) -> Vec4 {
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (xi, yi) = (x0 as i64, y0 as i64);
        let (xj, yj) = (xi.saturating_add(1), yi.saturating_add(1));
        let top = self
            .wrapped_texel(xi, yi)
            .lerp(self.wrapped_texel(xj, yi), fx);
        let bottom = self
            .wrapped_texel(xi, yj)
            .lerp(self.wrapped_texel(xj, yj), fx);
        top.lerp(bottom, fy)
    }

    /// Mean linear RGBA over all texels (used for light power estimates), computed on first use.
    pub fn average(&self) -> Vec4 {
        *self.average.get_or_init(|| self.compute_average())
    }

    fn compute_average(&self) -> Vec4 {
        let mut sum = [0f64; 4];
        for y in 0..self.height {
            for x in 0..self.width {
                let t = self.texel(x, y);
                for (s, c) in sum.iter_mut().zip(t.to_array()) {
                    *s += f64::from(c);
                }
            }
        }
        let n = f64::from(self.width) * f64::from(self.height);
        Vec4::from_array(sum.map(|s| (s / n) as f32))
    }
}

/// A material's reference to a texture: which texture, which UV set, and how the UVs are
/// transformed before the lookup.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into [`crate::Scene::textures`].
    pub index: usize,
    /// The file's texture coordinate set (`TEXCOORD_n`). The glTF loader reads each primitive's
    /// coordinates from the one set its material's textures use, so a lookup takes the
    /// surface's coordinates whatever the number.
    pub tex_coord: u32,
    /// Applied to the surface's texture coordinates before the lookup
    /// (`KHR_texture_transform`; the identity without it).
    pub transform: UvTransform,
}

impl TextureRef {
    /// A reference to texture `index` through UV set 0, untransformed.
    pub fn new(index: usize) -> TextureRef {
        TextureRef {
            index,
            tex_coord: 0,
            transform: UvTransform::IDENTITY,
        }
    }

    /// The referenced texture of `textures` at the surface's texture coordinates `uv`.
    #[inline]
    pub fn sample(&self, textures: &[Texture], uv: Vec2) -> Vec4 {
        textures[self.index].sample(self.transform.apply(uv))
    }
}

/// An affine map of texture coordinates: `uv' = linear · uv + offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// The linear part, as columns (the images of the u and v axes).
    pub linear: [Vec2; 2],
    /// Added after the linear part.
    pub offset: Vec2,
}

impl UvTransform {
    /// Leaves coordinates as they are.
    pub const IDENTITY: UvTransform = UvTransform {
        linear: [Vec2::X, Vec2::Y],
        offset: Vec2::ZERO,
    };

    /// `KHR_texture_transform`'s map: scale the coordinates by `scale`, rotate them by
    /// `rotation` radians (counter-clockwise in UV space, whose v axis points down the
    /// image), then add `offset`: uv' = T·R·S·uv with R = [[cos, sin], [−sin, cos]].
    pub fn from_offset_rotation_scale(offset: Vec2, rotation: f32, scale: Vec2) -> UvTransform {
        let (sin, cos) = rotation.sin_cos();
        UvTransform {
            linear: [
                Vec2::new(cos, -sin) * scale.x,
                Vec2::new(sin, cos) * scale.y,
            ],
            offset,
        }
    }

    /// The transformed coordinates of `uv`.
    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        if *self == UvTransform::IDENTITY {
            return uv;
        }
        self.linear[0] * uv.x + self.linear[1] * uv.y + self.offset
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Texture {
        let texels = vec![
            [0, 0, 0, 255],
            [255, 255, 255, 255],
            [255, 255, 255, 255],
            [0, 0, 0, 0],
        ];
        Texture::new("checker".into(), 2, 2, texels, ColorEncoding::Linear).unwrap()
    }

    /// The two examples of the `KHR_texture_transform` specification.
    #[test]
    fn uv_transforms_follow_the_specification_examples() {
        let close = |a: Vec2, b: Vec2| a.abs_diff_eq(b, 1e-6);
        // "Only the lower left quadrant of the source image, rotated clockwise 90°."
        let quadrant = UvTransform::from_offset_rotation_scale(
            Vec2::new(0.0, 1.0),
            std::f32::consts::FRAC_PI_2,
            Vec2::splat(0.5),
        );
        for (uv, expected) in [
            ((0.0, 0.0), (0.0, 1.0)),
            ((1.0, 0.0), (0.0, 0.5)),
            ((0.0, 1.0), (0.5, 1.0)),
            ((1.0, 1.0), (0.5, 0.5)),
        ] {
            let (uv, expected) = (Vec2::from(uv), Vec2::from(expected));
            assert!(close(quadrant.apply(uv), expected), "{uv}");
        }
        // "Inverts the T axis, effectively defining a bottom-left origin."
        let flipped =
            UvTransform::from_offset_rotation_scale(Vec2::new(0.0, 1.0), 0.0, Vec2::new(1.0, -1.0));
        assert_eq!(flipped.apply(Vec2::new(0.25, 0.25)), Vec2::new(0.25, 0.75));
        // The identity leaves even non-finite coordinates as they are.
        let odd = Vec2::new(f32::NAN, -0.0);
        let kept = UvTransform::IDENTITY.apply(odd);
        assert!(kept.x.is_nan() && kept.y.to_bits() == (-0.0f32).to_bits());
    }

    #[test]
    fn texel_centers_return_exact_values() {
        let t = checker();
        assert_eq!(
            t.sample(Vec2::new(0.25, 0.25)),
            Vec4::new(0.0, 0.0, 0.0, 1.0)
        );
        assert_eq!(t.sample(Vec2::new(0.75, 0.25)), Vec4::ONE);
    }

    #[test]
    fn bilinear_midpoint_averages_four_texels() {
        let t = checker();
        let mid = t.sample(Vec2::new(0.5, 0.5));
        assert!((mid - Vec4::new(0.5, 0.5, 0.5, 0.75)).abs().max_element() < 1e-6);
    }

    /// Nearest-texel lookups return the texel a point falls in, up to its edges, with the
    /// wrap modes outside the image.
    #[test]
    fn nearest_lookup_returns_the_texel_under_the_point() {
        let mut t = checker();
        t.filter = Filter::Nearest;
        let (black, white) = (Vec4::new(0.0, 0.0, 0.0, 1.0), Vec4::ONE);
        assert_eq!(t.sample(Vec2::new(0.0, 0.0)), black);
        assert_eq!(t.sample(Vec2::new(0.49, 0.1)), black);
        assert_eq!(t.sample(Vec2::new(0.5, 0.1)), white);
        assert_eq!(t.sample(Vec2::new(0.99, 0.99)), Vec4::ZERO);
        // Repeat: u = 1.2 is u = 0.2; mirrored repeat: v = 1.2 is v = 0.8.
        assert_eq!(t.sample(Vec2::new(1.2, 0.3)), black);
        t.wrap_v = WrapMode::MirroredRepeat;
        assert_eq!(t.sample(Vec2::new(0.2, 1.2)), white);
        assert!(t.sample(Vec2::new(-1e30, 1e30)).is_finite());
    }

    #[test]
    fn wrap_modes_map_into_range() {
        assert_eq!(WrapMode::Repeat.apply(-1, 4), 3);
        assert_eq!(WrapMode::Repeat.apply(9, 4), 1);
        assert_eq!(WrapMode::ClampToEdge.apply(-5, 4), 0);
        assert_eq!(WrapMode::ClampToEdge.apply(7, 4), 3);
        assert_eq!(WrapMode::MirroredRepeat.apply(4, 4), 3);
        assert_eq!(WrapMode::MirroredRepeat.apply(-1, 4), 0);
        assert_eq!(WrapMode::MirroredRepeat.apply(8, 4), 0);
        // Extreme coordinates do not panic.
        let t = checker();
        assert!(t.sample(Vec2::new(1e30, -1e30)).is_finite());
        assert!(t.sample(Vec2::new(f32::NAN, 0.0)).is_finite());
    }

    #[test]
    fn srgb_decoding_matches_the_standard_curve() {
        let t = Texture::new(
            "grey".into(),
            1,
            1,
            vec![[188, 188, 188, 128]],
            ColorEncoding::Srgb,
        )
        .unwrap();
        let v = t.texel(0, 0);
        // sRGB 188/255 ≈ 0.5029 linear; alpha is not decoded.
        assert!((v.x - 0.5029).abs() < 1e-3, "{v}");
        assert!((v.w - 128.0 / 255.0).abs() < 1e-6);
    }
}
