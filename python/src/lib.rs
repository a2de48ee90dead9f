//! `geltip._geltip`: the native half of the Python package, a thin layer over the geltip
//! library. NumPy arrays in and out, keyword arguments, and every library error raised as
//! the Python exception class of its kind (see `geltip/_errors.py`) with the one-line message
//! the command line prints. Rendering and localising run with the GIL released
//! ([`Python::detach`]); a panic inside the library is caught and raised as a `GpuError`
//! instead of unwinding into the interpreter.

use geltip::finger::Region;
use geltip::gpu::context::MAX_STREAMS;
use geltip::localise::{Localiser, Method};
use geltip::object::Object;
use geltip::render::gpu::{Renderer, MAX_BATCH};
use geltip::render::{Frame, GroundTruth, Hold, Place, Press};
use geltip::GeltipError;
use glam::{DVec2, DVec3};
use numpy::{
    AllowTypeChange, PyArray, PyArray2, PyArray3, PyArrayLikeDyn, PyArrayMethods,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple, PyType};
use serde_json::Value;
use std::collections::HashMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

// ---------------------------------------------------------------------------------------
// Errors

/// An error on its way to Python: the exception class (in `geltip._errors`) and the message.
struct Failure {
    class: &'static str,
    message: String,
}

impl From<GeltipError> for Failure {
    fn from(e: GeltipError) -> Self {
        let class = match e {
            GeltipError::InvalidConfig { .. }
            | GeltipError::ConfigParse { .. }
            | GeltipError::UnknownSensor { .. }
            | GeltipError::InvalidInput { .. }
            | GeltipError::InvalidContact { .. }
            | GeltipError::InvalidMesh { .. }
            | GeltipError::InvalidImage { .. } => "InvalidArgumentError",
            GeltipError::NoAdapter(_) | GeltipError::Gpu(_) | GeltipError::Shader { .. } => {
                "GpuError"
            }
            GeltipError::Io { .. } => "GeltipIOError",
        };
        // Display is the CLI's message (the CLI prefixes it with "error: ").
        Failure {
            class,
            message: e.to_string(),
        }
    }
}

impl From<Failure> for PyErr {
    fn from(f: Failure) -> PyErr {
        Python::attach(|py| {
            let class = py
                .import("geltip._errors")
                .and_then(|m| m.getattr(f.class))
                .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
            match class {
                Ok(class) => PyErr::from_type(class, f.message),
                // Only if the pure-Python half is missing (the module imported on its own).
                Err(_) => match f.class {
                    "GpuError" => pyo3::exceptions::PyRuntimeError::new_err(f.message),
                    "GeltipIOError" => pyo3::exceptions::PyOSError::new_err(f.message),
                    _ => pyo3::exceptions::PyValueError::new_err(f.message),
                },
            }
        })
    }
}

/// A bad argument: `InvalidArgumentError` (a `ValueError`) whose message starts with the
/// argument's name.
fn bad(field: impl AsRef<str>, reason: impl AsRef<str>) -> PyErr {
    Failure {
        class: "InvalidArgumentError",
        message: format!("{}: {}", field.as_ref(), reason.as_ref()),
    }
    .into()
}

fn lib<T>(r: geltip::Result<T>) -> PyResult<T> {
    r.map_err(|e| Failure::from(e).into())
}

/// Runs `f` with the GIL released, turning a panic into a `GpuError` (the interpreter must
/// survive whatever the GPU stack does).
fn detached<T: Send>(
    py: Python<'_>,
    what: &str,
    f: impl FnOnce() -> geltip::Result<T> + Send,
) -> PyResult<T> {
    let out = py.detach(|| catch_unwind(AssertUnwindSafe(f)));
    match out {
        Ok(r) => lib(r),
        Err(panic) => {
            let text = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "unknown panic".to_string());
            let text: Vec<&str> = text.split_whitespace().collect();
            Err(Failure {
                class: "GpuError",
                message: format!("{what}: internal error: {}", text.join(" ")),
            }
            .into())
        }
    }
}

// ---------------------------------------------------------------------------------------
// Conversions

/// serde_json value -> Python object (dict, list, str, int, float, bool, None).
fn json_to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
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
fn image_array<'py>(py: Python<'py>, frame: &Frame) -> Bound<'py, PyArray3<u8>> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    // SAFETY: every element is written below before the array is handed to Python.
    let array = unsafe { PyArray3::<u8>::new(py, [h, w, 3], false) };
    // SAFETY: the array is new, C-contiguous and not yet visible to Python.
    let out = unsafe { std::slice::from_raw_parts_mut(array.data(), h * w * 3) };
    rgba_to_rgb(&frame.rgba, out);
    array
}

