//! The keyword arguments of `render` and `render_state`: read, checked and turned into the
//! library's settings, with errors that name the argument.

use clap::ValueEnum;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use vcm_rs::integrators::{
    Algorithm, AlgorithmOption, IntegratorOptions, MergeRadius, SamplerKind, image_size,
};
use vcm_rs::render_loop::{Budget, ScheduleOptions};
use vcm_rs::state::{RenderSettings, SETTING_OPTIONS};
use vcm_rs::{Backend, Shading};

use crate::scene::Scene;

/// The keyword arguments of `render` and `render_state` besides the settings' own
/// ([`SETTING_OPTIONS`] but the camera, which the scene carries).
const OTHER_KEYWORDS: [&str; 8] = [
    "spp",
    "time",
    "backend",
    "shading",
    "spp_per_frame",
    "scheduler",
    "tile_size",
    "progress",
];

/// Samples per pixel when neither `spp` nor `time` is given (as `vcm render`).
const DEFAULT_SPP: u32 = 16;

/// Image width when none is given (as `vcm render`).
const DEFAULT_WIDTH: u32 = 512;

/// A render as the keyword arguments ask for it.
pub struct Request {
    /// `algo`: one algorithm, or `auto`.
    pub algorithm: AlgorithmOption,
    /// (width, height) of the image in pixels.
    pub size: (u32, u32),
    /// The file's camera rendered from (`None`: the default).
    pub camera: Option<String>,
    /// Seed, sampler, path length, connections, merge radius and its reduction, pruning.
    pub options: IntegratorOptions,
    /// How the work is scheduled.
    pub schedule: ScheduleOptions,
    /// Where rays are traced.
    pub backend: Backend,
    /// Where paths are shaded.
    pub shading: Shading,
    /// `spp`, if given.
    pub spp: Option<u32>,
    /// `time` in seconds, if given.
    pub time: Option<f64>,
    /// Called with the progress while rendering.
    pub progress: Option<Py<PyAny>>,
}

impl Request {
    /// Reads `kwargs` for a render of `scene`: unknown names are a `TypeError`, values of the
    /// wrong type a `TypeError` and values out of range a `ValueError`, each naming the
    /// argument.
    pub fn from_kwargs(scene: &Scene, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Request> {
        let mut algorithm = AlgorithmOption::Auto;
        let mut width = DEFAULT_WIDTH;
        let mut height = None;
        let mut options = IntegratorOptions::default();
        let mut schedule = ScheduleOptions::default();
        let mut backend = Backend::Cpu;
        let mut shading = Shading::Cpu;
        let (mut spp, mut time, mut progress) = (None, None, None);
        for (key, value) in kwargs.into_iter().flatten() {
            let key: String = key.extract()?;
            let key = key.as_str();
            let value = &value;
            match key {
                "algo" => algorithm = choice(key, value)?,
                "spp" => spp = Some(positive(key, value)?),
                "time" => time = Some(seconds(key, value)?),
                "width" => width = positive(key, value)?,
                "height" => height = optional(value, |v| positive(key, v))?,
                "seed" => options.seed = value_as(key, value)?,
                "sampler" => options.sampler = choice::<SamplerKind>(key, value)?,
                "max_depth" => options.max_depth = optional(value, |v| positive(key, v))?,
                "connections" => options.connections = value_as(key, value)?,
                "light_paths" => options.light_paths = light_paths(key, value)?,
                "radius" => options.radius = merge_radius(key, value)?,
                "alpha" => options.alpha = value_as(key, value)?,
                "no_prune" => options.no_prune = value_as(key, value)?,
                "backend" => backend = choice(key, value)?,
                "shading" => shading = choice(key, value)?,
                "spp_per_frame" => schedule.spp_per_frame = optional(value, |v| positive(key, v))?,
                "scheduler" => schedule.scheduler = optional(value, |v| choice(key, v))?,
                "tile_size" => schedule.tile_size = optional(value, |v| positive(key, v))?,
                "progress" if value.is_callable() => progress = Some(value.clone().unbind()),
                "progress" => {
                    return Err(PyTypeError::new_err(
                        "progress: expected a function of (done, total)",
                    ));
                }
                _ => {
                    let keywords = SETTING_OPTIONS.iter().filter(|&&k| k != "camera");
                    let keywords: Vec<&str> = keywords.chain(&OTHER_KEYWORDS).copied().collect();
                    return Err(PyTypeError::new_err(format!(
                        "unexpected keyword argument '{key}' (the keywords are {})",
                        keywords.join(", ")
                    )));
                }
            }
        }
        if spp.is_some() && time.is_some() {
            return Err(PyValueError::new_err(
                "give spp (samples per pixel) or time (seconds), not both",
            ));
        }
        if shading == Shading::Gpu && backend != Backend::Gpu {
            return Err(PyValueError::new_err(
                "shading: \"gpu\" shades on the GPU backend's device: give backend=\"gpu\" too",
            ));
        }
        Ok(Request {
            algorithm,
            size: image_size(&scene.data, width, height),
            camera: scene.camera.clone(),
            options,
            schedule,
            backend,
            shading,
            spp,
            time,
            progress,
        })
    }

    /// What the estimator computes, rendered with `algorithm` (the request's, or the one
    /// `algo="auto"` chose): the image a seed gives depends on these only.
    pub fn settings(&self, algorithm: Algorithm) -> RenderSettings {
        let (width, height) = self.size;
        RenderSettings {
            algorithm,
            width,
            height,
            camera: self.camera.clone(),
            options: self.options.clone(),
        }
    }

    /// The budget `spp` or `time` give (16 samples per pixel when neither is given).
    pub fn budget(&self) -> Budget {
        match (self.spp, self.time) {
            (_, Some(seconds)) => Budget::Seconds(seconds),
            (spp, None) => Budget::Samples(spp.unwrap_or(DEFAULT_SPP)),
        }
    }
}

/// `value` as a `T`; a conversion error names the argument `key` and keeps its class
/// (`TypeError` for another type, `OverflowError` or `ValueError` for a value out of range).
fn value_as<'py, T>(key: &str, value: &Bound<'py, PyAny>) -> PyResult<T>
where
    T: for<'a> FromPyObject<'a, 'py>,
    for<'a> <T as FromPyObject<'a, 'py>>::Error: Into<PyErr>,
{
    value.extract::<T>().map_err(|e| {
        let e: PyErr = e.into();
        let message = format!("{key}: {}", e.value(value.py()));
        if e.is_instance_of::<PyTypeError>(value.py()) {
            PyTypeError::new_err(message)
        } else {
            PyValueError::new_err(message)
        }
    })
}

