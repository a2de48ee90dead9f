//! `geltip.localise`, `geltip.load_image` and `geltip.save_image`: finding a contact in a
//! frame, reading and writing frames.

use crate::convert::{detector_options, json_to_py, path_or_str, rgb_image};
use crate::errors::{detached, lib};
use crate::sensor::Sensor;
use geltip::localise::Method;
use numpy::{PyArray, PyArray3, PyArrayMethods};
use pyo3::prelude::*;

/// Finds the contact in `image` against `reference` (both (H, W, 3) uint8 of the sensor's
/// size): `{"detected", "pixel", "point", "region", "confidence", "regions_found", "note"}`,
/// as `geltip localise` prints. `threshold` and `noise`: the change method's decision
/// threshold and the sensor's noise (as `--threshold` and `--noise`); `area_mm2`: (min, max)
/// of the contact's area on the finger, change and paper methods (as `--area-mm2`).
#[pyfunction]
#[allow(clippy::too_many_arguments)] // The keyword arguments of geltip.localise, one each.
#[pyo3(signature = (sensor, reference, image, method = "change", threshold = None, noise = None, area_mm2 = None))]
pub fn localise<'py>(
    py: Python<'py>,
    sensor: &Bound<'py, Sensor>,
    reference: &Bound<'py, PyAny>,
    image: &Bound<'py, PyAny>,
    method: &str,
    threshold: Option<f64>,
    noise: Option<f64>,
    area_mm2: Option<(f64, f64)>,
) -> PyResult<Bound<'py, PyAny>> {
    let s = sensor.get();
    let options = detector_options(threshold, noise, area_mm2)?;
    let method = lib(Method::from_name(method))?;
    let reference = rgb_image("reference", reference)?;
    let image = rgb_image("image", image)?;
    let detection = detached(py, "localising", || {
        s.localiser
            .localise_with(&reference, &image, method, &options)
    })?;
    json_to_py(py, &detection.to_json())
}

/// Reads an image file (PNG) as an (H, W, 3) uint8 array.
#[pyfunction]
pub fn load_image<'py>(
    py: Python<'py>,
    path: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let path = path_or_str("path", path)?;
    let img = detached(py, "reading an image", || {
        geltip::localise::load_image(&path)
    })?;
    let (w, h) = img.dimensions();
    PyArray::from_vec(py, img.into_raw()).reshape([h as usize, w as usize, 3])
}

/// Writes an (H, W, 3) uint8 array as a PNG file, atomically (to a temporary name in the
/// same folder, then renamed), with the encoder `geltip dataset` uses.
#[pyfunction]
pub fn save_image(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    image: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let path = path_or_str("path", path)?;
    let image = rgb_image("image", image)?;
    detached(py, "writing an image", || {
        geltip::output::write_png_rgb8(
            std::path::Path::new(&path),
            image.width(),
            image.height(),
            image.as_raw(),
        )
    })
}
