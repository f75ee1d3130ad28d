//! glTF materials and textures → [`Material`] and [`Texture`].

use std::collections::HashMap;

use glam::{Vec3, Vec4};
use gltf::json::Value;
use gltf::texture::{MagFilter, MinFilter, WrappingMode};

use super::accessors::check_view;
use super::texture_transform::{EXTENSION, TextureTransform};
use crate::error::SceneError;
use crate::image_limits::image_decoder;
use crate::loader::builder::SceneBuilder;
use crate::loader::files::{Length, ReadError, SceneFolder};
use crate::loader::uri::read_uri;
use crate::material::{AlphaMode, Material};
use crate::texture::{ColorEncoding, Filter, Texture, TextureRef, WrapMode};

/// Loads each (texture, encoding) pair once and hands out [`TextureRef`]s. Each image is
/// decoded once: textures of the same image share its texels.
pub(super) struct TextureLoader<'a> {
    folder: &'a SceneFolder,
    buffers: &'a [Vec<u8>],
    loaded: HashMap<(usize, bool), usize>,
    /// Per decoded image, the scene texture first made from it.
    decoded: HashMap<usize, usize>,
}

/// The filter of a glTF sampler, for lookups without mipmaps: its magnification filter, or
/// where it gives none its minification filter with the mipmap part dropped; bilinear where
/// it gives neither.
///
/// One lookup per sample at the sample's point, many samples per pixel: where texels are
/// smaller than a pixel, the pixel's samples average them whichever filter looks them up (the
/// work a minification filter does for a rasterizer), and only where texels are larger does
/// the filter show. That is the magnification filter's case, so it decides when both are
/// given: a sampler of nearest magnification and linear mipmaps (pixel art) keeps its texels
/// hard-edged up close.
fn filter(sampler: &gltf::texture::Sampler) -> Filter {
    let nearest = match (sampler.mag_filter(), sampler.min_filter()) {
        (Some(mag), _) => mag == MagFilter::Nearest,
        (None, Some(min)) => matches!(
            min,
            MinFilter::Nearest | MinFilter::NearestMipmapNearest | MinFilter::NearestMipmapLinear
        ),
        (None, None) => false,
    };
    if nearest {
        Filter::Nearest
    } else {
        Filter::Bilinear
    }
}

fn wrap_mode(mode: WrappingMode) -> WrapMode {
    match mode {
        WrappingMode::Repeat => WrapMode::Repeat,
        WrappingMode::MirroredRepeat => WrapMode::MirroredRepeat,
        WrappingMode::ClampToEdge => WrapMode::ClampToEdge,
    }
}

impl<'a> TextureLoader<'a> {
    pub fn new(folder: &'a SceneFolder, buffers: &'a [Vec<u8>]) -> Self {
        TextureLoader {
            folder,
            buffers,
            loaded: HashMap::new(),
            decoded: HashMap::new(),
        }
    }

    /// The encoded bytes of an image and a name for messages.
    fn image_bytes(&self, image: &gltf::Image) -> (String, Result<Vec<u8>, ReadError>) {
        match image.source() {
            gltf::image::Source::Uri { uri, .. } => {
                let name = if uri.starts_with("data:") {
                    format!("image {} (data URI)", image.index())
                } else {
                    format!("'{uri}'")
                };
                (name, read_uri(self.folder, uri, Length::Whole))
            }
            gltf::image::Source::View { view, .. } => {
                let name = format!("image {} (buffer view {})", image.index(), view.index());
                let bytes = check_view(&view, self.buffers)
                    .map(|()| {
                        let start = view.offset();
                        self.buffers[view.buffer().index()][start..start + view.length()].to_vec()
                    })
                    .map_err(ReadError::Failed);
                (name, bytes)
            }
        }
    }

    /// A reference to `texture` (loaded once per encoding) through UV set `tex_coord` with
    /// the `KHR_texture_transform` object `transform`, if any (its `texCoord` overrides).
    fn load(
        &mut self,
        builder: &mut SceneBuilder,
        texture: gltf::Texture,
        tex_coord: u32,
        transform: Option<&Value>,
        encoding: ColorEncoding,
    ) -> Result<Option<TextureRef>, SceneError> {
        let transform =
            TextureTransform::read(transform).map_err(|e| SceneError::gltf(builder.path(), e))?;
        let tex_coord = transform.tex_coord.unwrap_or(tex_coord);
        Ok(Some(TextureRef {
            index: self.texture_index(builder, texture, encoding)?,
            tex_coord,
            transform: transform.uv,
        }))
    }

