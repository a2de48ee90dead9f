//! `Simulator.render_batch`: many contacts rendered on the Simulator's render streams, each
//! frame written straight into the NumPy arrays returned.

use crate::convert::{json_to_py, output_array, rgba_to_rgb};
use crate::errors::{bad, detached};
use crate::simulator::Simulator;
use geltip::render::gpu::{Renderer, MAX_BATCH};
use geltip::render::pool::RenderPool;
use geltip::render::{GroundTruth, Press};
use geltip::scene::ContactSpec;
use numpy::{Ix3, Ix4, PyArray, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};

/// The arrays a batch is written into: images (N, H, W, 3) uint8 and, unless left out, depth
/// maps (N, H, W) float32; the caller's (`out=`, `depth_out=`) or new ones.
pub struct Outputs<'py> {
    images: Bound<'py, PyArray<u8, Ix4>>,
    depths: Option<Bound<'py, PyArray<f32, Ix3>>>,
    size: (usize, usize),
}

impl<'py> Outputs<'py> {
    pub fn new(
        py: Python<'py>,
        sensor: &geltip::Sensor,
        n: usize,
        depth_maps: bool,
        out: Option<&Bound<'py, PyAny>>,
        depth_out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Outputs<'py>> {
        let (h, w) = (sensor.height as usize, sensor.width as usize);
        let images = output_array(py, "out", out, [n, h, w, 3])?;
        let depths = if depth_maps {
            Some(output_array(py, "depth_out", depth_out, [n, h, w])?)
        } else if depth_out.is_some_and(|d| !d.is_none()) {
            return Err(bad("depth_out", "given with depth_maps=False"));
        } else {
            None
        };
        Ok(Outputs {
            images,
            depths,
            size: (h, w),
        })
    }
}

/// Renders `specs` into `outputs`: `(images, [labels], depth maps or None)`.
pub fn render<'py>(
    py: Python<'py>,
    sim: &Simulator,
    specs: &[ContactSpec],
    outputs: Outputs<'py>,
) -> PyResult<Bound<'py, PyTuple>> {
    let truths = {
        let mut images = outputs
            .images
            .try_readwrite()
            .map_err(|e| bad("out", e.to_string()))?;
        let mut depths = match &outputs.depths {
            Some(d) => Some(
                d.try_readwrite()
                    .map_err(|e| bad("depth_out", e.to_string()))?,
            ),
            None => None,
        };
        let image_px = images
            .as_slice_mut()
            .map_err(|e| bad("out", e.to_string()))?;
        let depth_px = match depths.as_mut() {
            Some(d) => Some(
                d.as_slice_mut()
                    .map_err(|e| bad("depth_out", e.to_string()))?,
            ),
            None => None,
        };
        detached(py, "rendering a batch", || {
            // Every press is checked before any is rendered, so that an error names its index.
            let presses = sim.presses(specs, false)?;
            render_into(
                &mut *sim.pool()?,
                &presses,
                image_px,
                depth_px,
                outputs.size,
            )
        })?
    };
    let labels = PyList::empty(py);
    for t in &truths {
        labels.append(json_to_py(py, &t.to_json())?)?;
    }
    let depths = match outputs.depths {
        Some(d) => d.into_any(),
        None => py.None().into_bound(py),
    };
    PyTuple::new(py, [outputs.images.into_any(), labels.into_any(), depths])
}

/// Renders `presses` in submissions of [`MAX_BATCH`] on the pool's streams (submission c on
/// stream c mod n, so the same calls give the same frames), writing frame i into slot i of
/// `images` (RGB) and `depths`; the labels in list order.
fn render_into(
    pool: &mut RenderPool,
    presses: &[Press],
    images: &mut [u8],
    depths: Option<&mut [f32]>,
    (h, w): (usize, usize),
) -> geltip::Result<Vec<GroundTruth>> {
    let (frame_rgb, frame_px) = (h * w * 3, h * w);
    let mut depth_parts: Vec<Option<&mut [f32]>> = match depths {
        Some(d) => d.chunks_mut(MAX_BATCH * frame_px).map(Some).collect(),
        None => Vec::new(),
    };
    depth_parts.resize_with(presses.len().div_ceil(MAX_BATCH), || None);
    let submissions = presses
        .chunks(MAX_BATCH)
        .zip(images.chunks_mut(MAX_BATCH * frame_rgb))
        .zip(depth_parts);
    let labelled = pool.map(
        submissions,
        |r: &mut Renderer, ((presses, image), mut depth)| {
            let mut truths = Vec::with_capacity(presses.len());
            for (k, (frame, truth)) in r.render_batch(presses)?.into_iter().enumerate() {
                rgba_to_rgb(&frame.rgba, &mut image[k * frame_rgb..(k + 1) * frame_rgb]);
                if let Some(d) = depth.as_deref_mut() {
                    d[k * frame_px..(k + 1) * frame_px].copy_from_slice(&frame.indentation);
                }
                truths.push(truth);
            }
            Ok(truths)
        },
    )?;
    Ok(labelled.into_iter().flatten().collect())
}
