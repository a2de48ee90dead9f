//! `geltip._geltip.dataset_labels`: a set's `labels.jsonl` read by the library's reader, for
//! `geltip.Dataset` (pure Python otherwise).

use crate::convert::{json_to_py, path_or_str};
use crate::errors::detached;
use pyo3::prelude::*;
use pyo3::types::PyList;
use std::path::PathBuf;

/// The label lines of the set in `root`, as dicts in file order (the library's rule: only
/// an unfinished last line is left out; any other bad line is an error naming it).
#[pyfunction]
pub fn dataset_labels<'py>(
    py: Python<'py>,
    root: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyList>> {
    let root = PathBuf::from(path_or_str("root", root)?);
    let path = root.join(geltip::jobs::dataset::LABELS);
    let lines = detached(py, "reading labels", || {
        geltip::jobs::dataset::read_labels(&path)
    })?;
    let out = PyList::empty(py);
    for line in &lines {
        out.append(json_to_py(py, &line.value)?)?;
    }
    Ok(out)
}
