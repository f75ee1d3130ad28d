//! The `RenderState` class and `load_state`: a render's film and the samples it holds, to
//! save, resume, send to other processes and merge.

use std::path::PathBuf;

use numpy::PyArray3;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyRange};
use vcm_rs::state::RenderState as State;

use crate::{images, vcm_error};

/// A render's state: its film (exact sums per pixel), which global samples it holds, and the
/// scene and settings it was rendered with. Made by `vcm_rs.render_state` or
/// `vcm_rs.load_state`; the same file format as `vcm render --state` (safetensors).
///
/// States of the same scene and settings holding different samples merge exactly: merging
/// shards in any order gives the image one process rendering all the samples gives, bit for
/// bit. States pickle (as their file's bytes), so they travel between processes.
#[pyclass(module = "vcm_rs", name = "RenderState", frozen)]
pub struct RenderState(pub State);

#[pymethods]
impl RenderState {
    /// The global sample (iteration) ranges held, as a list of `range`s.
    #[getter]
    fn samples<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyRange>>> {
        let ranges = self.0.samples.ranges().iter();
        ranges
            .map(|r| PyRange::new(py, r.start as isize, r.end as isize))
            .collect()
    }

    /// Samples per pixel held.
    #[getter]
    fn spp(&self) -> u64 {
        self.0.samples.count()
    }

    /// Image width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.0.settings.width
    }

    /// Image height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.0.settings.height
    }

    /// The scene file it was rendered from.
    #[getter]
    fn scene_path(&self) -> PathBuf {
        self.0.scene_path.clone()
    }

    /// The settings that make the estimator, as text (the state file's metadata):
    /// algorithm, width, height, camera, seed, sampler, max_depth, connections, light_paths,
    /// radius, alpha, no_prune.
    fn settings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let settings = PyDict::new(py);
        for (key, value) in self.0.settings.to_metadata() {
            settings.set_item(key, value)?;
        }
        Ok(settings)
    }

    /// A new state holding the samples of both this state and `other`.
    ///
    /// Raises:
    ///     VcmError: the two come from other scenes or settings, or both hold some sample.
    fn merge(&self, other: &RenderState) -> PyResult<RenderState> {
        let mut merged = self.0.clone();
        merged
            .merge(&other.0, "this state", "the other state")
            .map_err(vcm_error)?;
        Ok(RenderState(merged))
    }

    /// The mean radiance per pixel: a float32 array of shape (height, width, 3).
    fn image<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        images::to_array(py, &self.0.image())
    }

    /// Writes the state file (through a temporary file renamed when complete); `vcm render
    /// --resume` and `vcm merge` read it.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| self.0.save(&path)).map_err(vcm_error)
    }

    /// The bytes of the state file.
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = py.detach(|| self.0.to_bytes()).map_err(vcm_error)?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// A state from the bytes of a state file, checked as `load_state` checks a file.
    #[staticmethod]
    fn from_bytes(py: Python<'_>, data: &[u8]) -> PyResult<RenderState> {
        let state = py
            .detach(|| State::from_bytes(data, "the render state's bytes"))
            .map_err(vcm_error)?;
        Ok(RenderState(state))
    }

    fn __repr__(&self) -> String {
        format!(
            "<vcm_rs.RenderState {} {}×{} samples {}>",
            self.0.settings.algorithm.name(),
            self.0.settings.width,
            self.0.settings.height,
            self.0.samples
        )
    }
}

/// Reads a render state file (written by `RenderState.save` or `vcm render --state`).
///
/// Raises:
///     VcmError: the file cannot be read, is no render state, or is damaged (the message
///         names the file and the problem).
#[pyfunction]
pub fn load_state(py: Python<'_>, path: PathBuf) -> PyResult<RenderState> {
    let state = py.detach(|| State::load(&path)).map_err(vcm_error)?;
    Ok(RenderState(state))
}
