//! `geltip.Sensor`: a sensor loaded by name, path or TOML text; its projection map on arrays.

use crate::convert::{array_out, json_to_py, path_or_str, points_in, repr};
use crate::errors::{bad, lib};
use geltip::finger::Region;
use geltip::localise::Localiser;
use geltip::GeltipError;
use glam::{DVec2, DVec3};
use numpy::{PyArray, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};
use std::path::{Path, PathBuf};

/// Region codes of `Sensor.unproject`.
pub const REGION_NONE: i8 = 0;
pub const REGION_HEMISPHERE: i8 = 1;
pub const REGION_CYLINDER: i8 = 2;

/// A GelTip sensor: the finger, its lens and the image they form.
#[pyclass(module = "geltip", frozen)]
pub struct Sensor {
    pub inner: geltip::Sensor,
    /// Keeps the surface detector's per-pixel table between `localise` calls.
    pub localiser: Localiser,
    /// The report of the calibration that made this sensor (`geltip.calibrate`): the text
    /// of its `report.json`.
    calibration: Option<String>,
}

impl Sensor {
    pub fn wrap(inner: geltip::Sensor) -> Sensor {
        Sensor {
            localiser: Localiser::new(&inner),
            inner,
            calibration: None,
        }
    }

    /// A sensor `geltip.calibrate` fitted, with its report (`report.json`'s text).
    pub fn calibrated(inner: geltip::Sensor, report: String) -> Sensor {
        Sensor {
            calibration: Some(report),
            ..Sensor::wrap(inner)
        }
    }

    /// A sensor given as a `Sensor`, or as `Sensor()`'s argument.
    pub fn of(py: Python<'_>, given: Option<&Bound<'_, PyAny>>) -> PyResult<Py<Sensor>> {
        match given.map(|s| s.cast::<Sensor>()) {
            Some(Ok(s)) => Ok(s.clone().unbind()),
            _ => Py::new(py, Sensor::new(given)?),
        }
    }
}

#[pymethods]
impl Sensor {
    /// `Sensor("paper")`: a preset name or the path of a sensor TOML file (as `--sensor`).
    #[new]
    #[pyo3(signature = (name = None))]
    fn new(name: Option<&Bound<'_, PyAny>>) -> PyResult<Sensor> {
        let name = match name {
            None => "paper".to_string(),
            Some(n) => path_or_str("sensor", n)?,
        };
        Ok(Sensor::wrap(lib(geltip::Sensor::load(&name))?))
    }

    /// A sensor from a TOML file (a path) or from TOML text.
    #[staticmethod]
    #[pyo3(signature = (path_or_str, name = None))]
    fn from_toml(path_or_str: &Bound<'_, PyAny>, name: Option<String>) -> PyResult<Sensor> {
        let sensor = match toml_source(path_or_str)? {
            TomlSource::Text(text) => {
                geltip::Sensor::from_toml(name.as_deref().unwrap_or("custom"), &text)
            }
            TomlSource::Path(path) => std::fs::read_to_string(&path)
                .map_err(|e| GeltipError::io(&path, e))
                .and_then(|text| {
                    let shown = path.to_string_lossy().into_owned();
                    geltip::Sensor::from_toml(name.as_deref().unwrap_or(&shown), &text)
                }),
        };
        Ok(Sensor::wrap(lib(sensor)?))
    }