/// A frame's indentation as a new (H, W) float32 array.
fn depth_array<'py>(py: Python<'py>, frame: &Frame) -> Bound<'py, PyArray2<f32>> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    // SAFETY: as in `image_array`.
    let array = unsafe { PyArray2::<f32>::new(py, [h, w], false) };
    let out = unsafe { std::slice::from_raw_parts_mut(array.data(), h * w) };
    out.copy_from_slice(&frame.indentation);
    array
}

fn rgba_to_rgb(rgba: &[u8], rgb: &mut [u8]) {
    for (d, s) in rgb.chunks_exact_mut(3).zip(rgba.chunks_exact(4)) {
        d.copy_from_slice(&s[..3]);
    }
}

/// An (H, W, 3) uint8 array of the sensor's size as an RGB image.
fn rgb_image(
    field: &str,
    value: &Bound<'_, PyAny>,
    sensor: &geltip::Sensor,
) -> PyResult<image::RgbImage> {
    let expected = format!(
        "expected a ({}, {}, 3) uint8 array (sensor '{}')",
        sensor.height, sensor.width, sensor.name
    );
    let array = value.cast::<PyArray3<u8>>().map_err(|_| {
        let got = describe_array(value);
        bad(field, format!("{expected}, got {got}"))
    })?;
    let shape = array.shape().to_vec();
    if shape != [sensor.height as usize, sensor.width as usize, 3] {
        return Err(bad(field, format!("{expected}, got shape {shape:?}")));
    }
    let readonly = array.readonly();
    let pixels: Vec<u8> = match readonly.as_slice() {
        Ok(s) => s.to_vec(),
        Err(_) => readonly.as_array().iter().copied().collect(),
    };
    image::RgbImage::from_raw(sensor.width, sensor.height, pixels)
        .ok_or_else(|| bad(field, "pixel buffer does not match its shape"))
}

