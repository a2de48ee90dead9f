//! `geltip.Simulator`: the renderer of one sensor (its render streams, the objects it has
//! loaded), rendering one contact, a scene or a batch.

use crate::contact::{specs_of, ContactArgs};
use crate::convert::{array_out, depth_array, image_array, json_to_py, path_or_str};
use crate::errors::{detached, lib};
use crate::sensor::Sensor;
use crate::{batch, mesh, scenes};
use geltip::object::ObjectCache;
use geltip::render::gpu::Renderer;
use geltip::render::pool::RenderPool;
use geltip::render::Frame;
use geltip::scene::{presses, ContactSpec};
use geltip::GeltipError;
use numpy::PyArray3;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use serde_json::Value;
use std::sync::{Mutex, MutexGuard, PoisonError};

/// The renderer of one sensor, holding the GPU context, pipelines and the reference frame.
#[pyclass(module = "geltip", frozen)]
pub struct Simulator {
    sensor: Py<Sensor>,
    /// Render stream 0 renders everything; `render_batch` shares its submissions among all
    /// of them (`streams=`). Locked only with the GIL released.
    pool: Mutex<RenderPool>,
    /// Objects by the name they were asked for: a mesh is loaded and baked once per
    /// Simulator (and its GPU grid uploaded once: the renderer keys it by the object).
    objects: Mutex<ObjectCache>,
    host: String,
}

/// The object cache, locked. A panic while it was held became a `GpuError` then; the cache
/// only ever holds whole objects, so it stays usable.
fn objects(sim: &Simulator) -> MutexGuard<'_, ObjectCache> {
    sim.objects.lock().unwrap_or_else(PoisonError::into_inner)
}

impl Simulator {
    pub fn sensor(&self) -> &geltip::Sensor {
        &self.sensor.get().inner
    }

    /// The render streams, locked. After a panic while they were held (raised as a
    /// `GpuError`) the GPU state is unknown: every later call is refused.
    pub fn pool(&self) -> geltip::Result<MutexGuard<'_, RenderPool>> {
        self.pool.lock().map_err(|_| {
            GeltipError::Gpu(
                "the simulator failed in an earlier call (internal error); create a new Simulator"
                    .into(),
            )
        })
    }

    /// The presses of `specs` (objects loaded through the Simulator's cache), placed on the
    /// finger when `placed`; errors name the contact (`contacts[1].depth: ...`).
    pub fn presses(
        &self,
        specs: &[ContactSpec],
        placed: bool,
    ) -> geltip::Result<Vec<geltip::render::Press>> {
        let sensor = placed.then(|| self.sensor());
        presses(specs, &mut objects(self), sensor)
    }

    /// Stream 0 of the pool, locked, for `f`.
    fn on_renderer<T>(
        &self,
        f: impl FnOnce(&mut Renderer) -> geltip::Result<T>,
    ) -> geltip::Result<T> {
        f(&mut self.pool()?.streams_mut()[0])
    }
}

