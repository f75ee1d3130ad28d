//! The glTF 2.0 loader (`.gltf` with external or embedded buffers, and `.glb`).

mod accessors;
mod environment;
mod extension_json;
mod geometry;
mod instancing;
mod materials;
mod texture_transform;

use std::path::Path;
use std::sync::Arc;

use glam::{Mat4, Vec3};
use gltf::khr_lights_punctual::Kind as LightKind;

use crate::camera::{Camera, FileCamera};
use crate::error::SceneError;
use crate::light::{Light, PointLight, SpotLight};
use crate::loader::builder::SceneBuilder;
use crate::loader::files::{Length, ReadError, SceneFolder};
use crate::loader::options::LoadOptions;
use crate::loader::uri::read_uri;
use crate::material::Material;
use crate::scene::Scene;
use materials::{TextureLoader, read_material};

/// Extensions whose meaning the loader implements (see the scene conventions).
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    texture_transform::EXTENSION,
    environment::EXTENSION,
];

/// The widest and the tallest a camera's `aspectRatio` may make the image: 16 : 1 either
/// way. An image's height follows from its width and this ratio where the output size gives
/// none, so a ratio of 10⁻⁶ would ask for an image a million times taller than wide; beyond
/// 16 : 1 (wider than cinema's 2.76 : 1 and most panoramas) the ratio is ignored, with a
/// warning, and the output size decides.
const MAX_ASPECT_RATIO: f32 = 16.0;

/// Parses a glTF document from `bytes`; `path` names it in messages and locates external files.
pub(super) fn load_gltf_bytes(
    path: &Path,
    bytes: &[u8],
    options: &LoadOptions,
) -> Result<Scene, SceneError> {
    let (document, blob) = parse_document(bytes).map_err(|e| SceneError::gltf(path, e))?;
    let document = &document;
    let mut builder = SceneBuilder::new(path, options);
    for extension in document.extensions_required() {
        if !SUPPORTED_EXTENSIONS.contains(&extension) {
            let reason = format!("requires the unsupported extension {extension}");
            return Err(SceneError::gltf(path, reason));
        }
    }
    for extension in document.extensions_used() {
        if !SUPPORTED_EXTENSIONS.contains(&extension) {
            builder.warn(format!(
                "{}: extension {extension} is not supported and is ignored",
                path.display()
            ));
        }
    }
    let roots: Vec<usize> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => scene.nodes().map(|n| n.index()).collect(),
        None => root_nodes(document),
    };
    // What the hierarchy expands to is checked before anything is read for it.
    let instances = instancing::instance_counts(document, &roots)
        .map_err(|reason| SceneError::gltf(path, reason))?;
    instancing::check_expansion(document, &instances, options)
        .map_err(|reason| SceneError::too_large(path, reason))?;
    let folder = SceneFolder::of(path, options);
    let buffers = load_buffers(path, &folder, document, blob.as_deref())?;

    let mut textures = TextureLoader::new(&folder, &buffers);
    let mut texture_coordinate_sets = Vec::new();
    for material in document.materials() {
        let (m, set) = read_material(&mut builder, &mut textures, &material)?;
        builder.materials.push(m);
        texture_coordinate_sets.push(set);
    }
    // Primitives without a material use the glTF default material, appended last.
    let default_material = builder.materials.len() as u32;
    builder.materials.push(Material::default());
    texture_coordinate_sets.push(0);

    let mut reader = NodeReader {
        builder: &mut builder,
        buffers: &buffers,
        texture_coordinate_sets: &texture_coordinate_sets,
        default_material,
    };
    reader.visit(document, &roots)?;
    let environment = environment::read(document.extension_value(environment::EXTENSION))
        .map_err(|e| SceneError::gltf(path, e))?;
    if let Some(sky) = environment {
        let map = match &sky.image {
            None => None,
            Some(uri) => Some(Arc::new(environment::load_map(&folder, uri).map_err(
                |e| match e {
                    ReadError::Outside => SceneError::outside(path, uri),
                    ReadError::Failed(reason) => SceneError::gltf(path, reason),
                },
            )?)),
        };
        builder.set_environment(sky.radiance, map);
    }
    Ok(builder.finish())
}