fn describe_array(value: &Bound<'_, PyAny>) -> String {
    let shape = value
        .getattr("shape")
        .ok()
        .map(|s| s.to_string())
        .unwrap_or_default();
    let dtype = value
        .getattr("dtype")
        .ok()
        .map(|s| s.to_string())
        .unwrap_or_default();
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

/// A number argument (any real: int, float, NumPy scalar). Its range is checked by the
/// library, with the CLI's messages.
fn number(field: &str, value: &Bound<'_, PyAny>) -> PyResult<f64> {
    value
        .extract()
        .map_err(|_| bad(field, format!("expected a number, got {}", repr(value))))
}

/// A place's number: finite (as `Place::parse` requires of `--at`).
fn place_number(field: &str, value: &Bound<'_, PyAny>) -> PyResult<f64> {
    let v = number(field, value)?;
    if !v.is_finite() {
        return Err(bad(
            field,
            format!("the value is not a finite number, got {v}"),
        ));
    }
    Ok(v)
}

fn repr(value: &Bound<'_, PyAny>) -> String {
    value
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// A `str` or `os.PathLike` argument.
fn path_or_str(field: &str, value: &Bound<'_, PyAny>) -> PyResult<String> {
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

// ---------------------------------------------------------------------------------------
// Sensor

/// A GelTip sensor: the finger, its lens and the image they form.
#[pyclass(module = "geltip", frozen)]
struct Sensor {
    inner: geltip::Sensor,
    /// Keeps the surface detector's per-pixel table between `localise` calls.
    localiser: Localiser,
}

impl Sensor {
    fn wrap(inner: geltip::Sensor) -> Sensor {
        Sensor {
            localiser: Localiser::new(&inner),
            inner,
        }
    }
}

/// Points (..., k) float64 from any array-like; returns the flat values and the leading shape.
fn points_in(
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

fn array_out<'py>(
    py: Python<'py>,
    lead: &[usize],
    k: usize,
    values: Vec<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut shape = lead.to_vec();
    shape.push(k);
    Ok(PyArray::from_vec(py, values).reshape(shape)?.into_any())
}

/// Region codes of `Sensor.unproject`.
const REGION_NONE: i8 = 0;
const REGION_HEMISPHERE: i8 = 1;
const REGION_CYLINDER: i8 = 2;

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
        let text_or_path = path_or_str_arg(path_or_str)?;
        let sensor = match text_or_path {
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
        if reasons {
            let list = if lead.is_empty() {
                why[0].clone().into_pyobject(py)?.into_any()
            } else {
                PyList::new(py, why)?.into_any()
            };
            Ok(PyTuple::new(py, [pixels, list])?.into_any())
        } else {
            Ok(pixels)
        }
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
        let regions = PyArray::from_vec(py, regions)
            .reshape(lead.clone())?
            .into_any();
        PyTuple::new(py, [points, normals, regions])
    }
}

enum TomlSource {
    Text(String),
    Path(PathBuf),
}

/// `from_toml`'s argument: a path (PathLike, or a str naming an existing file or holding no
/// TOML syntax) or TOML text.
fn path_or_str_arg(value: &Bound<'_, PyAny>) -> PyResult<TomlSource> {
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

// ---------------------------------------------------------------------------------------
// Contacts from keyword arguments

/// The keys a contact accepts (keyword arguments of `render`, keys of `render_batch`'s dicts).
const CONTACT_KEYS: [&str; 11] = [
    "object",
    "at",
    "rotation",
    "translation",
    "s",
    "azimuth",
    "spin",
    "tilt",
    "tilt_towards",
    "depth",
    "pose",
];

/// A contact's fields, as given.
#[derive(Default)]
struct ContactArgs<'a, 'py> {
    object: Option<&'a Bound<'py, PyAny>>,
    at: Option<&'a Bound<'py, PyAny>>,
    rotation: Option<&'a Bound<'py, PyAny>>,
    translation: Option<&'a Bound<'py, PyAny>>,
    s: Option<&'a Bound<'py, PyAny>>,
    azimuth: Option<&'a Bound<'py, PyAny>>,
    spin: Option<&'a Bound<'py, PyAny>>,
    tilt: Option<&'a Bound<'py, PyAny>>,
    tilt_towards: Option<&'a Bound<'py, PyAny>>,
    depth: Option<&'a Bound<'py, PyAny>>,
    pose: Option<&'a Bound<'py, PyAny>>,
}

fn some<'a, 'py>(v: Option<&'a Bound<'py, PyAny>>) -> Option<&'a Bound<'py, PyAny>> {
    v.filter(|v| !v.is_none())
}

/// `at` as the CLI's text (`"rotation=30"`), a pair (`("rotation", 30)`) or a one-key dict
/// (`{"rotation": 30}`).
fn place_of(field: &str, at: &Bound<'_, PyAny>) -> PyResult<Place> {
    if let Ok(text) = at.extract::<String>() {
        return lib(Place::parse(&text));
    }
    let pair: Option<(String, Bound<'_, PyAny>)> = if let Ok(d) = at.cast::<PyDict>() {
        if d.len() == 1 {
            d.items()
                .get_item(0)
                .ok()
                .and_then(|kv| kv.extract::<(String, Bound<'_, PyAny>)>().ok())
        } else {
            None
        }
    } else {
        at.extract::<(String, Bound<'_, PyAny>)>().ok()
    };
    let Some((key, value)) = pair else {
        return Err(bad(
            field,
            format!(
                "expected 'rotation=<deg>', 'translation=<mm>' or 's=<mm>' (or a pair such as ('rotation', 30)), got {}",
                repr(at)
            ),
        ));
    };
    let v = place_number(&format!("{field} {key}"), &value)?;
    match key.as_str() {
        "rotation" => Ok(Place::Rotation(v)),
        "translation" => Ok(Place::Translation(v)),
        "s" => Ok(Place::ArcLength(v)),
        _ => Err(bad(
            field,
            format!("unknown place '{key}', expected rotation, translation or s"),
        )),
    }
}

impl<'a, 'py> ContactArgs<'a, 'py> {
    /// Reads a contact dict's keys; `field` names the dict in messages (`contacts[3]`).
    fn from_dict(
        field: &str,
        d: &'a Bound<'py, PyDict>,
        store: &'a mut Vec<Bound<'py, PyAny>>,
    ) -> PyResult<()> {
        for (k, v) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| bad(field, format!("keys must be strings, got {}", repr(&k))))?;
            if !CONTACT_KEYS.contains(&key.as_str()) {
                return Err(bad(
                    format!("{field}.{key}"),
                    format!("unknown key, expected one of {}", CONTACT_KEYS.join(", ")),
                ));
            }
            store.push(PyString::new(d.py(), &key).into_any());
            store.push(v);
        }
        Ok(())
    }

    fn from_pairs(pairs: &'a [Bound<'py, PyAny>]) -> ContactArgs<'a, 'py> {
        let mut a = ContactArgs::default();
        for kv in pairs.chunks_exact(2) {
            let key = kv[0].extract::<String>().unwrap_or_default();
            let v = Some(&kv[1]);
            match key.as_str() {
                "object" => a.object = v,
                "at" => a.at = v,
                "rotation" => a.rotation = v,
                "translation" => a.translation = v,
                "s" => a.s = v,
                "azimuth" => a.azimuth = v,
                "spin" => a.spin = v,
                "tilt" => a.tilt = v,
                "tilt_towards" => a.tilt_towards = v,
                "depth" => a.depth = v,
                "pose" => a.pose = v,
                _ => {}
            }
        }
        a
    }

    /// The press, resolving the object through `objects`. `prefix` is "" for keyword
    /// arguments and "contacts[3]." for a batch's dicts.
    fn press(&self, prefix: &str, objects: &Objects) -> PyResult<Press> {
        let f = |name: &str| format!("{prefix}{name}");
        let object = some(self.object).ok_or_else(|| {
            bad(
                f("object"),
                "required: a built-in solid (cone, sphere, irregular-prism, cylinder, edge, tube, slab, torus, disc) or a mesh file",
            )
        })?;
        let object = objects.get(object.py(), &path_or_str(&f("object"), object)?)?;
        let places = [
            ("at", self.at),
            ("rotation", self.rotation),
            ("translation", self.translation),
            ("s", self.s),
        ];
        let given: Vec<(&str, &Bound<'_, PyAny>)> = places
            .iter()
            .filter_map(|(n, v)| some(*v).map(|v| (*n, v)))
            .collect();
        if let Some(pose) = some(self.pose) {
            if let Some((n, _)) = given.first() {
                return Err(bad(f("pose"), format!("give either pose or {n}, not both")));
            }
            for (n, v) in [
                ("azimuth", self.azimuth),
                ("spin", self.spin),
                ("tilt", self.tilt),
                ("tilt_towards", self.tilt_towards),
                ("depth", self.depth),
            ] {
                if some(v).is_some() {
                    return Err(bad(
                        f(n),
                        "cannot be combined with pose (the pose fixes it)",
                    ));
                }
            }
            let numbers: Vec<f64> = if let Ok(t) = pose.extract::<String>() {
                t.split(|c: char| c == ',' || c.is_whitespace())
                    .filter(|t| !t.is_empty())
                    .map(|t| {
                        t.parse::<f64>()
                            .map_err(|_| bad(f("pose"), format!("'{t}' is not a number")))
                    })
                    .collect::<PyResult<_>>()?
            } else {
                pose
                    .call_method0("__iter__")
                    .and_then(|_| {
                        let arr: PyArrayLikeDyn<'_, f64, AllowTypeChange> = pose.extract()?;
                        Ok(arr.as_array().iter().copied().collect())
                    })
                    .map_err(|_| {
                        bad(
                            f("pose"),
                            format!("expected 16 numbers (a 4x4 matrix) or 7 (x y z qw qx qy qz), got {}", repr(pose)),
                        )
                    })?
            };
            let hold = lib(Hold::from_pose(&numbers))?;
            return Ok(Press { object, hold });
        }
        let place = match given.as_slice() {
            [(name, v)] => {
                if *name == "at" {
                    place_of(&f("at"), v)?
                } else {
                    let x = place_number(&f(name), v)?;
                    match *name {
                        "rotation" => Place::Rotation(x),
                        "translation" => Place::Translation(x),
                        _ => Place::ArcLength(x),
                    }
                }
            }
            [] => {
                return Err(bad(
                    f("at"),
                    "required: at='rotation=30' (or 'translation=<mm>', 's=<mm>'), or rotation=, translation=, s=, or pose=",
                ))
            }
            many => {
                let names: Vec<&str> = many.iter().map(|(n, _)| *n).collect();
                return Err(bad(
                    f(names[1]),
                    format!("give one place, not {}", names.join(" and ")),
                ));
            }
        };
        let opt = |name: &str, v: Option<&Bound<'_, PyAny>>| -> PyResult<f64> {
            some(v).map_or(Ok(0.0), |v| number(&f(name), v))
        };
        let depth =
            some(self.depth).ok_or_else(|| bad(f("depth"), "required: the press depth in mm"))?;
        let depth_mm = number(&f("depth"), depth)?;
        Ok(Press {
            object,
            hold: Hold::Surface {
                place,
                azimuth_deg: opt("azimuth", self.azimuth)?,
                spin_deg: opt("spin", self.spin)?,
                tilt_deg: opt("tilt", self.tilt)?,
                tilt_towards_deg: opt("tilt_towards", self.tilt_towards)?,
                depth_mm,
            },
        })
    }
}

/// Objects by the name they were asked for: a mesh is loaded and baked once per Simulator
/// (and its GPU grid uploaded once: the renderer keys it by the object's address).
struct Objects(Mutex<HashMap<String, Arc<Object>>>);

impl Objects {
    fn get(&self, py: Python<'_>, name: &str) -> PyResult<Arc<Object>> {
        if let Some(o) = self.0.lock().map_err(|_| poisoned())?.get(name) {
            return Ok(o.clone());
        }
        // A mesh is baked here (seconds for a detailed one): without the GIL.
        let object = Arc::new(detached(py, "loading an object", || {
            Object::from_arg(name)
        })?);
        self.0
            .lock()
            .map_err(|_| poisoned())?
            .insert(name.to_string(), object.clone());
        Ok(object)
    }
}

fn poisoned() -> PyErr {
    Failure {
        class: "GpuError",
        message: "the simulator failed in an earlier call (internal error); create a new Simulator"
            .into(),
    }
    .into()
}

// ---------------------------------------------------------------------------------------
// Simulator

/// The renderer of one sensor, holding the GPU context, pipelines and the reference frame.
#[pyclass(module = "geltip", frozen)]
struct Simulator {
    sensor: Py<Sensor>,
    renderer: Mutex<Renderer>,
    /// Renderers of render streams 1.. (`streams=`), each on a device of its own: only
    /// `render_batch` uses them.
    more: Vec<Mutex<Renderer>>,
    objects: Objects,
    host: String,
}

/// A raw output buffer handed to the detached render loop.
struct OutPtr<T>(*mut T, usize);
// SAFETY: the arrays behind the pointers are kept alive (and borrowed read-write) by the
// calling frame for the whole detached call, and only the render loop writes to them.
unsafe impl<T> Send for OutPtr<T> {}

impl<T> OutPtr<T> {
    /// SAFETY: the pointer and length must describe a live, exclusively used allocation.
    unsafe fn slice<'a>(self) -> &'a mut [T] {
        std::slice::from_raw_parts_mut(self.0, self.1)
    }
}

/// Renders `list` in submissions of [`MAX_BATCH`]: submission c on renderer c mod n, each
/// renderer on its own thread, in a fixed order (so the same calls give the same frames),
/// writing frame i into slot i of `images` (RGB) and `depths`; the labels in list order.
fn render_chunks(
    renderers: Vec<&mut Renderer>,
    list: &[Press],
    images: &mut [u8],
    depths: Option<&mut [f32]>,
    (h, w): (usize, usize),
) -> geltip::Result<Vec<GroundTruth>> {
    type Job<'a> = (usize, &'a [Press], &'a mut [u8], Option<&'a mut [f32]>);
    // A submission's index and its labels.
    type Labelled = (usize, Vec<GroundTruth>);
    let (frame_rgb, frame_px) = (h * w * 3, h * w);
    let streams = renderers.len().max(1);
    let mut depth_parts: Vec<Option<&mut [f32]>> = match depths {
        Some(d) => d.chunks_mut(MAX_BATCH * frame_px).map(Some).collect(),
        None => Vec::new(),
    };
    depth_parts.resize_with(list.len().div_ceil(MAX_BATCH), || None);
    let mut jobs: Vec<Vec<Job<'_>>> = (0..streams).map(|_| Vec::new()).collect();
    let parts = list
        .chunks(MAX_BATCH)
        .zip(images.chunks_mut(MAX_BATCH * frame_rgb))
        .zip(depth_parts);
    for (c, ((contacts, image), depth)) in parts.enumerate() {
        jobs[c % streams].push((c, contacts, image, depth));
    }
    let results: Vec<geltip::Result<Vec<Labelled>>> = std::thread::scope(|scope| {
        let handles: Vec<_> = renderers
            .into_iter()
            .zip(jobs)
            .map(|(r, jobs)| {
                scope.spawn(move || {
                    let mut done = Vec::with_capacity(jobs.len());
                    for (c, contacts, image, mut depth) in jobs {
                        let mut truths = Vec::with_capacity(contacts.len());
                        for (k, (frame, truth)) in r.render_batch(contacts)?.into_iter().enumerate()
                        {
                            rgba_to_rgb(
                                &frame.rgba,
                                &mut image[k * frame_rgb..(k + 1) * frame_rgb],
                            );
                            if let Some(d) = depth.as_deref_mut() {
                                d[k * frame_px..(k + 1) * frame_px]
                                    .copy_from_slice(&frame.indentation);
                            }
                            truths.push(truth);
                        }
                        done.push((c, truths));
                    }
                    Ok(done)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Err(GeltipError::Gpu("a render stream panicked".into())))
            })
            .collect()
    });
    let mut chunks = Vec::new();
    for r in results {
        chunks.extend(r?);
    }
    chunks.sort_by_key(|(c, _)| *c);
    Ok(chunks.into_iter().flat_map(|(_, t)| t).collect())
}

impl Simulator {
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, Renderer>> {
        self.renderer.lock().map_err(|_| poisoned())
    }

    fn contact_args<'a, 'py>(kwargs: &'a [Bound<'py, PyAny>]) -> ContactArgs<'a, 'py> {
        ContactArgs::from_pairs(kwargs)
    }
}

fn frame_tuple<'py>(
    py: Python<'py>,
    frame: &Frame,
    labels: &Value,
) -> PyResult<Bound<'py, PyTuple>> {
    PyTuple::new(
        py,
        [
            image_array(py, frame).into_any(),
            json_to_py(py, labels)?,
            depth_array(py, frame).into_any(),
        ],
    )
}

