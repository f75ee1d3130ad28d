//! Scene file loaders. glTF 2.0 is the canonical format; Wavefront OBJ/MTL is mapped onto the
//! same material model (see [`obj`] for the mapping).

mod builder;
mod gltf;
pub mod obj;
mod uri;

use std::path::Path;

use crate::error::SceneError;
use crate::scene::Scene;

/// Loads a scene, choosing the format from the file extension (`.gltf`, `.glb`, `.obj`).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("gltf") | Some("glb") => {
            let bytes = std::fs::read(path).map_err(|reason| SceneError::Io {
                path: path.to_path_buf(),
                reason,
            })?;
            gltf::load_gltf_bytes(path, &bytes)
        }
        Some("obj") => obj::load_obj(path),
        _ => Err(SceneError::UnknownFormat {
            path: path.to_path_buf(),
        }),
    }
}

/// Loads a glTF document (JSON or binary) from memory; external files are resolved relative to
/// `path`'s folder and errors name `path`.
pub fn load_gltf_from_bytes(path: &Path, bytes: &[u8]) -> Result<Scene, SceneError> {
    gltf::load_gltf_bytes(path, bytes)
}
