//! `vcm_rs._native`: the Rust half of the Python package `vcm_rs` (the Python half, with the
//! documentation users read, is in `python/vcm_rs/`).
//!
//! - `scene`: `load_scene` and the `Scene` class.
//! - `request`: the keyword arguments of `render` and `render_state`, read and checked.
//! - `render`: `render` and `render_state`, run with the interpreter released.
//! - `state`: the `RenderState` class and `load_state`.
//! - `images`: arrays to and from images, EXR files and error metrics.
//! - `released`: running Rust work off the interpreter while Ctrl-C keeps working.

mod images;
mod released;
mod render;
mod request;
mod scene;
mod state;

use pyo3::prelude::*;

pyo3::create_exception!(
    vcm_rs,
    VcmError,
    pyo3::exceptions::PyException,
    "What vcm-rs could not do, with the reason: a scene or file it could not read, a render it \
     could not run, states it could not merge."
);

/// The extension module: its functions and classes, re-exported by `vcm_rs`.
#[pymodule]
fn _native(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add("VcmError", module.py().get_type::<VcmError>())?;
    module.add_class::<scene::Scene>()?;
    module.add_class::<state::RenderState>()?;
    module.add_function(wrap_pyfunction!(scene::load_scene, module)?)?;
    module.add_function(wrap_pyfunction!(render::render, module)?)?;
    module.add_function(wrap_pyfunction!(render::render_state, module)?)?;
    module.add_function(wrap_pyfunction!(state::load_state, module)?)?;
    module.add_function(wrap_pyfunction!(images::write_exr, module)?)?;
    module.add_function(wrap_pyfunction!(images::read_exr, module)?)?;
    module.add_function(wrap_pyfunction!(images::rmse, module)?)?;
    module.add_function(wrap_pyfunction!(images::relmse, module)?)?;
    Ok(())
}

/// A [`VcmError`] carrying `error`'s message with its causes.
fn vcm_error(error: impl std::fmt::Display) -> PyErr {
    VcmError::new_err(format!("{error:#}"))
}