#[pymethods]
impl Simulator {
    /// `Simulator(sensor, objects=[...], streams=1)`: starts the GPU context (once per
    /// process), compiles the pipelines and renders the empty finger. `objects` preloads
    /// meshes (a mesh is baked on first use otherwise). `streams` (1..=4): renderers on
    /// devices of their own that `render_batch` shares its batches between, at the same time
    /// (on a software rasteriser they fill the cores one leaves idle).
    #[new]
    #[pyo3(signature = (sensor = None, objects = None, streams = 1))]
    fn new(
        py: Python<'_>,
        sensor: Option<&Bound<'_, PyAny>>,
        objects: Option<Vec<Bound<'_, PyAny>>>,
        streams: usize,
    ) -> PyResult<Simulator> {
        if !(1..=MAX_STREAMS).contains(&streams) {
            return Err(bad(
                "streams",
                format!("must lie in 1..={MAX_STREAMS}, got {streams}"),
            ));
        }
        let sensor: Py<Sensor> = match sensor {
            None => Py::new(py, Sensor::new(None)?)?,
            Some(s) => match s.cast::<Sensor>() {
                Ok(s) => s.clone().unbind(),
                Err(_) => Py::new(py, Sensor::new(Some(s))?)?,
            },
        };
        let store = Objects(Mutex::new(HashMap::new()));
        for (k, o) in objects.unwrap_or_default().iter().enumerate() {
            let name = path_or_str(&format!("objects[{k}]"), o)?;
            let loaded = detached(py, "loading objects", || Object::from_arg(&name))?;
            store
                .0
                .lock()
                .map_err(|_| poisoned())?
                .insert(name, Arc::new(loaded));
        }
        let rs = sensor.get().inner.clone();
        let mut renderers = detached(py, "starting the renderer", move || {
            Renderer::on_streams(&rs, streams, &[])
        })?;
        let more = renderers.split_off(1).into_iter().map(Mutex::new).collect();
        let renderer = renderers.remove(0);
        let host = geltip::gpu::host_description(renderer.adapter());
        Ok(Simulator {
            sensor,
            renderer: Mutex::new(renderer),
            more,
            objects: store,
            host,
        })
    }

