//! The Wavefront OBJ/MTL loader (through `tobj`), mapped onto the glTF material model:
//!
//! | MTL | material |
//! | --- | --- |
//! | `Kd`, `map_Kd` | base color and base color texture (sRGB); default grey 0.8 |
//! | `Ks` = 0 or absent | pure Lambertian diffuse (metallic 0, specular 0) |
//! | `Ks` > 0, `Kd` = 0 | conductor: metallic 1, base color = `Ks` |
//! | `Ks` > 0, `Kd` > 0 | dielectric base: specular = max(`Ks`), specular color = `Ks` / max(`Ks`) |
//! | `Ns` | roughness = α^½ with GGX α = (2 / (`Ns` + 2))^½ (Blinn-Phong to microfacet); absent: 1 |
//! | `Ke` | emitted radiance |
//! | `Ni` | index of refraction (values below 1 are ignored: 1.5) |
//! | `illum` 4, 6, 7 or 9 | solid glass: transmission 1, base color white |
//! | `d` < 1 (other illum) | thin-walled transmission 1 − `d` |
//!
//! OBJ has no sidedness: all OBJ materials are double-sided (emission still leaves the front
//! face, from the winding order). Texture coordinates have v flipped to glTF's top-left origin.
//! Files without materials use the grey diffuse default; OBJ files have no cameras or lights
//! other than emissive materials, so the default camera frames the scene.

use std::cell::RefCell;
use std::io::{BufRead, Read};
use std::path::Path;

use glam::{Vec2, Vec3};

use crate::error::SceneError;
use crate::image_limits::image_decoder;
use crate::loader::LoadOptions;
use crate::loader::builder::{Primitive, SceneBuilder};
use crate::loader::files::{Length, ReadError, SceneFolder, open_regular_file};
use crate::material::Material;
use crate::scene::Scene;
use crate::texture::{ColorEncoding, Texture, TextureRef};

/// Loads an OBJ file and the MTL files it references (relative to its folder) with the
/// default [`LoadOptions`].
pub fn load_obj(path: &Path) -> Result<Scene, SceneError> {
    load_obj_with(path, &LoadOptions::default())
}

/// [`load_obj`] within `options`.
pub fn load_obj_with(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    let (file, length) = open_regular_file(path).map_err(|reason| SceneError::Io {
        path: path.to_path_buf(),
        reason,
    })?;
    let mut reader = std::io::BufReader::new(file.take(length));
    load_obj_from_reader_with(path, &mut reader, options)
}

fn obj_error(path: &Path, reason: impl Into<String>) -> SceneError {
    SceneError::Obj {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Loads OBJ text from `reader` with the default [`LoadOptions`]; `path` names it in
/// messages and locates MTL and texture files.
pub fn load_obj_from_reader(path: &Path, reader: &mut impl BufRead) -> Result<Scene, SceneError> {
    load_obj_from_reader_with(path, reader, &LoadOptions::default())
}

/// [`load_obj_from_reader`] within `options`.
pub fn load_obj_from_reader_with(
    path: &Path,
    reader: &mut impl BufRead,
    options: &LoadOptions,
) -> Result<Scene, SceneError> {
    let folder = SceneFolder::of(path, options);
    let obj_options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    // tobj's errors are fixed words; why a library was not read is kept here to report.
    let library_error: RefCell<Option<ReadError>> = RefCell::new(None);
    let load_library = |mtl: &Path| {
        let bytes = folder
            .read(&mtl.to_string_lossy(), Length::Whole)
            .map_err(|e| {
                let problem = match &e {
                    ReadError::Outside => tobj::LoadError::OpenFileFailed,
                    ReadError::Failed(_) => tobj::LoadError::ReadError,
                };
                library_error.replace(Some(e));
                problem
            })?;
        tobj::load_mtl_buf(&mut std::io::Cursor::new(bytes))
    };
    let (models, materials) = tobj::load_obj_buf(reader, &obj_options, load_library)
        .map_err(|e| obj_error(path, e.to_string()))?;

    let mut builder = SceneBuilder::new(path, options);
    match (materials, library_error.into_inner()) {
        (Ok(materials), _) => {
            for m in &materials {
                let material = convert_material(&mut builder, &folder, m)?;
                builder.materials.push(material);
            }
        }
        (Err(_), Some(ReadError::Outside)) => builder.warn(format!(
            "{}: a material library is outside the scene's folder and is not read (the load \
             options do not allow it); using the default material",
            path.display()
        )),
        (Err(_), Some(ReadError::Failed(reason))) => builder.warn(format!(
            "{}: material library not loaded ({reason}); using the default material",
            path.display()
        )),
        (Err(e), None) => builder.warn(format!(
            "{}: material library not loaded ({e}); using the default material",
            path.display()
        )),
    }
    let default_material = builder.materials.len() as u32;
    builder
        .materials
        .push(Material::diffuse("default", Vec3::splat(0.8)));

    for (i, model) in models.iter().enumerate() {
        let mesh = &model.mesh;
        let material = match mesh.material_id {
            Some(id) if id < default_material as usize => id as u32,
            _ => default_material,
        };
        let triples = |v: &[f32]| -> Vec<Vec3> {
            v.chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]))
                .collect()
        };
        let positions = triples(&mesh.positions);
        // Objects whose faces mix vertices with and without `vn`/`vt` get partial attribute
        // arrays from tobj: such an attribute is dropped for the object, with a warning.
        let vertex_count = positions.len();
        let mut complete = |what: &str, len: usize, per_vertex: usize| {
            let ok = len == vertex_count * per_vertex;
            if len > 0 && !ok {
                builder.warn(format!(
                    "{}: object '{}' has {what} on only some faces; they are ignored",
                    path.display(),
                    model.name
                ));
            }
            ok && len > 0
        };
        let normals = complete("normals", mesh.normals.len(), 3).then(|| triples(&mesh.normals));
        let uvs = complete("texture coordinates", mesh.texcoords.len(), 2).then(|| {
            mesh.texcoords
                .chunks_exact(2)
                .map(|c| Vec2::new(c[0], 1.0 - c[1]))
                .collect()
        });
        let triangles = mesh
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        builder.add_primitive(Primitive {
            name: format!("object '{}' ({i})", model.name),
            positions,
            normals,
            uvs,
            tangents: None,
            colors: None,
            triangles,
            material,
        })?;
    }
    Ok(builder.finish())
}