    /// The index of `texture` in the scene's textures, decoding it the first time it is
    /// asked for with `encoding`.
    fn texture_index(
        &mut self,
        builder: &mut SceneBuilder,
        texture: gltf::Texture,
        encoding: ColorEncoding,
    ) -> Result<usize, SceneError> {
        let key = (texture.index(), encoding == ColorEncoding::Srgb);
        if let Some(&index) = self.loaded.get(&key) {
            return Ok(index);
        }
        let image = texture.source();
        let mut tex = match self.decoded.get(&image.index()) {
            Some(&decoded) => {
                let first = &builder.textures[decoded];
                first.sharing_texels(first.name.clone(), encoding)
            }
            None => self.decode(builder, &image, encoding)?,
        };
        let sampler = texture.sampler();
        tex.wrap_u = wrap_mode(sampler.wrap_s());
        tex.wrap_v = wrap_mode(sampler.wrap_t());
        tex.filter = filter(&sampler);
        let index = builder.textures.len();
        self.decoded.entry(image.index()).or_insert(index);
        builder.textures.push(tex);
        self.loaded.insert(key, index);
        Ok(index)
    }

    /// Reads and decodes `image`, within the texels the load options leave.
    fn decode(
        &mut self,
        builder: &mut SceneBuilder,
        image: &gltf::Image,
        encoding: ColorEncoding,
    ) -> Result<Texture, SceneError> {
        let (name, bytes) = self.image_bytes(image);
        let path = builder.path().to_path_buf();
        let texture_error = |reason: String| SceneError::Texture {
            path: path.clone(),
            texture: name.clone(),
            reason,
        };
        let bytes = bytes.map_err(|e| match (e, image.source()) {
            (ReadError::Failed(reason), _) => texture_error(reason),
            (ReadError::Outside, gltf::image::Source::Uri { uri, .. }) => {
                SceneError::outside(builder.path(), uri)
            }
            (ReadError::Outside, gltf::image::Source::View { .. }) => {
                texture_error("outside the scene's folder".into())
            }
        })?;
        let decoder = image_decoder(&bytes).map_err(texture_error)?;
        let (width, height) = image::ImageDecoder::dimensions(&decoder);
        builder.reserve_texels(&name, width, height)?;
        let decoded = image::DynamicImage::from_decoder(decoder)
            .map_err(|e| texture_error(format!("cannot decode: {e}")))?;
        Ok(Texture::from_image(name, decoded, encoding))
    }

    fn load_info(
        &mut self,
        builder: &mut SceneBuilder,
        info: Option<gltf::texture::Info>,
        encoding: ColorEncoding,
    ) -> Result<Option<TextureRef>, SceneError> {
        match info {
            Some(info) => {
                let transform = info.extension_value(EXTENSION);
                self.load(
                    builder,
                    info.texture(),
                    info.tex_coord(),
                    transform,
                    encoding,
                )
            }
            None => Ok(None),
        }
    }
}

/// The texture coordinate set that the primitives of `material` are read with: the one its
/// textures use. Where they use several, the base color texture's (or, without one, the first
/// texture's) counts and the textures on other sets are dropped, with a warning.
fn texture_coordinate_set(builder: &mut SceneBuilder, material: &mut Material) -> u32 {
    let mut slots = material.textures_mut();
    let Some(set) = slots.iter().find_map(|t| t.map(|t| t.tex_coord)) else {
        return 0;
    };
    let mut dropped = false;
    for slot in &mut slots {
        if slot.is_some_and(|t| t.tex_coord != set) {
            **slot = None;
            dropped = true;
        }
    }
    if dropped {
        let message = format!(
            "{}: material '{}' takes textures from several texture coordinate sets; only \
             those on set {set} are used",
            builder.path().display(),
            material.name
        );
        builder.warn(message);
    }
    set
}