    #[getter]
    fn sensor(&self, py: Python<'_>) -> Py<Sensor> {
        self.sensor.clone_ref(py)
    }

    /// The host the frames are rendered on: CPU, adapter and driver, in one line.
    #[getter]
    fn host(&self) -> &str {
        &self.host
    }

    fn __repr__(&self) -> String {
        format!(
            "Simulator(Sensor('{}'), host='{}')",
            self.sensor.get().inner.name,
            self.host
        )
    }

    /// The empty finger, (H, W, 3) uint8: what `geltip render --reference` writes. With
    /// sensor noise configured, each call draws fresh noise, as a camera would.
    fn reference<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let mut guard = self.lock()?;
        let r: &mut Renderer = &mut guard;
        let frame = detached(py, "rendering the reference", || r.render_empty())?;
        drop(guard);
        Ok(image_array(py, &frame))
    }

    /// One contact: `(image (H, W, 3) uint8, labels dict, depth_map (H, W) float32 mm)`,
    /// the bytes `geltip render` writes for the same flags. Place it with `at="rotation=30"`
    /// (or `("rotation", 30)`), or `rotation=`, `translation=`, `s=`; or give `pose=` (16 or
    /// 7 numbers, as `--pose`) instead of a place and depth.
    #[pyo3(signature = (*, object = None, at = None, rotation = None, translation = None, s = None, azimuth = None, spin = None, tilt = None, tilt_towards = None, depth = None, pose = None))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        object: Option<&Bound<'py, PyAny>>,
        at: Option<&Bound<'py, PyAny>>,
        rotation: Option<&Bound<'py, PyAny>>,
        translation: Option<&Bound<'py, PyAny>>,
        s: Option<&Bound<'py, PyAny>>,
        azimuth: Option<&Bound<'py, PyAny>>,
        spin: Option<&Bound<'py, PyAny>>,
        tilt: Option<&Bound<'py, PyAny>>,
        tilt_towards: Option<&Bound<'py, PyAny>>,
        depth: Option<&Bound<'py, PyAny>>,
        pose: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let args = ContactArgs {
            object,
            at,
            rotation,
            translation,
            s,
            azimuth,
            spin,
            tilt,
            tilt_towards,
            depth,
            pose,
        };
        let press = args.press("", &self.objects)?;
        let mut guard = self.lock()?;
        let r: &mut Renderer = &mut guard;
        let (frame, truths) = detached(py, "rendering a contact", || {
            // As the CLI: refuse a bad pose before the GPU work.
            press.pose(r.sensor())?;
            r.render_scene(std::slice::from_ref(&press))
        })?;
        drop(guard);
        let truth = truths
            .first()
            .ok_or_else(|| Failure::from(GeltipError::Gpu("no labels for the contact".into())))?;
        frame_tuple(py, &frame, &truth.to_json())
    }

    /// Several contacts in one frame (`geltip render --scene`): a list of dicts with
    /// `render`'s keyword names. Labels: `{"contacts": [...], "mask_pixels", "mask_bbox",
    /// "over_pressed"}`.
    fn render_scene<'py>(
        &self,
        py: Python<'py>,
        contacts: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let presses = self.presses(contacts)?;
        if presses.is_empty() {
            return Err(bad("contacts", "no contacts to render"));
        }
        let mut guard = self.lock()?;
        let r: &mut Renderer = &mut guard;
        let (frame, truths) = detached(py, "rendering a scene", || {
            for p in &presses {
                p.pose(r.sensor())?;
            }
            r.render_scene(&presses)
        })?;
        drop(guard);
        let (count, bbox) = frame.mask();
        let labels = serde_json::json!({
            "contacts": truths.iter().map(|t| t.to_json()).collect::<Vec<_>>(),
            "mask_pixels": count,
            "mask_bbox": bbox,
            "over_pressed": truths.iter().any(|t| t.over_pressed),
        });
        frame_tuple(py, &frame, &labels)
    }

    /// Many single contacts, batched on the GPU (`MAX_BATCH` per submission): `(images (N,
    /// H, W, 3) uint8, labels [dict], depth_maps (N, H, W) float32 | None)`. Each contact is
    /// a dict with `render`'s keyword names except `tilt`, `tilt_towards` and `pose`. Each
    /// frame is written straight into the output arrays (`out=`/`depth_out=` reuse yours:
    /// C-contiguous, writeable, of those shapes and dtypes); `depth_maps=False` skips the
    /// depth maps.
    #[pyo3(signature = (contacts, *, depth_maps = true, out = None, depth_out = None))]
    fn render_batch<'py>(
        &self,
        py: Python<'py>,
        contacts: &Bound<'py, PyAny>,
        depth_maps: bool,
        out: Option<&Bound<'py, PyAny>>,
        depth_out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let presses = self.presses(contacts)?;
        // A press the library would refuse halfway through the batch, refused up front
        // with the contact's index.
        for (k, p) in presses.iter().enumerate() {
            p.hold
                .check()
                .map_err(|e| bad(format!("contacts[{k}]"), e.to_string()))?;
        }
        let list = presses;
        let n = list.len();
        let sensor = &self.sensor.get().inner;
        let (h, w) = (sensor.height as usize, sensor.width as usize);
        let images = output_array::<u8, numpy::Ix4>(py, "out", out, [n, h, w, 3])?;
        let depths = if depth_maps {
            Some(output_array::<f32, numpy::Ix3>(
                py,
                "depth_out",
                depth_out,
                [n, h, w],
            )?)
        } else {
            if depth_out.is_some_and(|d| !d.is_none()) {
                return Err(bad("depth_out", "given with depth_maps=False"));
            }
            None
        };
        let truths = {
            let mut image_rw = images
                .try_readwrite()
                .map_err(|e| bad("out", e.to_string()))?;
            let image_ptr = {
                let s = image_rw
                    .as_slice_mut()
                    .map_err(|e| bad("out", e.to_string()))?;
                OutPtr(s.as_mut_ptr(), s.len())
            };
            let mut depth_rw = match &depths {
                Some(d) => Some(
                    d.try_readwrite()
                        .map_err(|e| bad("depth_out", e.to_string()))?,
                ),
                None => None,
            };
            let depth_ptr = match depth_rw.as_mut() {
                Some(d) => {
                    let s = d
                        .as_slice_mut()
                        .map_err(|e| bad("depth_out", e.to_string()))?;
                    Some(OutPtr(s.as_mut_ptr(), s.len()))
                }
                None => None,
            };
            // Every stream's renderer, always in the same order (no lock-order deadlock).
            let mut guards = vec![self.lock()?];
            for m in &self.more {
                guards.push(m.lock().map_err(|_| poisoned())?);
            }
            let renderers: Vec<&mut Renderer> = guards.iter_mut().map(|g| &mut **g).collect();
            let truths = detached(py, "rendering a batch", move || {
                // SAFETY: see `OutPtr`; the lengths are the arrays' own.
                let images = unsafe { image_ptr.slice() };
                let depths = depth_ptr.map(|d| unsafe { d.slice() });
                render_chunks(renderers, &list, images, depths, (h, w))
            });
            drop(guards);
            drop(depth_rw);
            drop(image_rw);
            truths?
        };
        let labels = PyList::empty(py);
        for t in &truths {
            labels.append(json_to_py(py, &t.to_json())?)?;
        }
        let depths = match depths {
            Some(d) => d.into_any(),
            None => py.None().into_bound(py),
        };
        PyTuple::new(py, [images.into_any(), labels.into_any(), depths])
    }
}

