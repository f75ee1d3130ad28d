//! `load_scene` and the `Scene` class: a loaded scene, its traversal structures built once
//! and kept for every render of it.

use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

use pyo3::prelude::*;
use pyo3::types::PyDict;
use vcm_rs::scene::{LoadOptions, Scene as SceneData};
use vcm_rs::state::scene_hash;
use vcm_rs::{Backend, BuiltTraversal, Traversals};

use crate::vcm_error;

/// A scene loaded from a glTF or OBJ file, rendered from one of its cameras.
///
/// Load one with `vcm_rs.load_scene(path)`. A scene can be rendered any number of times; the
/// ray traversal structure is built by the first render on each backend and kept.
#[pyclass(module = "vcm_rs", frozen)]
pub struct Scene {
    /// The scene itself, shared with the renders.
    pub data: Arc<SceneData>,
    /// The camera chosen when loading (`None`: the file's first).
    pub camera: Option<String>,
    /// The scene's content hash, computed when a state first needs it.
    hash: OnceLock<u64>,
    /// The traversal structures built so far, one per backend.
    traversals: Mutex<Traversals>,
}

impl Scene {
    /// The scene's content hash ([`scene_hash`]), computed once.
    pub fn hash(&self) -> u64 {
        *self.hash.get_or_init(|| scene_hash(&self.data))
    }

    /// The traversal structure of `backend` for this scene, built on first use, with the GPU
    /// backend's hierarchy (for shading on the GPU).
    pub fn traversal(&self, backend: Backend) -> anyhow::Result<BuiltTraversal> {
        let mut traversals = self.traversals.lock().unwrap_or_else(|e| e.into_inner());
        Ok(traversals.built(backend, |_| ())?.clone())
    }
}

#[pymethods]
impl Scene {
    /// The scene file.
    #[getter]
    fn path(&self) -> PathBuf {
        self.data.path.clone()
    }

    /// What the scene contains, as a dict: path, triangles, materials, textures, lights (by
    /// kind), cameras (their names), the camera rendered from, bounds, material classes,
    /// features (whether it has textures, alpha masks, normal maps, vertex colours,
    /// absorbing volumes) and the loader's warnings.
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let scene = &self.data;
        let features = &scene.features;
        let info = PyDict::new(py);
        info.set_item("path", scene.path.clone())?;
        info.set_item("triangles", features.triangles)?;
        info.set_item("dropped_triangles", scene.dropped_triangles)?;
        info.set_item("materials", scene.materials.len())?;
        info.set_item("textures", scene.textures.len())?;
        let counts = &features.lights;
        let lights = dict_of(
            py,
            [
                ("area", counts.area),
                ("point", counts.point),
                ("spot", counts.spot),
                ("directional", counts.directional),
                ("environment", counts.environment),
            ],
        )?;
        info.set_item("lights", lights)?;
        let cameras: Vec<String> = scene.cameras.iter().map(ToString::to_string).collect();
        info.set_item("cameras", cameras)?;
        info.set_item("camera", self.camera.clone())?;
        let bounds = features.bounds;
        info.set_item("bounds", (bounds.min.to_array(), bounds.max.to_array()))?;
        let classes = &features.materials;
        let material_classes = dict_of(
            py,
            [
                ("diffuse", classes.diffuse),
                ("glossy", classes.glossy),
                ("specular", classes.specular),
                ("near_specular", classes.near_specular),
                ("transmission", classes.transmission),
            ],
        )?;
        info.set_item("material_classes", material_classes)?;
        let present = dict_of(
            py,
            [
                ("textures", features.textures),
                ("alpha_masks", features.alpha_masks),
                ("normal_maps", features.normal_maps),
                ("vertex_colors", features.vertex_colors),
                ("absorbing_volumes", features.absorbing_volumes),
            ],
        )?;
        info.set_item("features", present)?;
        info.set_item("warnings", scene.warnings.clone())?;
        Ok(info)
    }

    fn __repr__(&self) -> String {
        format!(
            "<vcm_rs.Scene {} ({} triangles, {} lights)>",
            self.data.path.display(),
            self.data.features.triangles,
            self.data.lights.len()
        )
    }
}

/// A dict of `pairs`.
fn dict_of<'py, V: IntoPyObject<'py>>(
    py: Python<'py>,
    pairs: impl IntoIterator<Item = (&'static str, V)>,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for (key, value) in pairs {
        dict.set_item(key, value)?;
    }
    Ok(dict)
}

/// Loads a scene file (.gltf, .glb or .obj).
///
/// Args:
///     path: the scene file.
///     camera: the file's camera to render from, by its index in the glTF `cameras` array or
///         its name or its node's name (default: the first camera the file's nodes place).
///     max_triangles: most triangles the scene may expand to, every instance counted.
///     max_texels: most texels all of the scene's textures may decode to.
///     allow_outside_files: let the scene's URIs lead outside its folder.
///
/// Raises:
///     VcmError: the file cannot be read or is not a scene this renderer understands (the
///         message names the file and the problem), or it has no such camera.
#[pyfunction]
#[pyo3(signature = (
    path,
    camera = None,
    max_triangles = LoadOptions::DEFAULT_MAX_TRIANGLES,
    max_texels = LoadOptions::DEFAULT_MAX_TEXELS,
    allow_outside_files = false
))]
pub fn load_scene(
    py: Python<'_>,
    path: PathBuf,
    camera: Option<String>,
    max_triangles: u64,
    max_texels: u64,
    allow_outside_files: bool,
) -> PyResult<Scene> {
    let options = LoadOptions {
        max_triangles,
        max_texels,
        allow_outside_files,
    };
    let loaded = py.detach(|| -> anyhow::Result<SceneData> {
        let mut scene = SceneData::load_with(&path, &options)?;
        if let Some(choice) = &camera {
            scene.use_camera(choice)?;
        }
        Ok(scene)
    });
    let data = Arc::new(loaded.map_err(vcm_error)?);
    Ok(Scene {
        traversals: Mutex::new(Traversals::new(Arc::clone(&data))),
        data,
        camera,
        hash: OnceLock::new(),
    })
}
