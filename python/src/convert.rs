//! Conversions between Python objects and the library's types: JSON values, NumPy arrays
//! of images, depth maps, points and pixels, numbers and paths. A value of the wrong type or
//! shape is refused here (naming the argument); its contents are the library's to check.

use crate::errors::bad;
use geltip::render::Frame;
use numpy::{
    AllowTypeChange, PyArray, PyArray2, PyArray3, PyArrayLikeDyn, PyArrayMethods,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use serde_json::Value;
use std::path::PathBuf;

/// serde_json value -> Python object (dict, list, str, int, float, bool, None).
pub fn json_to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_pyobject(py)?.into_any()
            } else if let Some(u) = n.as_u64() {
                u.into_pyobject(py)?.into_any()
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any()
            }
        }
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(json_to_py(py, item)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, item) in map {
                dict.set_item(k, json_to_py(py, item)?)?;
            }
            dict.into_any()
        }
    })
}

/// A frame's RGB image as a new (H, W, 3) uint8 array.
pub fn image_array<'py>(py: Python<'py>, frame: &Frame) -> Bound<'py, PyArray3<u8>> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    // SAFETY: every element is written below before the array is handed to Python.
    let array = unsafe { PyArray3::<u8>::new(py, [h, w, 3], false) };
    // SAFETY: the array is new, C-contiguous and not yet visible to Python.
    let out = unsafe { std::slice::from_raw_parts_mut(array.data(), h * w * 3) };
    rgba_to_rgb(&frame.rgba, out);
    array
}

/// A frame's indentation as a new (H, W) float32 array.
pub fn depth_array<'py>(py: Python<'py>, frame: &Frame) -> Bound<'py, PyArray2<f32>> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    // SAFETY: as in `image_array`.
    let array = unsafe { PyArray2::<f32>::new(py, [h, w], false) };
    let out = unsafe { std::slice::from_raw_parts_mut(array.data(), h * w) };
    out.copy_from_slice(&frame.indentation);
    array
}

/// RGBA pixels into RGB ones (as many as both hold).
pub fn rgba_to_rgb(rgba: &[u8], rgb: &mut [u8]) {
    for (d, s) in rgb.chunks_exact_mut(3).zip(rgba.chunks_exact(4)) {
        d.copy_from_slice(&s[..3]);
    }
}

/// An (H, W, 3) uint8 array as an RGB image (whether its size suits a sensor is the
/// library's to say).
pub fn rgb_image(field: &str, value: &Bound<'_, PyAny>) -> PyResult<image::RgbImage> {
    let expected = "expected an (H, W, 3) uint8 array";
    let array = value
        .cast::<PyArray3<u8>>()
        .map_err(|_| bad(field, format!("{expected}, got {}", describe_array(value))))?;
    let shape = array.shape().to_vec();
    let size = (u32::try_from(shape[1]), u32::try_from(shape[0]));
    let (Ok(width), Ok(height), 3) = (size.0, size.1, shape[2]) else {
        return Err(bad(field, format!("{expected}, got shape {shape:?}")));
    };
    let readonly = array.readonly();
    let pixels: Vec<u8> = match readonly.as_slice() {
        Ok(s) => s.to_vec(),
        Err(_) => readonly.as_array().iter().copied().collect(),
    };
    image::RgbImage::from_raw(width, height, pixels)
        .ok_or_else(|| bad(field, "pixel buffer does not match its shape"))
}

/// "an array of shape (..) and dtype .." or "a <type>", for messages.
pub fn describe_array(value: &Bound<'_, PyAny>) -> String {
    let attr = |name: &str| {
        value
            .getattr(name)
            .ok()
            .map(|s| s.to_string())
            .unwrap_or_default()
    };
    let (shape, dtype) = (attr("shape"), attr("dtype"));
    if shape.is_empty() {
        let ty = value
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_default();
        format!("a {ty}")
    } else {
        format!("an array of shape {shape} and dtype {dtype}")
    }
}

/// A number argument (any real: int, float, NumPy scalar); its range is the library's to
/// check.
pub fn number(field: &str, value: &Bound<'_, PyAny>) -> PyResult<f64> {
    value
        .extract()
        .map_err(|_| bad(field, format!("expected a number, got {}", repr(value))))
}

