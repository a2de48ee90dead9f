//! `Simulator.render_batch`: many contacts rendered on the Simulator's render streams, each
//! frame written straight into the NumPy arrays returned (the output arrays and the
//! submissions are shared with `render_scenes`).

use crate::convert::{json_to_py, output_array, rgba_to_rgb};
use crate::errors::{bad, detached};
use crate::simulator::Simulator;
use geltip::render::gpu::Renderer;
use geltip::render::pool::RenderPool;
use geltip::render::Frame;
use geltip::scene::ContactSpec;
use numpy::{Ix3, Ix4, PyArray, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};
use rayon::prelude::*;

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

impl<'py> Outputs<'py> {
    /// Runs `render` with the GIL released on the arrays' pixels: the images' (RGB), and
    /// the depth maps' when there are any.
    pub fn fill<T: Send>(
        &self,
        py: Python<'py>,
        what: &str,
        render: impl FnOnce(&mut [u8], Option<&mut [f32]>) -> geltip::Result<T> + Send,
    ) -> PyResult<T> {
        let mut images = self
            .images
            .try_readwrite()
            .map_err(|e| bad("out", e.to_string()))?;
        let mut depths = match &self.depths {
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
        detached(py, what, || render(image_px, depth_px))
    }

    /// With the GIL released, makes the jobs (`jobs`, which checks them) and renders them
    /// into the arrays with `work` on `sim`'s render streams ([`render_into`]); `what` names
    /// the work in a detached error. What `work` gives with each frame, in order.
    pub fn render<J: Sync, T: Send>(
        &self,
        py: Python<'py>,
        sim: &Simulator,
        what: &str,
        jobs: impl FnOnce() -> geltip::Result<Vec<J>> + Send,
        work: impl Fn(&mut Renderer, usize, &[J]) -> geltip::Result<Vec<(Frame, T)>> + Sync + Send,
    ) -> PyResult<Vec<T>> {
        let size = self.size;
        self.fill(py, what, |images, depths| {
            let jobs = jobs()?;
            render_into(&mut *sim.pool()?, &jobs, images, depths, size, work)
        })
    }

    /// `(images, labels, depth maps or None)`, the labels converted from JSON.
    pub fn with_labels(
        self,
        py: Python<'py>,
        labels: impl IntoIterator<Item = serde_json::Value>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let list = PyList::empty(py);
        for l in labels {
            list.append(json_to_py(py, &l)?)?;
        }
        let depths = match self.depths {
            Some(d) => d.into_any(),
            None => py.None().into_bound(py),
        };
        PyTuple::new(py, [self.images.into_any(), list.into_any(), depths])
    }
}

/// Renders `specs` into `outputs`: `(images, [labels], depth maps or None)`.
pub fn render<'py>(
    py: Python<'py>,
    sim: &Simulator,
    specs: &[ContactSpec],
    outputs: Outputs<'py>,
) -> PyResult<Bound<'py, PyTuple>> {
    // Every press is checked before any is rendered, so that an error names its index.
    let truths = outputs.render(
        py,
        sim,
        "rendering a batch",
        || sim.presses(specs, false),
        |r, _, p| r.render_batch(p),
    )?;
    outputs.with_labels(py, truths.iter().map(|t| t.to_json()))
}

/// Renders `jobs` (a frame each) in submissions of the pool's batch on its streams
/// (submission c on stream c mod n, so the same calls give the same frames) with `work`,
/// writing frame i into slot i of `images` (RGB) and `depths`; what `work` gives with each
/// frame comes back in list order. `work` gets the index of its submission's first job.
pub fn render_into<J: Sync, T: Send>(
    pool: &mut RenderPool,
    jobs: &[J],
    images: &mut [u8],
    depths: Option<&mut [f32]>,
    (h, w): (usize, usize),
    work: impl Fn(&mut Renderer, usize, &[J]) -> geltip::Result<Vec<(Frame, T)>> + Sync,
) -> geltip::Result<Vec<T>> {
    let (frame_rgb, frame_px) = (h * w * 3, h * w);
    let batch = pool.batch_frames();
    let mut depth_parts: Vec<Option<&mut [f32]>> = match depths {
        Some(d) => d.chunks_mut(batch * frame_px).map(Some).collect(),
        None => Vec::new(),
    };
    depth_parts.resize_with(jobs.len().div_ceil(batch), || None);
    let submissions = jobs
        .chunks(batch)
        .enumerate()
        .zip(images.chunks_mut(batch * frame_rgb))
        .zip(depth_parts);
    let done = pool.map(
        submissions,
        |r: &mut Renderer, (((c, jobs), image), mut depth)| {
            let (frames, out): (Vec<Frame>, Vec<T>) = work(r, c * batch, jobs)?.into_iter().unzip();
            // Side by side: a frame's copy into the arrays is as long as its render on a GPU.
            image
                .par_chunks_mut(frame_rgb)
                .zip(&frames)
                .for_each(|(dst, f)| rgba_to_rgb(&f.rgba, dst));
            if let Some(d) = depth.as_deref_mut() {
                d.par_chunks_mut(frame_px)
                    .zip(&frames)
                    .for_each(|(dst, f)| dst.copy_from_slice(&f.indentation));
            }
            Ok(out)
        },
    )?;
    Ok(done.into_iter().flatten().collect())
}
