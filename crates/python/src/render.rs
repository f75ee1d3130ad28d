//! `render` and `render_state`: a render run on its own thread with the interpreter
//! released, stopped cleanly by Ctrl-C, reporting its progress to an optional callback.

use std::ops::Range;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use numpy::PyArray3;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use vcm_rs::gpu::GpuRenderError;
use vcm_rs::integrators::Algorithm;
use vcm_rs::integrators::choice::{self, Pilots};
use vcm_rs::render_loop::{self, Budget, Frames};
use vcm_rs::state::RenderState as State;
use vcm_rs::vcm::{Film, StopFlag};

use crate::images;
use crate::released::run_released;
use crate::request::Request;
use crate::scene::Scene;
use crate::state::RenderState;
use crate::vcm_error;

/// Renders `scene` and returns the image: a float32 array of shape (height, width, 3),
/// linear radiance, rows from the top.
///
/// Keyword arguments (all optional):
///     algo: "auto" (default: the most efficient of pt, bpt and vcm for the scene, from
///         short pilot renders, as `vcm render` chooses), "pt", "lt", "bpt", "ppm", "bpm" or
///         "vcm".
///     spp: samples per pixel (iterations for the VCM family); default 16.
///     time: render for this many seconds instead (not with spp).
///     width: image width in pixels (default 512); height: default from the camera's aspect
///         ratio, else square.
///     seed: the seed of all random numbers (default 0): an image is a pure function of the
///         scene, the settings and the seed.
///     sampler: "sobol" (stratified, default) or "independent".
///     max_depth: most path segments (default: unlimited, with Russian roulette).
///     connections: light vertices each camera vertex connects to (bpt, vcm; default 1).
///     light_paths: light paths each iteration traces per pixel (lt, bpt, ppm, bpm, vcm;
///         1/16 to 16; default 1).
///     radius: initial merge radius (ppm, bpm, vcm): pixel footprints as a text ending in
///         `px` ("2px", the default) or a fraction of the scene's radius (0.003).
///     alpha: the merge radius's reduction exponent (ppm, bpm, vcm).
///     no_prune: run every part of the algorithm, even those the scene does not need.
///     backend: "cpu" (default) or "gpu" (WGSL compute shaders through wgpu).
///     shading: "cpu" (default) or "gpu": whole paths in WGSL kernels on the GPU
///         backend's device (needs backend="gpu"; "auto" means path tracing there).
///     spp_per_frame, scheduler ("none", "tile", "queue"), tile_size: how work is scheduled
///         (the image does not depend on them).
///     progress: a function called as progress(done, total) while rendering: samples per
///         pixel done and asked for, or with `time` seconds elapsed and asked for. With
///         tqdm: `bar = tqdm(total=64); render(scene, spp=64, progress=lambda n, _:
///         bar.update(n - bar.n))`.
///
/// The interpreter is released while rendering, so other Python threads run. Ctrl-C stops
/// the render within a tile and raises KeyboardInterrupt.
///
/// Raises:
///     TypeError, ValueError: an unknown keyword, or a value of the wrong type or out of
///         range (the message names the argument).
///     VcmError: the render cannot run (no GPU adapter for backend="gpu", an image too
///         large, …).
#[pyfunction]
#[pyo3(signature = (scene, **options))]
pub fn render<'py>(
    py: Python<'py>,
    scene: &Bound<'py, Scene>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let request = Request::from_kwargs(scene.get(), options)?;
    let (film, _, _) = run(py, scene.get(), &request, 0, request.budget())?;
    images::to_array(py, &film.image())
}

/// Renders the global samples `samples` (a `range`; iterations for the VCM family) of
/// `scene` and returns their state, to merge with the states of other samples, to save or
/// to turn into an image. Without `samples`, renders from sample 0 for `spp` samples or
/// `time` seconds. Takes the keyword arguments of `render`.
///
/// Raises:
///     as `render`; ValueError also for an empty range, a step other than 1, or `samples`
///     given together with `spp` or `time`.
#[pyfunction]
#[pyo3(signature = (scene, samples = None, **options))]
pub fn render_state<'py>(
    py: Python<'py>,
    scene: &Bound<'py, Scene>,
    samples: Option<&Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<RenderState> {
    let scene = scene.get();
    let request = Request::from_kwargs(scene, options)?;
    let (first, budget) = match samples {
        Some(_) if request.spp.is_some() || request.time.is_some() => {
            return Err(PyValueError::new_err(
                "give samples (a range of global samples) or spp or time, not both",
            ));
        }
        Some(range) => {
            let range = sample_range(range)?;
            (range.start, Budget::Samples(range.end - range.start))
        }
        None => (0, request.budget()),
    };
    let (film, spp, algorithm) = run(py, scene, &request, first, budget)?;
    let path = scene.data.path.clone();
    let mut state = State::new(request.settings(algorithm), scene.hash(), path);
    state.film = film;
    state.samples.insert(first..first + spp);
    if let (None, Budget::Samples(spp)) = (samples, budget) {
        state.target_spp = Some(spp);
    }
    Ok(RenderState(state))
}

