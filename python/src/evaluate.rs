//! `geltip._geltip.evaluate`: a detector scored by the library's `geltip evaluate` job. The
//! detector is a built-in localiser's name, or a Python function given each frame's image,
//! reference and sensor that answers with a list of detections (dicts): converted here into
//! the library's [`Given`], which the library checks.

use crate::convert::{detector_options, json_to_py, path_or_str};
use crate::errors::{bad, detached, lib};
use crate::sensor::Sensor;
use geltip::evaluate::{Detector, Found, Given, MethodDetector, Named, Sample};
use geltip::jobs::evaluate as job;
use geltip::localise::Method;
use geltip::GeltipError;
use numpy::{PyArray, PyArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// A Python function as a detector. An exception it raises stops the run and is raised
/// again, as it was, once the run has stopped.
struct PyDetector {
    function: Py<PyAny>,
    /// Each frame's sensor as a `geltip.Sensor`, made once per sensor.
    sensors: Vec<(geltip::SensorConfig, Py<Sensor>)>,
    /// What the function raised, for the caller to raise again.
    raised: Arc<Mutex<Option<PyErr>>>,
}

impl PyDetector {
    fn sensor(&mut self, py: Python<'_>, sensor: &geltip::Sensor) -> PyResult<Py<Sensor>> {
        if let Some((_, s)) = self.sensors.iter().find(|(c, _)| *c == sensor.config) {
            return Ok(s.clone_ref(py));
        }
        let s = Py::new(py, Sensor::wrap(sensor.clone()))?;
        self.sensors.push((sensor.config.clone(), s.clone_ref(py)));
        Ok(s)
    }

    /// The function's answer for `sample`.
    fn call<'py>(&mut self, py: Python<'py>, sample: &Sample) -> PyResult<Bound<'py, PyAny>> {
        let array = |rgb: &image::RgbImage| {
            let (w, h) = rgb.dimensions();
            PyArray::from_slice(py, rgb.as_raw()).reshape([h as usize, w as usize, 3])
        };
        let image = array(sample.image.rgb(&sample.sensor).map_err(to_py)?)?;
        let reference = array(sample.reference.rgb(&sample.sensor).map_err(to_py)?)?;
        let sensor = self.sensor(py, &sample.sensor)?;
        Ok(self
            .function
            .call1(py, (image, reference, sensor))?
            .into_bound(py))
    }
}

/// A function's answer as the library's detections: None or a list (or tuple) of dicts with
/// "pixel" and/or "point" (sequences of numbers: lists, tuples, arrays) and "confidence".
/// Only types are checked here (a wrong kind of answer is a `TypeError`, as Python would
/// raise); the values are the library's to check.
fn given(answer: &Bound<'_, PyAny>, what: &str) -> PyResult<Result<Vec<Given>, GeltipError>> {
    if answer.is_none() {
        return Ok(Ok(Vec::new()));
    }
    let items: Vec<Bound<'_, PyAny>> = if let Ok(list) = answer.cast::<PyList>() {
        list.iter().collect()
    } else if let Ok(tuple) = answer.cast::<PyTuple>() {
        tuple.iter().collect()
    } else {
        return Err(PyTypeError::new_err(format!(
            "a detector returns a list of detections (dicts), got {}",
            answer
                .get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_default()
        )));
    };
    let mut out = Vec::with_capacity(items.len());
    for (j, item) in items.iter().enumerate() {
        let what = format!("{what}: detections[{j}]");
        let Ok(d) = item.cast::<PyDict>() else {
            return Ok(Err(GeltipError::input(what, "expected an object")));
        };
        let field = |key: &str| -> PyResult<Option<Bound<'_, PyAny>>> {
            Ok(d.get_item(key)?.filter(|v| !v.is_none()))
        };
        let numbers = |key: &str| -> PyResult<Result<Option<Vec<f64>>, GeltipError>> {
            Ok(match field(key)? {
                None => Ok(None),
                Some(v) => v.extract::<Vec<f64>>().map(Some).map_err(|_| {
                    GeltipError::input(
                        &what,
                        format!(
                            "{key}: expected a sequence of numbers, got {}",
                            crate::convert::repr(&v)
                        ),
                    )
                }),
            })
        };
        let confidence = match field("confidence")? {
            None => None,
            Some(c) => match c.extract::<f64>() {
                Ok(c) => Some(c),
                Err(_) => {
                    return Ok(Err(GeltipError::input(
                        &what,
                        format!(
                            "confidence: expected a number, got {}",
                            crate::convert::repr(&c)
                        ),
                    )))
                }
            },
        };
        let (pixel, point) = match (numbers("pixel")?, numbers("point")?) {
            (Ok(pixel), Ok(point)) => (pixel, point),
            (Err(e), _) | (_, Err(e)) => return Ok(Err(e)),
        };
        out.push(Given {
            pixel,
            point,
            confidence,
        });
    }
    Ok(Ok(out))
}

fn to_py(e: GeltipError) -> PyErr {
    crate::errors::lib::<()>(Err(e)).unwrap_err()
}

impl Detector for PyDetector {
    fn name(&self) -> String {
        Python::attach(|py| {
            self.function
                .bind(py)
                .getattr("__name__")
                .and_then(|n| n.extract::<String>())
                .unwrap_or_else(|_| "python".into())
        })
    }