impl Simulator {
    /// A list of contact dicts as presses.
    fn presses(&self, contacts: &Bound<'_, PyAny>) -> PyResult<Vec<Press>> {
        let iter = contacts.try_iter().map_err(|_| {
            bad(
                "contacts",
                format!("expected a list of dicts, got {}", repr(contacts)),
            )
        })?;
        let mut presses = Vec::new();
        for (k, item) in iter.enumerate() {
            let item = item?;
            let field = format!("contacts[{k}]");
            let d = item
                .cast::<PyDict>()
                .map_err(|_| bad(&field, format!("expected a dict, got {}", repr(&item))))?;
            let mut store = Vec::new();
            ContactArgs::from_dict(&field, d, &mut store)?;
            let args = Self::contact_args(&store);
            presses.push(args.press(&format!("{field}."), &self.objects)?);
        }
        Ok(presses)
    }
}

/// `out` if given (checked: dtype, shape, C order, writeable), else a new uninitialised
/// array the caller fills completely.
fn output_array<'py, T: numpy::Element, D: numpy::ndarray::Dimension>(
    py: Python<'py>,
    field: &str,
    given: Option<&Bound<'py, PyAny>>,
    shape: impl numpy::ndarray::IntoDimension<Dim = D> + Copy + std::fmt::Debug,
) -> PyResult<Bound<'py, PyArray<T, D>>> {
    match given.filter(|g| !g.is_none()) {
        None => {
            // SAFETY: `render_batch` writes every element before returning the array.
            Ok(unsafe { PyArray::<T, D>::new(py, shape, false) })
        }
        Some(g) => {
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
    }
}

