//! `geltip._geltip`: the native half of the Python package, a thin layer over the geltip
//! library. It converts (NumPy arrays and keyword arguments in, arrays and dicts out) and
//! leaves every check of a value to the library, whose errors are raised as the Python
//! exception class of their kind (see `geltip/_errors.py`) with the one-line message the
//! command line prints. Rendering and localising run with the GIL released; a panic inside
//! the library is caught and raised as a `GpuError` instead of unwinding into the
//! interpreter.
//!
//! - `errors`: library errors as Python exceptions, the GIL released around library calls.
//! - `convert`: JSON, images, depth maps, points and pixels, numbers and paths.
//! - `contact`: a contact's keyword arguments or dict as the library's `ContactSpec`.
//! - `sensor`: `Sensor`. `simulator`: `Simulator`; `batch`: its `render_batch`; `scenes`:
//!   its `render_scenes`; `mesh`: its `add_mesh`'s arrays.
//! - `localise`: `localise`, `load_image`, `save_image`. `host`: `keep_freed_memory`, `host_speed`.
//! - `dataset`: `dataset_labels`, a set's labels by the library's reader.
//! - `evaluate`: `evaluate`, a detector (a function or a built-in) scored on a set or suite.
//! - `calibrate`: `calibrate`, a sensor fitted to a real sensor's empty frames.

mod batch;
mod calibrate;
mod contact;
mod convert;
mod dataset;
mod errors;
mod evaluate;
mod host;
mod localise;
mod mesh;
mod scenes;
mod sensor;
mod simulator;

use geltip::render::gpu::MAX_BATCH;
use pyo3::prelude::*;
use sensor::{REGION_CYLINDER, REGION_HEMISPHERE, REGION_NONE};

#[pymodule]
fn _geltip(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<sensor::Sensor>()?;
    m.add_class::<simulator::Simulator>()?;
    m.add_function(wrap_pyfunction!(localise::localise, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate::evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(dataset::dataset_labels, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(localise::load_image, m)?)?;
    m.add_function(wrap_pyfunction!(localise::save_image, m)?)?;
    m.add_function(wrap_pyfunction!(host::keep_freed_memory, m)?)?;
    m.add_function(wrap_pyfunction!(host::host_speed, m)?)?;
    m.add("MAX_BATCH", MAX_BATCH)?;
    m.add(
        "PRIMITIVE_SIZE_MM",
        (
            geltip::object::primitive::MIN_PRIMITIVE_MM,
            geltip::object::primitive::MAX_PRIMITIVE_MM,
        ),
    )?;
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