/// A count argument (a whole number, 0 or more: int or NumPy integer); its range beyond
/// that is the library's to check.
pub fn count(field: &str, value: &Bound<'_, PyAny>) -> PyResult<usize> {
    value.extract().map_err(|_| {
        bad(
            field,
            format!("expected a whole number >= 0, got {}", repr(value)),
        )
    })
}

/// `repr(value)`, for messages.
pub fn repr(value: &Bound<'_, PyAny>) -> String {
    value
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// A `str` or `os.PathLike` argument.
pub fn path_or_str(field: &str, value: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(s) = value.extract::<String>() {
        return Ok(s);
    }
    value
        .extract::<PathBuf>()
        .map(|p| p.to_string_lossy().into_owned())
        .map_err(|_| {
            bad(
                field,
                format!("expected a str or a path, got {}", repr(value)),
            )
        })
}

/// Points (..., k) float64 from any array-like: the flat values and the leading shape.
pub fn points_in(
    field: &str,
    values: &Bound<'_, PyAny>,
    k: usize,
    what: &str,
) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let array: PyArrayLikeDyn<'_, f64, AllowTypeChange> = values.extract().map_err(|_| {
        bad(
            field,
            format!(
                "expected {what}: an array of shape (N, {k}) or ({k},) of numbers, got {}",
                describe_array(values)
            ),
        )
    })?;
    let shape = array.shape().to_vec();
    let ok =
        matches!(shape.as_slice(), [n] if *n == k) || matches!(shape.as_slice(), [_, n] if *n == k);
    if !ok {
        return Err(bad(
            field,
            format!("expected an array of shape (N, {k}) or ({k},), got shape {shape:?}"),
        ));
    }
    let flat: Vec<f64> = array.as_array().iter().copied().collect();
    Ok((flat, shape[..shape.len() - 1].to_vec()))
}

/// `values` as a float64 array of shape `lead + (k,)`.
pub fn array_out<'py>(
    py: Python<'py>,
    lead: &[usize],
    k: usize,
    values: Vec<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut shape = lead.to_vec();
    shape.push(k);
    Ok(PyArray::from_vec(py, values).reshape(shape)?.into_any())
}

/// `given` if there is one (checked: dtype, shape, C order), else a new uninitialised array
/// the caller fills completely.
pub fn output_array<'py, T: numpy::Element, D: numpy::ndarray::Dimension>(
    py: Python<'py>,
    field: &str,
    given: Option<&Bound<'py, PyAny>>,
    shape: impl numpy::ndarray::IntoDimension<Dim = D> + Copy + std::fmt::Debug,
) -> PyResult<Bound<'py, PyArray<T, D>>> {
    let Some(g) = given.filter(|g| !g.is_none()) else {
        // SAFETY: the caller writes every element before returning the array.
        return Ok(unsafe { PyArray::<T, D>::new(py, shape, false) });
    };
    let want = shape.into_dimension();
    let a = g.cast::<PyArray<T, D>>().map_err(|_| {
        bad(
            field,
            format!(
                "expected a {} array of shape {:?}, got {}",
                std::any::type_name::<T>(),
                want.slice(),
                describe_array(g)
            ),
        )
    })?;
    if a.shape() != want.slice() {
        return Err(bad(
            field,
            format!("expected shape {:?}, got {:?}", want.slice(), a.shape()),
        ));
    }
    if !a.is_c_contiguous() {
        return Err(bad(field, "must be C-contiguous"));
    }
    Ok(a.clone())
}

/// The detectors' keyword arguments (`threshold`, `noise`, `area_mm2=(min, max)`) as the
/// library's options; the library checks them.
pub fn detector_options(
    threshold: Option<f64>,
    noise: Option<f64>,
    area_mm2: Option<(f64, f64)>,
) -> PyResult<geltip::localise::DetectorOptions> {
    Ok(geltip::localise::DetectorOptions {
        threshold,
        noise,
        area_mm2: area_mm2
            .map(|(lo, hi)| crate::errors::lib(geltip::localise::AreaWindow::new(lo, hi)))
            .transpose()?,
    })
}