// ---------------------------------------------------------------------------------------
// Functions

/// Finds the contact in `image` against `reference` (both (H, W, 3) uint8 of the sensor's
/// size): `{"detected", "pixel", "point", "region", "confidence", "regions_found", "note"}`,
/// as `geltip localise` prints.
#[pyfunction]
#[pyo3(signature = (sensor, reference, image, method = "surface"))]
fn localise<'py>(
    py: Python<'py>,
    sensor: &Bound<'py, Sensor>,
    reference: &Bound<'py, PyAny>,
    image: &Bound<'py, PyAny>,
    method: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let s = sensor.get();
    let method = lib(Method::from_name(method))?;
    let reference = rgb_image("reference", reference, &s.inner)?;
    let image = rgb_image("image", image, &s.inner)?;
    let detection = detached(py, "localising", || {
        s.localiser.localise(&reference, &image, method)
    })?;
    json_to_py(py, &detection.to_json())
}

/// Reads an image file (PNG) as an (H, W, 3) uint8 array.
#[pyfunction]
fn load_image<'py>(
    py: Python<'py>,
    path: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let path = path_or_str("path", path)?;
    let img = detached(py, "reading an image", || {
        geltip::localise::load_image(&path)
    })?;
    let (w, h) = img.dimensions();
    let array = PyArray::from_vec(py, img.into_raw());
    array.reshape([h as usize, w as usize, 3])
}