    fn detect(&mut self, sample: &Sample) -> geltip::Result<Vec<Found>> {
        let k = sample.truth.index;
        let what = format!("detector, sample {k}");
        let answered = Python::attach(|py| self.call(py, sample).and_then(|a| given(&a, &what)));
        match answered {
            Ok(found) => found?
                .iter()
                .enumerate()
                .map(|(j, g)| {
                    Found::from_given(&sample.sensor, g, &format!("{what}: detections[{j}]"))
                })
                .collect(),
            Err(e) => {
                if let Ok(mut slot) = self.raised.lock() {
                    *slot = Some(e);
                }
                Err(GeltipError::input(what, "the function raised an exception"))
            }
        }
    }
}

/// Scores `detector` (a function `(image, reference, sensor) -> JSON text`, or "surface",
/// "paper" or "change", whose decision `threshold` and `noise` may be given, and the
/// contact's area on the finger `area_mm2` = (min, max) for change and paper) on a dataset's directory or
/// a suite ("paper", "stability", with `sensor`), with the matching gate `gate_mm` (None:
/// any distance), or on a real sensor's labelled frames (`real`: a set file or the AllSight
/// labels.json, with the `sensor` that took them). With `out`, the report's files go there,
/// beside `compare`'s (another run's output directory). Returns {"summary", "tables",
/// "per_sample", "files"} ({"summary", "tables", "files"} for real frames).
#[pyfunction]
#[pyo3(signature = (detector, *, dataset = None, suite = None, sensor = None, out = None, gate_mm = Some(3.0), name = None, compare = None, real = None, threshold = None, noise = None, area_mm2 = None))]
#[allow(clippy::too_many_arguments)] // The keyword arguments of geltip.evaluate, one each.
pub fn evaluate<'py>(
    py: Python<'py>,
    detector: &Bound<'py, PyAny>,
    dataset: Option<&Bound<'py, PyAny>>,
    suite: Option<String>,
    sensor: Option<&Bound<'py, PyAny>>,
    out: Option<&Bound<'py, PyAny>>,
    gate_mm: Option<f64>,
    name: Option<String>,
    compare: Option<&Bound<'py, PyAny>>,
    real: Option<&Bound<'py, PyAny>>,
    threshold: Option<f64>,
    noise: Option<f64>,
    area_mm2: Option<(f64, f64)>,
) -> PyResult<Bound<'py, PyAny>> {
    let options = detector_options(threshold, noise, area_mm2)?;
    let path = |field: &str, v: Option<&Bound<'py, PyAny>>| -> PyResult<Option<PathBuf>> {
        v.map(|v| path_or_str(field, v).map(PathBuf::from))
            .transpose()
    };
    let (dataset, out, compare, real) = (
        path("dataset", dataset)?,
        path("out", out)?,
        path("compare", compare)?,
        path("real", real)?,
    );
    let sensor = sensor
        .map(|s| Sensor::of(py, Some(s)).map(|s| s.get().inner.clone()))
        .transpose()?;
    let raised = Arc::new(Mutex::new(None));
    let inner: Box<dyn Detector> = if let Ok(method) = detector.extract::<String>() {
        // The library names the method; here the argument is the detector.
        let method = Method::from_name(&method).map_err(|e| match e {
            GeltipError::InvalidInput { reason, .. } => bad("detector", reason),
            other => to_py(other),
        })?;
        Box::new(lib(MethodDetector::with_options(method, options))?)
    } else if options.any() {
        let (name, methods) = if threshold.is_some() {
            ("threshold", "the method 'change'")
        } else if noise.is_some() {
            ("noise", "the method 'change'")
        } else {
            ("area_mm2", "the methods 'change' and 'paper'")
        };
        return Err(bad(name, format!("applies to {methods}")));
    } else if detector.is_callable() {
        Box::new(PyDetector {
            function: detector.clone().unbind(),
            sensors: Vec::new(),
            raised: raised.clone(),
        })
    } else {
        return Err(bad(
            "detector",
            "expected a function (image, reference, sensor) -> detections, or 'surface', 'paper' or 'change'",
        ));
    };
    let mut detector = Named::new(inner, name);
    // The exception the function raised, if it stopped the run; else the run's error.
    let reraised = |e: PyErr| raised.lock().ok().and_then(|mut r| r.take()).unwrap_or(e);
    if let Some(set) = real {
        let sensor = sensor.ok_or_else(|| bad("real", "name the sensor that took the frames"))?;
        let outcome = detached(py, "evaluating", || {
            job::run_real(&set, &sensor, &mut detector, out.as_deref(), |_, _| {})
        });
        let outcome = outcome.map_err(reraised)?;
        let report = PyDict::new(py);
        report.set_item("summary", json_to_py(py, &outcome.report.summary())?)?;
        report.set_item("tables", outcome.report.tables())?;
        report.set_item("files", outcome.files)?;
        return Ok(report.into_any());
    }
    let outcome = detached(py, "evaluating", || {
        let source = job::source(dataset.as_deref(), suite.as_deref(), sensor.as_ref())?;
        job::run(
            &source,
            &mut detector,
            gate_mm,
            out.as_deref(),
            compare.as_deref(),
            |_, _| {},
        )
    });
    let outcome = outcome.map_err(reraised)?;
    let report = PyDict::new(py);
    report.set_item("summary", json_to_py(py, &outcome.summary)?)?;
    report.set_item("tables", outcome.tables)?;
    let per_sample = geltip::evaluate::report::per_sample(&outcome.evaluation);
    report.set_item(
        "per_sample",
        json_to_py(py, &serde_json::Value::Array(per_sample))?,
    )?;
    report.set_item("files", outcome.files)?;
    Ok(report.into_any())
}