/// `value` as a whole number of at least 1.
fn positive(key: &str, value: &Bound<'_, PyAny>) -> PyResult<u32> {
    let n: i64 = value_as(key, value)?;
    u32::try_from(n).ok().filter(|&n| n >= 1).ok_or_else(|| {
        PyValueError::new_err(format!("{key}: must be from 1 to 4294967295, not {n}"))
    })
}

/// `value` as a number of light paths per pixel, within the range the integrator takes
/// (`vcm::light_paths_per_pixel`).
fn light_paths(key: &str, value: &Bound<'_, PyAny>) -> PyResult<f32> {
    let n: f32 = value_as(key, value)?;
    vcm_rs::vcm::light_paths_per_pixel(n).map_err(|e| PyValueError::new_err(format!("{key}: {e}")))
}

/// `value` as a merge radius: a number (a fraction of the scene's radius) or a text as
/// `vcm render --radius` reads it (`"2px"`: pixel footprints).
fn merge_radius(key: &str, value: &Bound<'_, PyAny>) -> PyResult<MergeRadius> {
    let radius = match value.extract::<String>() {
        Ok(text) => text.parse(),
        Err(_) => MergeRadius::SceneFraction(value_as(key, value)?).validated(),
    };
    radius.map_err(|e| PyValueError::new_err(format!("{key}: {e}")))
}

/// `value` as a positive, finite number of seconds.
fn seconds(key: &str, value: &Bound<'_, PyAny>) -> PyResult<f64> {
    let seconds: f64 = value_as(key, value)?;
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(PyValueError::new_err(format!(
            "{key}: must be a positive number of seconds, not {seconds}"
        )));
    }
    Ok(seconds)
}

/// `None` for Python's `None`, else `read(value)`.
fn optional<'py, T>(
    value: &Bound<'py, PyAny>,
    read: impl FnOnce(&Bound<'py, PyAny>) -> PyResult<T>,
) -> PyResult<Option<T>> {
    if value.is_none() {
        Ok(None)
    } else {
        read(value).map(Some)
    }
}

/// `value` as one of the names of `T`'s values (as on the command line).
fn choice<T: ValueEnum>(key: &str, value: &Bound<'_, PyAny>) -> PyResult<T> {
    let name: String = value_as(key, value)?;
    T::from_str(&name, true).map_err(|_| {
        let names: Vec<String> = T::value_variants()
            .iter()
            .filter_map(|v| v.to_possible_value())
            .map(|v| v.get_name().to_string())
            .collect();
        PyValueError::new_err(format!(
            "{key}: unknown value '{name}' (one of {})",
            names.join(", ")
        ))
    })
}