/// Asks the C allocator to keep freed memory for reuse instead of returning it to the OS
/// (glibc only; process-wide, so geltip never does it on import): each frame's fresh image
/// buffers are then not page-faulted in again every frame (1.0-1.4 ms a 640x480 frame on a
/// 2-core VM). True when it applied.
#[pyfunction]
fn keep_freed_memory() -> bool {
    geltip::memory::keep_freed_memory()
}

/// How fast the host's cores run now (`geltip::host_speed::HostSpeed`): a fixed scalar loop's
/// milliseconds on one core and on all cores at once, the best of three tries (some 35 ms).
/// Shared machines run faster and slower by phases; time it beside a speed figure.
#[pyfunction]
fn host_speed(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let speed = py.detach(geltip::host_speed::HostSpeed::measure);
    let d = PyDict::new(py);
    d.set_item("one_core_ms", speed.one_core_ms)?;
    d.set_item("all_cores_ms", speed.all_cores_ms)?;
    Ok(d)
}

#[pymodule]
fn _geltip(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Sensor>()?;
    m.add_class::<Simulator>()?;
    m.add_function(wrap_pyfunction!(localise, m)?)?;
    m.add_function(wrap_pyfunction!(load_image, m)?)?;
    m.add_function(wrap_pyfunction!(keep_freed_memory, m)?)?;
    m.add_function(wrap_pyfunction!(host_speed, m)?)?;
    m.add("MAX_BATCH", MAX_BATCH)?;
    m.add("REGION_NONE", REGION_NONE)?;
    m.add("REGION_HEMISPHERE", REGION_HEMISPHERE)?;
    m.add("REGION_CYLINDER", REGION_CYLINDER)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // "release" for wheels and `maturin develop --release`; benchmarks refuse "debug".
    m.add(
        "BUILD_PROFILE",
        if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        },
    )?;
    Ok(())
}