/// Maps one MTL material (see the module documentation for the table).
fn convert_material(
    builder: &mut SceneBuilder,
    folder: &SceneFolder,
    m: &tobj::Material,
) -> Result<Material, SceneError> {
    let path = builder.path().to_path_buf();
    let kd = Vec3::from(m.diffuse.unwrap_or([0.8; 3]));
    let ks = Vec3::from(m.specular.unwrap_or([0.0; 3]));
    let ke = Vec3::from(m.emissive.unwrap_or([0.0; 3]));
    let values = [kd, ks, ke];
    if values
        .iter()
        .any(|v| !v.is_finite() || v.min_element() < 0.0)
    {
        let reason = format!("material '{}' has a negative or non-finite color", m.name);
        return Err(obj_error(&path, reason));
    }
    let roughness = m
        .shininess
        .filter(|n| n.is_finite() && *n >= 0.0)
        .map_or(1.0, |ns| {
            let alpha = (2.0 / (ns + 2.0)).sqrt();
            alpha.sqrt()
        });
    let ior = match m.optical_density {
        Some(ni) if ni.is_finite() && ni >= 1.0 => ni,
        _ => 1.5,
    };
    let glass = matches!(m.illumination_model, Some(4 | 6 | 7 | 9));
    let dissolve = m
        .dissolve
        .filter(|d| d.is_finite())
        .unwrap_or(1.0)
        .clamp(0.0, 1.0);
    let mut material = Material {
        name: m.name.clone(),
        emission: ke,
        roughness,
        ior,
        double_sided: true,
        ..Material::diffuse(&m.name, kd)
    };
    if glass {
        material.base_color = glam::Vec4::ONE;
        material.transmission = 1.0;
        material.thin_walled = false;
        material.specular = 1.0;
    } else if ks.max_element() > 0.0 {
        if kd.max_element() == 0.0 {
            material.metallic = 1.0;
            material.base_color = ks.extend(1.0);
        } else {
            let strength = ks.max_element();
            material.specular = strength.min(1.0);
            material.specular_color = ks / strength;
        }
    }
    if dissolve < 1.0 && !glass {
        material.transmission = 1.0 - dissolve;
        material.specular = material.specular.max(1.0);
    }
    if let Some(texture) = &m.diffuse_texture {
        material.base_color_texture = Some(load_texture(builder, folder, texture)?);
    }
    let ignored = [
        ("map_Ks", &m.specular_texture),
        ("map_Bump / norm", &m.normal_texture),
        ("map_Ns", &m.shininess_texture),
        ("map_d", &m.dissolve_texture),
    ];
    for (name, texture) in ignored {
        if texture.is_some() {
            builder.warn(format!(
                "{}: {name} textures are not supported and are ignored",
                path.display()
            ));
        }
    }
    Ok(material)
}

/// Loads `map_Kd` (sRGB) relative to the OBJ's folder.
fn load_texture(
    builder: &mut SceneBuilder,
    folder: &SceneFolder,
    name: &str,
) -> Result<TextureRef, SceneError> {
    let path = builder.path().to_path_buf();
    let texture_error = |reason: String| SceneError::Texture {
        path: path.clone(),
        texture: name.to_string(),
        reason,
    };
    let bytes = folder.read(name, Length::Whole).map_err(|e| match e {
        ReadError::Outside => SceneError::outside(builder.path(), name),
        ReadError::Failed(reason) => texture_error(reason),
    })?;
    let decoder = image_decoder(&bytes).map_err(texture_error)?;
    let (width, height) = image::ImageDecoder::dimensions(&decoder);
    builder.reserve_texels(name, width, height)?;
    let image = image::DynamicImage::from_decoder(decoder)
        .map_err(|e| texture_error(format!("cannot decode: {e}")))?;
    let index = builder.textures.len();
    builder.textures.push(Texture::from_image(
        name.to_string(),
        image,
        ColorEncoding::Srgb,
    ));
    Ok(TextureRef::new(index))
}