/// Parses and validates a glTF document (JSON or GLB), returning it with the GLB binary chunk.
///
/// `gltf-json` 1.4.1's validation indexes a primitive's POSITION accessor without a bounds check,
/// and `gltf::Image::source` unwraps an image's `uri` (or, for one in a buffer view, its
/// `mimeType`) that validation does not require (both found by fuzzing): those are checked here.
fn parse_document(bytes: &[u8]) -> Result<(gltf::Document, Option<Vec<u8>>), String> {
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(describe)?;
    let root = gltf.document.into_json();
    let accessor_count = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(index) = primitive.attributes.get(&position)
                && index.value() >= accessor_count
            {
                return Err(format!(
                    "mesh {m} primitive {p}: POSITION refers to missing accessor {}",
                    index.value()
                ));
            }
        }
    }
    for (i, image) in root.images.iter().enumerate() {
        match (&image.buffer_view, &image.uri, &image.mime_type) {
            (None, None, _) => return Err(format!("image {i} has neither a uri nor a bufferView")),
            (Some(_), _, None) => {
                return Err(format!("image {i} is in a bufferView and needs a mimeType"));
            }
            _ => {}
        }
    }
    let document = gltf::Document::from_json(root).map_err(describe)?;
    Ok((document, gltf.blob))
}

/// The `gltf` crate's error in words, without the "invalid glTF:" that its validation errors
/// start with (the caller's [`SceneError::Gltf`] says that already).
fn describe(error: gltf::Error) -> String {
    match error {
        gltf::Error::Validation(errors) => {
            let errors: Vec<String> = errors
                .iter()
                .map(|(path, error)| format!("{path}: {error}"))
                .collect();
            errors.join("; ")
        }
        other => other.to_string(),
    }
}

/// Nodes that are nobody's child (used when the file has no scene).
fn root_nodes(document: &gltf::Document) -> Vec<usize> {
    let mut is_child = vec![false; document.nodes().count()];
    for node in document.nodes() {
        for child in node.children() {
            is_child[child.index()] = true;
        }
    }
    (0..is_child.len()).filter(|&n| !is_child[n]).collect()
}

/// Loads every buffer: external files, data URIs, or the GLB binary chunk; each holds its
/// declared `byteLength`, and no more is read from a file than that.
fn load_buffers(
    path: &Path,
    folder: &SceneFolder,
    document: &gltf::Document,
    blob: Option<&[u8]>,
) -> Result<Vec<Vec<u8>>, SceneError> {
    document
        .buffers()
        .map(|buffer| {
            let declared = buffer.length();
            let failed =
                |reason| SceneError::gltf(path, format!("buffer {}: {reason}", buffer.index()));
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => blob
                    .map(<[u8]>::to_vec)
                    .ok_or_else(|| failed("refers to a missing GLB binary chunk".to_string()))?,
                gltf::buffer::Source::Uri(uri) => {
                    read_uri(folder, uri, Length::Declared(declared as u64)).map_err(
                        |e| match e {
                            ReadError::Outside => SceneError::outside(path, uri),
                            ReadError::Failed(reason) => failed(reason),
                        },
                    )?
                }
            };
            if data.len() < declared {
                return Err(failed(format!(
                    "holds {} bytes but declares {declared}",
                    data.len()
                )));
            }
            Ok(data)
        })
        .collect()
}

/// Walks the node hierarchy, reading meshes, cameras and punctual lights.
struct NodeReader<'a> {
    builder: &'a mut SceneBuilder,
    buffers: &'a [Vec<u8>],
    /// Per material, the texture coordinate set its primitives are read with.
    texture_coordinate_sets: &'a [u32],
    default_material: u32,
}