/// A Python `range` of global samples: step 1, not empty, within 0..2³².
fn sample_range(range: &Bound<'_, PyAny>) -> PyResult<Range<u32>> {
    let read = |name: &str| -> PyResult<i64> {
        range
            .getattr(name)
            .and_then(|v| v.extract())
            .map_err(|_| PyTypeError::new_err("samples: expected a range, such as range(0, 64)"))
    };
    let (start, stop, step) = (read("start")?, read("stop")?, read("step")?);
    let bounded = |n: i64| u32::try_from(n).ok();
    match (bounded(start), bounded(stop)) {
        (Some(start), Some(stop)) if step == 1 && start < stop => Ok(start..stop),
        _ => Err(PyValueError::new_err(format!(
            "samples: range({start}, {stop}, {step}) is not a range of sample indices (step \
             1, not empty, from 0 to 4294967295)"
        ))),
    }
}

/// Renders `request` on `scene` from global sample `first` until `budget` is spent, on a
/// thread of its own (see [`run_released`]); the film, the samples per pixel rendered and
/// the algorithm (the one chosen, for `algo="auto"`).
fn run(
    py: Python<'_>,
    scene: &Scene,
    request: &Request,
    first: u32,
    budget: Budget,
) -> PyResult<(Film, u32, Algorithm)> {
    let size = request.size;
    let samples_left = budget.remaining(0, Duration::ZERO).samples;
    let built = py
        .detach(|| scene.traversal(request.backend))
        .map_err(vcm_error)?;
    let started = Instant::now();
    let stop = StopFlag::new();
    let algorithm = match request.algorithm.fixed() {
        Some(algorithm) => algorithm,
        // Pilots, stopped by Ctrl-C as a render is.
        None => {
            let options = &request.options;
            let pilots = Pilots::of(&built, request.shading).map_err(vcm_error)?;
            let choose = || choice::choose(&scene.data, pilots, size, options, &stop);
            run_released(py, &stop, |_| Ok(()), choose)?
                .map_err(vcm_error)?
                .algorithm
        }
    };
    let mut frames = Frames::new(request.schedule, request.backend).starting_at(first);
    let integrator = frames.shaded_integrator(
        (algorithm, request.shading),
        &scene.data,
        &built,
        size,
        &request.options,
        samples_left,
    );
    let mut integrator = integrator.map_err(|error| match error {
        GpuRenderError::Render(error) => PyValueError::new_err(error.to_string()),
        other => vcm_error(other),
    })?;
    // (samples per pixel, seconds) after the latest frame, and what was last reported.
    let latest = Mutex::new((0, 0.0));
    let mut reported = (0, 0.0);
    let report = |py: Python<'_>| -> PyResult<()> {
        let Some(callback) = &request.progress else {
            return Ok(());
        };
        let now = *latest.lock().unwrap_or_else(|e| e.into_inner());
        if now == reported {
            return Ok(());
        }
        reported = now;
        let (spp, seconds) = now;
        match budget {
            Budget::Samples(total) => callback.call1(py, (spp, total))?,
            Budget::Seconds(total) => callback.call1(py, (seconds, total))?,
        };
        Ok(())
    };
    let rendered = run_released(py, &stop, report, || {
        let mut film = Film::new(size.0, size.1);
        let rendered = render_loop::render(
            integrator.as_mut(),
            &mut frames,
            &mut film,
            (budget, started),
            &stop,
            |frame| {
                let now = (frame.spp, frame.elapsed.as_secs_f64());
                *latest.lock().unwrap_or_else(|e| e.into_inner()) = now;
                Ok(())
            },
        );
        rendered.and_then(|r| match r.failure {
            Some(failure) => Err(anyhow::anyhow!(failure)),
            None => Ok((film, r.spp, algorithm)),
        })
    })?;
    rendered.map_err(vcm_error)
}
