//! The host's side of speed figures: the allocator setting and the cores' speed now.

use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Asks the C allocator to keep freed memory for reuse instead of returning it to the OS
/// (glibc only; process-wide, so geltip never does it on import): each frame's fresh image
/// buffers are then not page-faulted in again every frame (1.0-1.4 ms a 640x480 frame on a
/// 2-core VM). True when it applied.
#[pyfunction]
pub fn keep_freed_memory() -> bool {
    geltip::memory::keep_freed_memory()
}

/// How fast the host's cores run now (`geltip::host_speed::HostSpeed`): a fixed scalar loop's
/// milliseconds on one core and on all cores at once, the best of three tries (some 35 ms).
/// Shared machines run faster and slower by phases; time it beside a speed figure.
#[pyfunction]
pub fn host_speed(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let speed = py.detach(geltip::host_speed::HostSpeed::measure);
    let d = PyDict::new(py);
    d.set_item("one_core_ms", speed.one_core_ms)?;
    d.set_item("all_cores_ms", speed.all_cores_ms)?;
    Ok(d)
}