/// `(image, labels, depth map)` of a frame.
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
        let sensor = Sensor::of(py, sensor)?;
        let names = objects
            .unwrap_or_default()
            .iter()
            .enumerate()
            .map(|(k, o)| path_or_str(&format!("objects[{k}]"), o))
            .collect::<PyResult<Vec<_>>>()?;
        let inner = &sensor.get().inner;
        let (pool, objects) = detached(py, "starting the renderer", || {
            let mut objects = ObjectCache::default();
            for name in &names {
                objects.get(name)?;
            }
            Ok((RenderPool::start(inner, streams, &[])?, objects))
        })?;
        let host = geltip::gpu::host_description(pool.first().adapter());
        Ok(Simulator {
            sensor,
            pool: Mutex::new(pool),
            objects: Mutex::new(objects),
            host,
        })
    }

    #[getter(sensor)]
    fn py_sensor(&self, py: Python<'_>) -> Py<Sensor> {
        self.sensor.clone_ref(py)
    }

    /// The host the frames are rendered on: CPU, adapter and driver, in one line.
    #[getter]
    fn host(&self) -> &str {
        &self.host
    }

    /// Frames one GPU submission renders (`render_batch`, `render_scenes` and the MuJoCo
    /// adapter hand over that many at a time): 8 on a software rasteriser, 64 on a GPU by
    /// default; 1 to `MAX_BATCH`. The frames are the same whatever it is.
    #[getter]
    fn batch_frames(&self) -> PyResult<usize> {
        Ok(lib(self.pool())?.batch_frames())
    }

    #[setter]
    fn set_batch_frames(&self, frames: usize) -> PyResult<()> {
        lib(lib(self.pool())?.set_batch_frames(frames))
    }

    fn __repr__(&self) -> String {
        format!(
            "Simulator(Sensor('{}'), host='{}')",
            self.sensor().name,
            self.host
        )
    }

    /// The empty finger, (H, W, 3) uint8: what `geltip render --reference` writes. With
    /// sensor noise configured, each call draws fresh noise, as a camera would.
    fn reference<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let frame = detached(py, "rendering the reference", || {
            self.on_renderer(|r| r.render_empty())
        })?;
        Ok(image_array(py, &frame))
    }

    /// One contact: `(image (H, W, 3) uint8, labels dict, depth_map (H, W) float32 mm)`,
    /// the bytes `geltip render` writes for the same flags. Place it with `at="rotation=30"`
    /// (or `("rotation", 30)`), or `rotation=`, `translation=`, `s=`; or give `pose=` (16 or
    /// 7 numbers, as `--pose`) instead of a place and depth, and `approach=` (3 numbers) the
    /// direction its depth is measured along.
    #[pyo3(signature = (*, object = None, at = None, rotation = None, translation = None, s = None, azimuth = None, spin = None, tilt = None, tilt_towards = None, depth = None, pose = None, approach = None))]
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
        approach: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let spec = ContactArgs::from_kwargs([
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
            approach,
        ])
        .spec()?;
        let (frame, truths) = detached(py, "rendering a contact", || {
            let press = spec.press(&mut objects(self))?;
            // As the CLI: refuse a press that does not fit the finger before the GPU work.
            press.pose(self.sensor())?;
            self.on_renderer(|r| r.render_scene(std::slice::from_ref(&press)))
        })?;
        let truth = lib(truths
            .first()
            .ok_or_else(|| GeltipError::Gpu("no labels for the contact".into())))?;
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
        let specs = specs_of(contacts)?;
        let (frame, truths) = detached(py, "rendering a scene", || {
            let presses = self.presses(&specs, true)?;
            self.on_renderer(|r| r.render_scene(&presses))
        })?;
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
    /// a dict with `render`'s keyword names. Each frame is written straight into the output
    /// arrays (`out=`/`depth_out=` reuse yours: C-contiguous, writeable, of those shapes and
    /// dtypes); `depth_maps=False` skips the depth maps.
    #[pyo3(signature = (contacts, *, depth_maps = true, out = None, depth_out = None))]
    fn render_batch<'py>(
        &self,
        py: Python<'py>,
        contacts: &Bound<'py, PyAny>,
        depth_maps: bool,
        out: Option<&Bound<'py, PyAny>>,
        depth_out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let specs = specs_of(contacts)?;
        let outputs =
            batch::Outputs::new(py, self.sensor(), specs.len(), depth_maps, out, depth_out)?;
        batch::render(py, self, &specs, outputs)
    }

    /// Many scenes (frames of several contacts each, as `render_scene`'s lists), batched on
    /// the GPU (`MAX_BATCH` frames per submission): `(images (N, H, W, 3) uint8, labels
    /// [dict], depth_maps (N, H, W) float32 | None)`. With `skip_untouching=True` a posed
    /// object that does not touch the finger is left out of its frame instead of raising,
    /// and the frame's labels list it under `"untouched"` (indices into its list); a frame
    /// with none touching is the empty finger. `out=`/`depth_out=` as `render_batch`.
    #[pyo3(signature = (scenes, *, skip_untouching = false, depth_maps = false, out = None, depth_out = None))]
    fn render_scenes<'py>(
        &self,
        py: Python<'py>,
        scenes: &Bound<'py, PyAny>,
        skip_untouching: bool,
        depth_maps: bool,
        out: Option<&Bound<'py, PyAny>>,
        depth_out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let frames = scenes::specs_of_scenes(scenes)?;
        let outputs =
            batch::Outputs::new(py, self.sensor(), frames.len(), depth_maps, out, depth_out)?;
        scenes::render(py, self, &frames, skip_untouching, outputs)
    }

    /// Makes a mesh given as `vertices` ((N, 3) numbers, mm) and `faces` ((M, 3) vertex
    /// indices, counter-clockwise seen from outside) the object `name` for this Simulator's
    /// contacts, placed and baked as the same vertices in an OBJ file would be (about 1.5 s
    /// for 4 000 triangles). Returns the point of the mesh (float64 (3,), mm, in the
    /// vertices' frame) that became the object's origin, its top: a pose of the object is
    /// the vertices' frame moved there.
    fn add_mesh<'py>(
        &self,
        py: Python<'py>,
        name: &str,
        vertices: &Bound<'py, PyAny>,
        faces: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let mesh = mesh::mesh_of(vertices, faces)?;
        let name = name.to_string();
        let top = detached(py, "baking a mesh", || {
            let (object, top) = geltip::object::Object::from_mesh(&name, mesh)?;
            objects(self).insert(&name, object);
            Ok(top)
        })?;
        array_out(py, &[], 3, top.to_array().to_vec())
    }
}