/// Converts one glTF material (loading its textures), with the texture coordinate set its
/// primitives are to be read with.
pub(super) fn read_material(
    builder: &mut SceneBuilder,
    textures: &mut TextureLoader,
    m: &gltf::Material,
) -> Result<(Material, u32), SceneError> {
    let pbr = m.pbr_metallic_roughness();
    let mut clamped = Clamped::default();
    let srgb = ColorEncoding::Srgb;
    let linear = ColorEncoding::Linear;
    let base_color_texture = textures.load_info(builder, pbr.base_color_texture(), srgb)?;
    let metallic_roughness_texture =
        textures.load_info(builder, pbr.metallic_roughness_texture(), linear)?;
    let emissive_texture = textures.load_info(builder, m.emissive_texture(), srgb)?;
    let (normal_texture, normal_scale) = match m.normal_texture() {
        Some(n) => (
            textures.load(
                builder,
                n.texture(),
                n.tex_coord(),
                n.extension_value(EXTENSION),
                linear,
            )?,
            n.scale(),
        ),
        None => (None, 1.0),
    };
    if m.occlusion_texture().is_some() {
        builder.warn_unsupported(
            "occlusionTexture (baked ambient occlusion; light transport computes it)",
        );
    }
    let alpha_mode = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => AlphaMode::Mask {
            cutoff: clamped.at_least("alphaCutoff", m.alpha_cutoff().unwrap_or(0.5), 0.0),
        },
        gltf::material::AlphaMode::Blend => {
            builder.warn_unsupported("alphaMode BLEND (rendered as OPAQUE)");
            AlphaMode::Opaque
        }
    };
    let (specular, specular_texture, specular_color, specular_color_texture) = match m.specular() {
        Some(s) => (
            clamped.unit("specularFactor", s.specular_factor()),
            textures.load_info(builder, s.specular_texture(), linear)?,
            clamped.at_least3("specularColorFactor", s.specular_color_factor().into(), 0.0),
            textures.load_info(builder, s.specular_color_texture(), srgb)?,
        ),
        None => (1.0, None, Vec3::ONE, None),
    };
    let (transmission, transmission_texture) = match m.transmission() {
        Some(t) => (
            clamped.unit("transmissionFactor", t.transmission_factor()),
            textures.load_info(builder, t.transmission_texture(), linear)?,
        ),
        None => (0.0, None),
    };
    let thin_walled = m.volume().is_none_or(|v| v.thickness_factor() <= 0.0);
    // The glTF specification ignores a thin-walled surface's volume properties.
    let absorption = match m.volume() {
        Some(v) if !thin_walled => {
            if v.thickness_texture().is_some() {
                builder.warn_unsupported(
                    "KHR_materials_volume thicknessTexture (a path tracer measures thickness)",
                );
            }
            let distance = v.attenuation_distance();
            if distance.is_nan() || distance <= 0.0 {
                return Err(SceneError::gltf(
                    builder.path(),
                    format!(
                        "material '{}' has attenuationDistance {distance} (must be > 0)",
                        m.name().unwrap_or("unnamed")
                    ),
                ));
            }
            let color = v.attenuation_color().into();
            let color = clamped.within3("attenuationColor", color, Vec3::ZERO, Vec3::ONE);
            absorption(color, distance)
        }
        _ => Vec3::ZERO,
    };
    let emissive_factor = m.emissive_factor().into();
    let emissive_factor = clamped.within3("emissiveFactor", emissive_factor, Vec3::ZERO, Vec3::ONE);
    let strength = m.emissive_strength().unwrap_or(1.0);
    let emission = emissive_factor * clamped.at_least("emissiveStrength", strength, 0.0);
    let base_color = Vec4::from(pbr.base_color_factor());
    let base_color = if base_color.is_finite()
        && (base_color.min_element() < 0.0 || base_color.max_element() > 1.0)
    {
        let within = base_color.clamp(Vec4::ZERO, Vec4::ONE);
        clamped.note("baseColorFactor", base_color, within);
        within
    } else {
        base_color
    };
    let mut material = Material {
        name: m.name().unwrap_or("unnamed").to_string(),
        base_color,
        base_color_texture,
        metallic: clamped.unit("metallicFactor", pbr.metallic_factor()),
        roughness: clamped.unit("roughnessFactor", pbr.roughness_factor()),
        metallic_roughness_texture,
        normal_texture,
        normal_scale,
        emission,
        emissive_texture,
        specular,
        specular_texture,
        specular_color,
        specular_color_texture,
        transmission,
        transmission_texture,
        ior: clamped.at_least("ior", m.ior().unwrap_or(1.5), 1.0),
        thin_walled,
        absorption,
        alpha_mode,
        double_sided: m.double_sided(),
    };
    let set = texture_coordinate_set(builder, &mut material);
    let material = validate(builder, material)?;
    if !clamped.0.is_empty() {
        let which = match (m.name(), m.index()) {
            (Some(name), _) => format!("material '{name}'"),
            (None, Some(index)) => format!("material {index}"),
            (None, None) => "the default material".to_string(),
        };
        let message = format!(
            "{}: {which} has {} outside the range glTF allows; clamped into it",
            builder.path().display(),
            clamped.0.join(", ")
        );
        builder.warn(message);
    }
    Ok((material, set))
}

