//! Scene file loaders. glTF 2.0 is the canonical format; Wavefront OBJ/MTL is mapped onto the
//! same material model (see [`obj`] for the mapping).
//!
//! A scene file is treated as untrusted input: what it may make the loader do (how many
//! triangles its instancing may create, whether it may read files outside its folder) is
//! bounded by [`LoadOptions`]; only regular files are read, never more of them than they hold
//! or the scene declares; and nothing a file says makes the loader panic.

mod builder;
mod files;
mod gltf;
pub mod obj;
mod options;
mod uri;

use std::io::Read;
use std::path::Path;

pub use options::LoadOptions;

use crate::error::SceneError;
use crate::scene::Scene;

/// Loads a scene with the default [`LoadOptions`], choosing the format from the file
/// extension (`.gltf`, `.glb`, `.obj`).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_with(path, &LoadOptions::default())
}

/// Loads a scene within `options`, choosing the format from the file extension (`.gltf`,
/// `.glb`, `.obj`).
pub fn load_with(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("gltf") | Some("glb") => {
            let bytes = read_scene_file(path).map_err(|reason| SceneError::Io {
                path: path.to_path_buf(),
                reason,
            })?;
            gltf::load_gltf_bytes(path, &bytes, options)
        }
        Some("obj") => obj::load_obj_with(path, options),
        _ => Err(SceneError::UnknownFormat {
            path: path.to_path_buf(),
        }),
    }
}

/// The bytes of the scene file itself, if it is a regular file.
fn read_scene_file(path: &Path) -> std::io::Result<Vec<u8>> {
    let (file, length) = files::open_regular_file(path)?;
    let mut bytes = Vec::new();
    file.take(length).read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// Loads a glTF document (JSON or binary) from memory with the default [`LoadOptions`];
/// external files are resolved relative to `path`'s folder and errors name `path`.
pub fn load_gltf_from_bytes(path: &Path, bytes: &[u8]) -> Result<Scene, SceneError> {
    load_gltf_from_bytes_with(path, bytes, &LoadOptions::default())
}

/// [`load_gltf_from_bytes`] within `options`.
pub fn load_gltf_from_bytes_with(
    path: &Path,
    bytes: &[u8],
    options: &LoadOptions,
) -> Result<Scene, SceneError> {
    gltf::load_gltf_bytes(path, bytes, options)
}

#[cfg(test)]
mod tests;