    /// The preset names.
    #[staticmethod]
    fn presets() -> Vec<&'static str> {
        geltip::sensor::PRESETS.iter().map(|(n, _)| *n).collect()
    }

    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }

    #[getter]
    fn width(&self) -> u32 {
        self.inner.width
    }

    #[getter]
    fn height(&self) -> u32 {
        self.inner.height
    }

    /// (height, width, 3): the shape of the sensor's images.
    #[getter]
    fn image_shape(&self) -> (u32, u32, u32) {
        (self.inner.height, self.inner.width, 3)
    }

    #[getter]
    fn description(&self) -> &str {
        &self.inner.config.description
    }

    /// The whole configuration as a dict (the TOML file's tables).
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v =
            serde_json::to_value(&self.inner.config).map_err(|e| bad("config", e.to_string()))?;
        json_to_py(py, &v)
    }

    /// The report of the calibration that made this sensor (`report.json`'s content:
    /// image circle, PSNR and SSIM before and after, each fitted value with its standard
    /// error, what the frames leave loose), or None for a sensor not made by
    /// `geltip.calibrate`.
    #[getter]
    fn calibration<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        match &self.calibration {
            // Python's own parser: the dict holds exactly the numbers the file holds.
            Some(text) => py.import("json")?.call_method1("loads", (text,)),
            None => Ok(py.None().into_bound(py)),
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "Sensor('{}', {}x{})",
            self.inner.name, self.inner.width, self.inner.height
        )
    }

    /// Points (N, 3) mm -> pixels (N, 2); NaN rows where a point is not visible. With
    /// `reasons=True`, also a list: None where visible, else why not (the CLI's `reason`).
    #[pyo3(signature = (points, *, reasons = false))]
    fn project<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
        reasons: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (flat, lead) = points_in("points", points, 3, "points in mm")?;
        let mut out = Vec::with_capacity(flat.len() / 3 * 2);
        let mut why: Vec<Option<String>> = Vec::new();
        for p in flat.chunks_exact(3) {
            match self.inner.project(DVec3::new(p[0], p[1], p[2])) {
                Ok(px) => {
                    out.extend([px.x, px.y]);
                    why.push(None);
                }
                Err(reason) => {
                    out.extend([f64::NAN, f64::NAN]);
                    why.push(Some(reason.to_string()));
                }
            }
        }
        let pixels = array_out(py, &lead, 2, out)?;
        if !reasons {
            return Ok(pixels);
        }
        let list = if lead.is_empty() {
            why[0].clone().into_pyobject(py)?.into_any()
        } else {
            PyList::new(py, why)?.into_any()
        };
        Ok(PyTuple::new(py, [pixels, list])?.into_any())
    }

    /// Pixels (N, 2) -> (points (N, 3), normals (N, 3), region (N,) int8): what the paper's
    /// map m sees at each pixel. Region codes: 0 none (NaN point and normal: outside the image
    /// or the field of view), 1 hemisphere, 2 cylinder (`geltip.REGION_NAMES`).
    fn unproject<'py>(
        &self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let (flat, lead) = points_in("pixels", pixels, 2, "pixels (u, v)")?;
        let n = flat.len() / 2;
        let mut points = Vec::with_capacity(n * 3);
        let mut normals = Vec::with_capacity(n * 3);
        let mut regions = Vec::with_capacity(n);
        for px in flat.chunks_exact(2) {
            match self.inner.unproject(DVec2::new(px[0], px[1])) {
                Some(sp) => {
                    points.extend(sp.point.to_array());
                    normals.extend(sp.normal.to_array());
                    regions.push(match sp.region {
                        Region::Hemisphere => REGION_HEMISPHERE,
                        Region::Cylinder => REGION_CYLINDER,
                    });
                }
                None => {
                    points.extend([f64::NAN; 3]);
                    normals.extend([f64::NAN; 3]);
                    regions.push(REGION_NONE);
                }
            }
        }
        let points = array_out(py, &lead, 3, points)?;
        let normals = array_out(py, &lead, 3, normals)?;
        let regions = PyArray::from_vec(py, regions).reshape(lead)?.into_any();
        PyTuple::new(py, [points, normals, regions])
    }
}

enum TomlSource {
    Text(String),
    Path(PathBuf),
}

/// `from_toml`'s argument: a path (PathLike, or a str naming an existing file or holding no
/// TOML syntax) or TOML text.
fn toml_source(value: &Bound<'_, PyAny>) -> PyResult<TomlSource> {
    if let Ok(s) = value.extract::<String>() {
        let looks_like_toml = s.contains('=') || s.contains('\n') || s.contains('[');
        if Path::new(&s).is_file() || !looks_like_toml {
            return Ok(TomlSource::Path(PathBuf::from(s)));
        }
        return Ok(TomlSource::Text(s));
    }
    value
        .extract::<PathBuf>()
        .map(TomlSource::Path)
        .map_err(|_| {
            bad(
                "path_or_str",
                format!("expected TOML text or a path, got {}", repr(value)),
            )
        })
}