/// The factors of one material that lay outside the glTF specification's range, clamped
/// into it, for one warning naming them all. Non-finite values are left alone for
/// [`validate`] to refuse: there is no nearest value to clamp them to that the file meant.
#[derive(Default)]
struct Clamped(Vec<String>);

impl Clamped {
    /// Records that `property` was `value` and is now `within`.
    fn note(
        &mut self,
        property: &str,
        value: impl std::fmt::Display,
        within: impl std::fmt::Display,
    ) {
        self.0.push(format!("{property} {value} (now {within})"));
    }

    /// `value` clamped to [`min`, `max`].
    fn within(&mut self, property: &str, value: f32, min: f32, max: f32) -> f32 {
        if value.is_finite() && !(min..=max).contains(&value) {
            let within = value.clamp(min, max);
            self.note(property, value, within);
            within
        } else {
            value
        }
    }

    /// `value` clamped to [0, 1].
    fn unit(&mut self, property: &str, value: f32) -> f32 {
        self.within(property, value, 0.0, 1.0)
    }

    /// `value` raised to at least `min`.
    fn at_least(&mut self, property: &str, value: f32, min: f32) -> f32 {
        self.within(property, value, min, f32::INFINITY)
    }

    /// Each channel of `value` clamped to [`min`, `max`].
    fn within3(&mut self, property: &str, value: Vec3, min: Vec3, max: Vec3) -> Vec3 {
        let within = value.clamp(min, max);
        if value.is_finite() && within != value {
            self.note(property, value, within);
            within
        } else {
            value
        }
    }

    /// Each channel of `value` raised to at least `min`.
    fn at_least3(&mut self, property: &str, value: Vec3, min: f32) -> Vec3 {
        self.within3(property, value, Vec3::splat(min), Vec3::INFINITY)
    }
}

/// Beer–Lambert absorption coefficient of `KHR_materials_volume`: light keeps the fraction
/// `color` of itself over `distance` (> 0; infinite: no absorption). A black channel absorbs
/// all but the smallest positive fraction, so the coefficient stays finite.
fn absorption(color: Vec3, distance: f32) -> Vec3 {
    let kept = color.clamp(Vec3::splat(f32::MIN_POSITIVE), Vec3::ONE);
    -kept.ln() / distance
}

/// Rejects non-finite factors (out-of-range ones were clamped), naming the material.
fn validate(builder: &SceneBuilder, m: Material) -> Result<Material, SceneError> {
    let finite = m.base_color.is_finite()
        && m.emission.is_finite()
        && m.specular_color.is_finite()
        && m.absorption.is_finite()
        && [
            m.metallic,
            m.roughness,
            m.specular,
            m.transmission,
            m.normal_scale,
        ]
        .iter()
        .all(|v| v.is_finite());
    if finite && m.ior.is_finite() {
        Ok(m)
    } else {
        let reason = format!("material '{}' has a non-finite factor", m.name);
        Err(SceneError::gltf(builder.path(), reason))
    }
}
