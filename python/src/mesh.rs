//! `Simulator.add_mesh`'s arrays: vertices and faces as the library's `Mesh`. Whether they
//! make a usable object (finite vertices, indices in range, triangles at all) is the
//! library's to say (`Object::from_mesh`).

use crate::convert::describe_array;
use crate::errors::bad;
use geltip::object::Mesh;
use glam::DVec3;
use numpy::{AllowTypeChange, PyArrayLikeDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// `vertices` ((N, 3) numbers, mm) and `faces` ((M, 3) non-negative integers).
pub fn mesh_of(vertices: &Bound<'_, PyAny>, faces: &Bound<'_, PyAny>) -> PyResult<Mesh> {
    let v: PyArrayLikeDyn<'_, f64, AllowTypeChange> = vertices.extract().map_err(|_| {
        bad(
            "vertices",
            format!(
                "expected an (N, 3) array of numbers, got {}",
                describe_array(vertices)
            ),
        )
    })?;
    if !matches!(v.shape(), [_, 3]) {
        return Err(bad(
            "vertices",
            format!("expected an (N, 3) array, got shape {:?}", v.shape()),
        ));
    }
    let f: PyArrayLikeDyn<'_, i64, AllowTypeChange> = faces.extract().map_err(|_| {
        bad(
            "faces",
            format!(
                "expected an (M, 3) array of vertex indices, got {}",
                describe_array(faces)
            ),
        )
    })?;
    if !matches!(f.shape(), [_, 3]) {
        return Err(bad(
            "faces",
            format!("expected an (M, 3) array, got shape {:?}", f.shape()),
        ));
    }
    let positions = v
        .as_array()
        .rows()
        .into_iter()
        .map(|r| DVec3::new(r[0], r[1], r[2]))
        .collect();
    let mut triangles = Vec::with_capacity(f.shape()[0]);
    for (t, row) in f.as_array().rows().into_iter().enumerate() {
        let mut tri = [0u32; 3];
        for (slot, &i) in tri.iter_mut().zip(row.iter()) {
            *slot = u32::try_from(i).map_err(|_| {
                bad(
                    "faces",
                    format!("face {t} holds {i}, not a vertex index (0 to 4294967295)"),
                )
            })?;
        }
        triangles.push(tri);
    }
    Ok(Mesh {
        positions,
        triangles,
    })
}
