//! Typed errors for scene loading. Every variant names the file and the problem.

use std::path::PathBuf;

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file (or one it references) could not be read.
    // The I/O error is part of the message, not an error source: a caller that prints the
    // chain of sources (`{:#}` of anyhow) would print it twice.
    #[error("{path}: cannot read file: {reason}")]
    Io {
        /// The file that could not be read.
        path: PathBuf,
        /// The underlying I/O error.
        reason: std::io::Error,
    },
    /// The extension is neither glTF (`.gltf`, `.glb`) nor OBJ (`.obj`).
    #[error("{path}: unknown scene format (expected .gltf, .glb or .obj)")]
    UnknownFormat {
        /// The offending file.
        path: PathBuf,
    },
    /// The glTF document is malformed (broken JSON, invalid indices, bad buffers ...).
    #[error("{path}: invalid glTF: {reason}")]
    Gltf {
        /// The glTF file.
        path: PathBuf,
        /// What is wrong, in words.
        reason: String,
    },
    /// The OBJ or MTL file is malformed.
    #[error("{path}: invalid OBJ: {reason}")]
    Obj {
        /// The OBJ file.
        path: PathBuf,
        /// What is wrong, in words.
        reason: String,
    },
    /// A texture image is missing or cannot be decoded.
    #[error("{path}: texture {texture}: {reason}")]
    Texture {
        /// The scene file that references the texture.
        path: PathBuf,
        /// The texture's URI or name.
        texture: String,
        /// What is wrong, in words.
        reason: String,
    },
    /// The camera asked for is not among the file's cameras.
    #[error("{path}: no camera '{choice}': {reason}")]
    Camera {
        /// The scene file.
        path: PathBuf,
        /// The index or name asked for.
        choice: String,
        /// The cameras there are, in words.
        reason: String,
    },
    /// The scene needs more than the [`LoadOptions`](crate::loader::LoadOptions) allow
    /// (triangles or vertices once instanced, node instances).
    #[error("{path}: {reason}")]
    TooLarge {
        /// The scene file.
        path: PathBuf,
        /// What it would need and what is allowed, in words.
        reason: String,
    },
    /// A URI or file name in the scene leads outside the scene file's folder, which the
    /// [`LoadOptions`](crate::loader::LoadOptions) do not allow. Nothing outside was opened,
    /// so the message says nothing about the file itself.
    #[error(
        "{path}: '{name}' is outside the scene's folder; files there are read only where the \
         load options allow it"
    )]
    OutsideFolder {
        /// The scene file.
        path: PathBuf,
        /// The URI or file name as the scene writes it.
        name: String,
    },
    /// Geometry data is unusable (non-finite positions, indices out of range ...).
    #[error("{path}: {mesh}: {reason}")]
    Geometry {
        /// The scene file.
        path: PathBuf,
        /// Which mesh and primitive (e.g. `mesh 'Bottle' primitive 0`).
        mesh: String,
        /// What is wrong, in words.
        reason: String,
    },
}

impl SceneError {
    pub(crate) fn too_large(path: &std::path::Path, reason: impl Into<String>) -> Self {
        SceneError::TooLarge {
            path: path.to_path_buf(),
            reason: reason.into(),
        }
    }

    pub(crate) fn outside(path: &std::path::Path, name: &str) -> Self {
        SceneError::OutsideFolder {
            path: path.to_path_buf(),
            name: name.to_string(),
        }
    }

    pub(crate) fn gltf(path: &std::path::Path, reason: impl Into<String>) -> Self {
        SceneError::Gltf {
            path: path.to_path_buf(),
            reason: reason.into(),
        }
    }

    pub(crate) fn geometry(
        path: &std::path::Path,
        mesh: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        SceneError::Geometry {
            path: path.to_path_buf(),
            mesh: mesh.into(),
            reason: reason.into(),
        }
    }
}