impl NodeReader<'_> {
    /// Visits every node instance under `roots` depth first, children in order, with an
    /// explicit stack: a chain of nodes may be deeper than the call stack. The hierarchy has
    /// no cycle and its expansion is bounded ([`instancing`] checked both).
    fn visit(&mut self, document: &gltf::Document, roots: &[usize]) -> Result<(), SceneError> {
        let path = self.builder.path().to_path_buf();
        let nodes: Vec<gltf::Node> = document.nodes().collect();
        let mut stack: Vec<(usize, Mat4)> =
            roots.iter().rev().map(|&n| (n, Mat4::IDENTITY)).collect();
        while let Some((index, parent)) = stack.pop() {
            let node = &nodes[index];
            let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
            if !world.is_finite() {
                let reason = format!("node {} has a non-finite transform", node.index());
                return Err(SceneError::gltf(&path, reason));
            }
            if let Some(mesh) = node.mesh() {
                if node.skin().is_some() {
                    let feature = "skinning (meshes are rendered in their bind pose)";
                    self.builder.warn_unsupported(feature);
                }
                self.read_mesh(&mesh, world)?;
            }
            if let Some(camera) = node.camera() {
                self.read_camera(&camera, node.name(), world)?;
            }
            if let Some(light) = node.light() {
                self.read_light(&light, world)?;
            }
            let first = stack.len();
            stack.extend(node.children().map(|child| (child.index(), world)));
            stack[first..].reverse();
        }
        Ok(())
    }

    fn read_mesh(&mut self, mesh: &gltf::Mesh, world: Mat4) -> Result<(), SceneError> {
        let mesh_name = mesh
            .name()
            .map_or(format!("mesh {}", mesh.index()), |n| format!("mesh '{n}'"));
        for primitive in mesh.primitives() {
            let name = format!("{mesh_name} primitive {}", primitive.index());
            if primitive.morph_targets().len() > 0 {
                self.builder
                    .warn_unsupported("morph targets (meshes keep their base shape)");
            }
            let material = primitive
                .material()
                .index()
                .map_or(self.default_material, |i| i as u32);
            let set = self.texture_coordinate_sets[material as usize];
            let read = geometry::read_primitive(
                &primitive,
                name.clone(),
                world,
                self.buffers,
                (material, set),
            )
            .map_err(|reason| SceneError::geometry(self.builder.path(), &name, reason))?;
            match read {
                Some(p) => self.builder.add_primitive(p)?,
                None => {
                    let message = format!(
                        "{}: {name}: {:?} primitives are not supported and are skipped",
                        self.builder.path().display(),
                        primitive.mode()
                    );
                    self.builder.warn(message);
                }
            }
        }
        Ok(())
    }

    /// Reads a camera a node places. An `aspectRatio` ≤ 0 or non-finite is an error (no
    /// image has that shape); one beyond [`MAX_ASPECT_RATIO`] is ignored with a warning.
    fn read_camera(
        &mut self,
        camera: &gltf::Camera,
        node: Option<&str>,
        world: Mat4,
    ) -> Result<(), SceneError> {
        match camera.projection() {
            gltf::camera::Projection::Perspective(p) => {
                let aspect_ratio = match p.aspect_ratio() {
                    Some(a) if !(a.is_finite() && a > 0.0) => {
                        let reason = format!(
                            "camera {} has aspectRatio {a} (must be a finite number > 0)",
                            camera.index()
                        );
                        return Err(SceneError::gltf(self.builder.path(), reason));
                    }
                    Some(a) if !(1.0 / MAX_ASPECT_RATIO..=MAX_ASPECT_RATIO).contains(&a) => {
                        let message = format!(
                            "{}: camera {} has aspectRatio {a}, beyond {MAX_ASPECT_RATIO} : 1 \
                             either way; it is ignored (the output size sets the image's shape)",
                            self.builder.path().display(),
                            camera.index()
                        );
                        self.builder.warn(message);
                        None
                    }
                    a => a,
                };
                let placed = Camera::from_transform(world, p.yfov(), aspect_ratio);
                if let Some(placed) = placed {
                    self.builder.cameras.push(FileCamera {
                        index: camera.index(),
                        name: camera.name().map(str::to_string),
                        node: node.map(str::to_string),
                        camera: placed,
                    });
                } else {
                    let message = format!(
                        "{}: camera {} has a degenerate transform or field of view; it is ignored",
                        self.builder.path().display(),
                        camera.index()
                    );
                    self.builder.warn(message);
                }
            }
            gltf::camera::Projection::Orthographic(_) => {
                let message = format!(
                    "{}: orthographic cameras are not supported; camera {} is ignored",
                    self.builder.path().display(),
                    camera.index()
                );
                self.builder.warn(message);
            }
        }
        Ok(())
    }

    fn read_light(
        &mut self,
        light: &gltf::khr_lights_punctual::Light,
        world: Mat4,
    ) -> Result<(), SceneError> {
        let value = Vec3::from(light.color()) * light.intensity();
        let position = world.w_axis.truncate();
        let direction = (-world.z_axis.truncate()).normalize_or_zero();
        let path = self.builder.path().to_path_buf();
        let invalid =
            |reason: &str| SceneError::gltf(&path, format!("light {} {reason}", light.index()));
        if !value.is_finite() || value.min_element() < 0.0 {
            return Err(invalid("has a negative or non-finite intensity"));
        }
        if light.range().is_some() {
            let message = format!(
                "{}: light range cut-offs are ignored (lights follow the inverse square law)",
                self.builder.path().display()
            );
            self.builder.warn(message);
        }
        match light.kind() {
            LightKind::Point => self.builder.add_light(Light::Point(PointLight {
                position,
                intensity: value,
            })),
            LightKind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                let valid = direction != Vec3::ZERO
                    && (0.0..=std::f32::consts::FRAC_PI_2).contains(&outer_cone_angle)
                    && (0.0..=outer_cone_angle).contains(&inner_cone_angle);
                if !valid {
                    return Err(invalid("has an invalid direction or cone angles"));
                }
                self.builder.add_light(Light::Spot(SpotLight {
                    position,
                    direction,
                    intensity: value,
                    cos_inner: inner_cone_angle.cos(),
                    cos_outer: outer_cone_angle.cos(),
                }));
            }
            LightKind::Directional => {
                if direction == Vec3::ZERO {
                    return Err(invalid("has a degenerate direction"));
                }
                self.builder.add_directional(direction, value);
            }
        }
        Ok(())
    }
}
