//! Images as NumPy arrays of shape (height, width, 3), EXR files, and error metrics.

use std::path::PathBuf;

use glam::Vec3;
use numpy::{PyArray1, PyArray3, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use vcm_rs::vcm::image_io::RgbImage;
use vcm_rs::vcm::metrics::{ErrorMetrics, compare};

use crate::vcm_error;

/// `image` as a float32 array of shape (height, width, 3); the array owns the pixels, which
/// are not copied again.
pub fn to_array<'py>(py: Python<'py>, image: &RgbImage) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let channels: Vec<f32> = image.pixels.iter().flat_map(|p| p.to_array()).collect();
    PyArray1::from_vec(py, channels).reshape([image.height, image.width, 3])
}

/// The image in `array`: float32 or float64, of shape (height, width, 3). `what` names the
/// argument in errors.
fn from_array(what: &str, array: &Bound<'_, PyAny>) -> PyResult<RgbImage> {
    fn read<T: numpy::Element + Copy + Into<f64>>(
        what: &str,
        array: PyReadonlyArray3<'_, T>,
    ) -> PyResult<RgbImage> {
        let shape = array.shape();
        if shape[2] != 3 || shape[0] == 0 || shape[1] == 0 {
            return Err(PyValueError::new_err(format!(
                "{what}: an image is an array of shape (height, width, 3), not {shape:?}"
            )));
        }
        let view = array.as_array();
        let pixels = view
            .outer_iter()
            .flat_map(|row| {
                row.outer_iter()
                    .map(|p| Vec3::new(p[0].into() as f32, p[1].into() as f32, p[2].into() as f32))
                    .collect::<Vec<_>>()
            })
            .collect();
        Ok(RgbImage {
            width: shape[1],
            height: shape[0],
            pixels,
        })
    }
    if let Ok(array) = array.extract::<PyReadonlyArray3<'_, f32>>() {
        read(what, array)
    } else if let Ok(array) = array.extract::<PyReadonlyArray3<'_, f64>>() {
        read(what, array)
    } else {
        Err(PyTypeError::new_err(format!(
            "{what}: expected a float32 or float64 NumPy array of shape (height, width, 3)"
        )))
    }
}

/// Writes an image (a float array of shape (height, width, 3), linear radiance) to an
/// OpenEXR file, through a temporary file renamed when complete.
///
/// Raises:
///     VcmError: the file cannot be written (the message says why).
#[pyfunction]
pub fn write_exr(py: Python<'_>, path: PathBuf, image: &Bound<'_, PyAny>) -> PyResult<()> {
    let image = from_array("image", image)?;
    py.detach(|| image.write_exr(&path)).map_err(vcm_error)
}

/// Reads an OpenEXR file's RGB channels as a float32 array of shape (height, width, 3).
///
/// Raises:
///     VcmError: the file cannot be read or is no RGB image (the message says why).
#[pyfunction]
pub fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let image = py.detach(|| RgbImage::read_exr(&path)).map_err(vcm_error)?;
    to_array(py, &image)
}

/// The error of `image` against `reference` (arrays of the same shape).
fn metrics(image: &Bound<'_, PyAny>, reference: &Bound<'_, PyAny>) -> PyResult<ErrorMetrics> {
    let image = from_array("image", image)?;
    let reference = from_array("reference", reference)?;
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(PyValueError::new_err(format!(
            "the image is {}×{} and the reference {}×{}",
            image.width, image.height, reference.width, reference.height
        )));
    }
    for (what, image) in [("image", &image), ("reference", &reference)] {
        let non_finite = image.pixels.iter().filter(|p| !p.is_finite()).count();
        if non_finite > 0 {
            return Err(PyValueError::new_err(format!(
                "{what}: {non_finite} pixels are not finite (NaN or infinite); an error \
                 measured over them would be meaningless"
            )));
        }
    }
    compare(&image.pixels, &reference.pixels)
        .ok_or_else(|| PyValueError::new_err("the images have different sizes"))
}

/// Root-mean-square error of `image` against `reference` over all pixels and channels.
#[pyfunction]
pub fn rmse(image: &Bound<'_, PyAny>, reference: &Bound<'_, PyAny>) -> PyResult<f64> {
    Ok(metrics(image, reference)?.rmse)
}

/// Relative mean squared error of `image` against `reference`: the mean over pixels and
/// channels of (I − R)² / (R² + 0.01) (what `vcm render --report` records).
#[pyfunction]
pub fn relmse(image: &Bound<'_, PyAny>, reference: &Bound<'_, PyAny>) -> PyResult<f64> {
    Ok(metrics(image, reference)?.relmse)
}
