//! Library errors on their way to Python: each [`GeltipError`] becomes the exception class
//! of its kind (in `geltip/_errors.py`) carrying the library's one-line message, the one the
//! command line prints after `error: `.

use geltip::GeltipError;
use pyo3::prelude::*;
use pyo3::types::PyType;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// An error on its way to Python: the exception class (in `geltip._errors`) and the message.
pub struct Failure {
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
            | GeltipError::InvalidOption { .. }
            | GeltipError::InvalidMesh { .. }
            | GeltipError::InvalidImage { .. } => "InvalidArgumentError",
            GeltipError::NoAdapter(_) | GeltipError::Gpu(_) | GeltipError::Shader { .. } => {
                "GpuError"
            }
            GeltipError::Io { ref cause, .. } if cause.kind() == std::io::ErrorKind::NotFound => {
                "GeltipFileNotFoundError"
            }
            GeltipError::Io { .. } => "GeltipIOError",
        };
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
                    "GeltipFileNotFoundError" => {
                        pyo3::exceptions::PyFileNotFoundError::new_err(f.message)
                    }
                    _ => pyo3::exceptions::PyValueError::new_err(f.message),
                },
            }
        })
    }
}

/// An argument Python cannot convert: `InvalidArgumentError` (a `ValueError`) whose message
/// starts with the argument's name.
pub fn bad(field: impl AsRef<str>, reason: impl AsRef<str>) -> PyErr {
    Failure {
        class: "InvalidArgumentError",
        message: format!("{}: {}", field.as_ref(), reason.as_ref()),
    }
    .into()
}

/// The library's result, its error raised as its Python class.
pub fn lib<T>(r: geltip::Result<T>) -> PyResult<T> {
    r.map_err(|e| Failure::from(e).into())
}

/// Runs `f` with the GIL released, turning a panic into a `GpuError` (the interpreter must
/// survive whatever the GPU stack does).
pub fn detached<T: Send>(
    py: Python<'_>,
    what: &str,
    f: impl FnOnce() -> geltip::Result<T> + Send,
) -> PyResult<T> {
    match py.detach(|| catch_unwind(AssertUnwindSafe(f))) {
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
