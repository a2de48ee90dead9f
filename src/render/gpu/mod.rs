//! The GPU renderer: the stages as compute pipelines over one bind group layout. The empty
//! finger is rendered once; each frame copies it and re-renders only the pixels that can
//! see its contacts' footprints: of the footprints' pixel rectangle, the tiles whose rays'
//! probes read a displaced texel are listed, of those the pixels whose rays the deformation
//! reaches, and the camera casts and shades that list alone, sized on the GPU (indirect
//! dispatch). The frames of a submission ([`Renderer::batch_frames`]) are recorded in waves
//! of [`Renderer::lanes`] frames, each stage one dispatch over the whole wave (sized by the
//! sum of its frames' work, each workgroup finding its frame), each frame into its own
//! slice of the output buffers and on its own heightfield, and read back together; the next
//! submission's frames are prepared on the CPU meanwhile.
//!
//! - `resources.rs` and `pipelines.rs`: everything the renderer binds and runs, made in one
//!   place; [`bindings`]: the one table of bindings; [`layout`]: where the shaders put
//!   things (held to `shaders/` by `tests/shaders.rs`).
//! - `frame.rs`: the one frame path; `stages.rs`: each stage's dispatches; `record.rs`: passes
//!   and profiling; `readback.rs`: frames back to the CPU; `prepare.rs`: the CPU's share.
//! - `reference.rs`: the empty finger; `profile.rs`, `rays.rs`, `streams.rs`: the profile
//!   of a frame, the lens rays for tests, renderers on devices of their own.

pub mod bindings;
mod frame;
pub mod layout;
mod pipelines;
mod prepare;
mod profile;
mod rays;
mod readback;
mod record;
mod reference;
mod resources;
mod stages;
mod streams;

pub use prepare::{PreparedBatch, Preparer};

use crate::error::{GeltipError, Result};
use crate::gpu::GpuContext;
use crate::object::Object;
use crate::render::softness::Softness;
use crate::render::uniforms::{object_kind, FrameUniform, SensorUniform};
use crate::render::{Frame, GroundTruth, HeightfieldGrid, Press, Rect};
use crate::sensor::Sensor;
use pipelines::Pipelines;
use resources::{whole_image, Resources};
use std::sync::Arc;
use std::time::{Duration, Instant};
use wgpu::util::DeviceExt;

/// Frames one submission takes at most ([`Renderer::set_batch_frames`]).
pub const MAX_BATCH: usize = 256;

/// Frames a renderer records into one submission unless told otherwise: a few on a software
/// device, whose cores render the frames anyway (more only hold memory), many on a GPU,
/// where a frame's own work is short and what a submission costs is fixed.
pub fn default_batch(adapter: &wgpu::AdapterInfo) -> usize {
    match adapter.device_type {
        wgpu::DeviceType::Cpu => 8,
        _ => 64,
    }
}

/// Frames of a submission whose stages are recorded side by side unless told otherwise
/// ([`Renderer::set_lanes`]): a batch's worth, as many as [`LANES_BYTES`] of heightfields
/// hold (a lane's heightfield of `texels` per side takes 48 bytes a texel, its buffers and
/// maps). On a GPU one frame's stage is too little work to fill it and each dispatch and
/// copy costs its own fixed time (a barrier); on a software device each dispatch and pass
/// has a fixed cost too, and a wave's dispatches run only its frames' own workgroups. The
/// renderer takes fewer where the device cannot bind that many at once.
pub fn default_lanes(adapter: &wgpu::AdapterInfo, texels: u32) -> usize {
    let lane_bytes = 48 * texels as u64 * texels as u64;
    (LANES_BYTES / lane_bytes.max(1)).clamp(1, default_batch(adapter) as u64) as usize
}

/// GPU memory the default lanes' heightfields take at most.
pub const LANES_BYTES: u64 = 256 << 20;

/// A contact a frame of [`Renderer::render_scenes`] shows: its index in the frame's list of
/// presses, and its labels.
pub type Shown = (usize, GroundTruth);

/// Seconds spent in each phase of the last batch.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Timings {
    /// CPU work before recording: poses, footprints, uniforms.
    pub prepare: Duration,
    /// Recording, submitting and waiting for the GPU work, which ends with copying the
    /// frames to mappable memory (one submission, one wait), and mapping them; while the GPU
    /// works, the frames' pixels that come from the reference are laid out.
    pub render: Duration,
    /// Unpacking the mapped frames into images and labels.
    pub readback: Duration,
    /// Of `render`, the CPU's share: planning, binding and recording the frames until the
    /// submission (the rest is the GPU's work and the wait for it).
    pub record: Duration,
    /// Pixels the camera and LED stages re-rendered (the touched lists' lengths), summed.
    pub touched_pixels: u64,
    /// Tiles of 8 x 8 pixels whose pixels the touched lists were chosen from (the tile
    /// lists' lengths), summed.
    pub listed_tiles: u64,
    /// Commands recorded: compute dispatches, and copies and clears (wgpu puts a barrier
    /// before each that writes), then the copies that read the frames back, summed.
    pub dispatches: u64,
    pub copies: u64,
    pub readback_copies: u64,
}

impl Timings {
    /// Adds `other`'s phases and pixels to these (totals over several batches or frames).
    pub fn add(&mut self, other: &Timings) {
        self.prepare += other.prepare;
        self.render += other.render;
        self.readback += other.readback;
        self.record += other.record;
        self.touched_pixels += other.touched_pixels;
        self.listed_tiles += other.listed_tiles;
        self.dispatches += other.dispatches;
        self.copies += other.copies;
        self.readback_copies += other.readback_copies;
    }
}

/// A renderer for one sensor.
pub struct Renderer {
    ctx: &'static GpuContext,
    sensor: Sensor,
    grid: HeightfieldGrid,
    resources: Resources,
    pipelines: Pipelines,
    /// Per lane, the texels its heightfield's maps may hold non-zero (the texel span of the
    /// last frame on it).
    dirty: Vec<Option<Rect>>,
    /// Frames recorded side by side, each on a heightfield of its own ([`Self::set_lanes`]).
    lanes: usize,
    /// Frames recorded into one submission ([`Self::batch_frames`]).
    batch: usize,
    /// The empty finger as the camera records it (its softness applied).
    reference: Frame,
    /// The camera's softness, and the empty finger's pixels before it, which frames are
    /// assembled on before they are softened.
    softness: Option<(Softness, Vec<u8>)>,
    /// Frames given noise so far: each draws its seed from it ([`Self::next_noise_seed`]).
    seed_counter: u32,
    timings: Timings,
}

impl Renderer {
    /// Whether the device is a software one (lavapipe): its copies are memory copies and
    /// its passes run on the same cores, so a wave's starts and heightfield copies are
    /// recorded a frame at a time rather than as one pass or copy for the wave.
    fn software(&self) -> bool {
        self.ctx.adapter_info.device_type == wgpu::DeviceType::Cpu
    }

    /// Compiles the pipelines, allocates the buffers and renders the empty finger once, on
    /// the process's shared device.
    pub fn new(sensor: &Sensor) -> Result<Renderer> {
        Renderer::on(sensor, GpuContext::shared()?)
    }

    /// As [`Renderer::new`], on the device of `ctx` (e.g. [`GpuContext::stream`]: renderers
    /// on different devices render at the same time).
    pub fn on(sensor: &Sensor, ctx: &'static GpuContext) -> Result<Renderer> {
        let grid = HeightfieldGrid::for_sensor(sensor);
        let batch = default_batch(&ctx.adapter_info);
        let lanes = default_lanes(&ctx.adapter_info, grid.texels)
            .min(resources::max_lanes(ctx, sensor, &grid));
        let mut resources = Resources::new(ctx, sensor, &grid, batch)?;
        resources.reserve_lanes(ctx, lanes);
        let constants = SensorUniform::new(sensor, &grid).pipeline_constants();
        let pipelines = Pipelines::new(ctx, &resources.pipeline_layout, constants)?;
        let mut renderer = Renderer {
            ctx,
            sensor: sensor.clone(),
            grid,
            resources,
            pipelines,
            dirty: vec![None; lanes],
            lanes,
            batch,
            reference: Frame {
                width: sensor.width,
                height: sensor.height,
                rgba: Vec::new(),
                indentation: Vec::new(),
            },
            softness: Softness::of(sensor).map(|s| (s, Vec::new())),
            seed_counter: 0,
            timings: Timings::default(),
        };
        renderer.render_reference()?;
        Ok(renderer)
    }

    /// The sensor this renderer draws.
    pub fn sensor(&self) -> &Sensor {
        &self.sensor
    }

    /// Frames recorded into one submission: [`Self::render_batch`] and
    /// [`Self::render_scenes`] render in chunks of this many, and the render pool's users
    /// ([`crate::render::pool::RenderPool::batch_frames`]) hand over submissions of it.
    pub fn batch_frames(&self) -> usize {
        self.batch
    }

    /// Records `frames` frames (1 to [`MAX_BATCH`]) into one submission from now on; the
    /// frames are the same whatever the batch (each draws its noise seed in turn).
    pub fn set_batch_frames(&mut self, frames: usize) -> Result<()> {
        if !(1..=MAX_BATCH).contains(&frames) {
            return Err(GeltipError::input(
                "batch",
                format!("{frames} frames a submission; 1 to {MAX_BATCH}"),
            ));
        }
        resources::check_frames(self.ctx, &self.sensor, frames)?;
        self.resources.reserve_frames(self.ctx, frames);
        self.batch = frames;
        Ok(())
    }

    /// Frames of a submission recorded side by side ([`default_lanes`]).
    pub fn lanes(&self) -> usize {
        self.lanes
    }

    /// Records the stages of `lanes` frames (1 to [`MAX_BATCH`], and as many as the device
    /// binds at once) side by side from now on: each stage of all of them in one dispatch,
    /// each frame on a heightfield of its own (`lanes` heightfields held). The frames are the
    /// same whatever it is.
    pub fn set_lanes(&mut self, lanes: usize) -> Result<()> {
        let most = resources::max_lanes(self.ctx, &self.sensor, &self.grid);
        if !(1..=MAX_BATCH.min(most)).contains(&lanes) {
            return Err(GeltipError::input(
                "lanes",
                format!(
                    "{lanes} frames side by side; 1 to {} on this device",
                    MAX_BATCH.min(most)
                ),
            ));
        }
        if lanes > self.resources.heightfield.lanes() as usize {
            self.resources.reserve_lanes(self.ctx, lanes);
            // A new heightfield is zero everywhere.
            self.dirty = vec![None; lanes];
        }
        self.lanes = lanes;
        Ok(())
    }

    /// The heightfield grid.
    pub fn grid(&self) -> &HeightfieldGrid {
        &self.grid
    }

    /// The empty finger (noise-free), as rendered once at start-up.
    pub fn reference(&self) -> &Frame {
        &self.reference
    }

    /// Timings of the last call to [`Renderer::render_batch`] (or the reference).
    pub fn timings(&self) -> Timings {
        self.timings
    }

    /// The adapter in use, for logs and benchmarks.
    pub fn adapter(&self) -> &wgpu::AdapterInfo {
        &self.ctx.adapter_info
    }

    /// Prepares contacts off the renderer: a [`Preparer`] works on its own thread (the pose
    /// and footprint searches are CPU work the GPU waits for) while the renderer renders the
    /// batch before.
    pub fn preparer(&self) -> Preparer {
        Preparer {
            sensor: self.sensor.clone(),
            grid: self.grid,
        }
    }

    /// Builds the contact stage's pipelines for `objects` now rather than at their first
    /// frame (each kind of object has its own). For runs that time their frames, such as
    /// `geltip dataset`.
    pub fn ready_objects(&mut self, objects: &[Arc<Object>]) -> Result<()> {
        for object in objects {
            self.pipelines
                .ready_contact(self.ctx, object_kind(object))?;
        }
        Ok(())
    }

    /// Renders one press.
    pub fn render(&mut self, press: &Press) -> Result<(Frame, GroundTruth)> {
        let mut out = self.render_batch(std::slice::from_ref(press))?;
        Ok(out.remove(0))
    }

    /// Renders presses, a frame each, in submissions of [`Self::batch_frames`].
    pub fn render_batch(&mut self, presses: &[Press]) -> Result<Vec<(Frame, GroundTruth)>> {
        self.render_chunks(presses, Preparer::prepare, |r, batch| {
            r.render_prepared(batch)
        })
    }

    /// Renders `items` in chunks of [`Self::batch_frames`], a submission each: each chunk is
    /// prepared by `prepare` (on rayon's threads) while the chunk before it renders, so the
    /// CPU's share of a frame leaves the GPU's path but for the first chunk. The timings
    /// are the chunks' totals (`prepare`: the CPU's time, mostly beside the rendering).
    fn render_chunks<I, P, O>(
        &mut self,
        items: &[I],
        prepare: impl Fn(&Preparer, &[I]) -> Result<P> + Sync,
        mut render: impl FnMut(&mut Renderer, P) -> Result<Vec<O>>,
    ) -> Result<Vec<O>>
    where
        I: Sync,
        P: Send,
    {
        let preparer = self.preparer();
        let chunks: Vec<&[I]> = items.chunks(self.batch).collect();
        let timed = |chunk: &[I]| {
            let start = Instant::now();
            (prepare(&preparer, chunk), start.elapsed())
        };
        let mut out = Vec::with_capacity(items.len());
        let mut total = Timings::default();
        let mut next = chunks.first().map(|c| timed(c));
        for k in 0..chunks.len() {
            let Some((prepared, took)) = next.take() else {
                break;
            };
            total.prepare += took;
            let prepared = prepared?;
            let (rendered, following) = std::thread::scope(|scope| {
                let following = chunks.get(k + 1).map(|c| scope.spawn(|| timed(c)));
                let rendered = render(self, prepared);
                (rendered, following.map(|h| h.join()))
            });
            out.extend(rendered?);
            total.add(&self.timings);
            next = match following {
                Some(Ok(n)) => Some(n),
                Some(Err(_)) => return Err(GeltipError::Gpu("preparing a batch panicked".into())),
                None => None,
            };
        }
        self.timings = total;
        Ok(out)
    }

    /// Renders a batch a [`Preparer`] prepared with [`Preparer::prepare`] (at most
    /// [`Self::batch_frames`] contacts, in one submission), a frame each, each frame drawing
    /// its noise seed in turn.
    pub fn render_prepared(&mut self, batch: PreparedBatch) -> Result<Vec<(Frame, GroundTruth)>> {
        let frames = self.render_prepared_frames(batch)?;
        Ok(frames
            .into_iter()
            .filter_map(|(frame, truths)| Some((frame, truths.into_iter().next()?)))
            .collect())
    }

    /// Renders a batch of frames of any number of contacts each (at most
    /// [`Self::batch_frames`] frames, in one submission), each frame drawing its noise seed
    /// in turn: each frame with its contacts' labels.
    pub fn render_prepared_frames(
        &mut self,
        batch: PreparedBatch,
    ) -> Result<Vec<(Frame, Vec<GroundTruth>)>> {
        if batch.0.len() > self.batch {
            return Err(prepare::too_many(batch.0.len(), self.batch));
        }
        let scenes = batch
            .0
            .into_iter()
            .map(|contacts| (contacts, self.next_noise_seed()))
            .collect();
        self.render_frames(scenes, Duration::ZERO)
    }

    /// Renders frames of several objects each (any number of frames,
    /// [`Self::batch_frames`] to a submission), as [`Renderer::render_scene`] renders one, each frame drawing its noise
    /// seed in turn. With `skip_untouching`, rigid poses that do not touch the finger are
    /// left out of their frame ([`Press::pose_if_touching`]) instead of failing the call, and
    /// a frame none of whose objects touch is the empty finger. Each frame comes with the
    /// labels of the contacts it shows and their indices in its list.
    pub fn render_scenes(
        &mut self,
        frames: &[Vec<Press>],
        skip_untouching: bool,
    ) -> Result<Vec<(Frame, Vec<Shown>)>> {
        let prepare = |preparer: &Preparer, chunk: &[Vec<Press>]| {
            if skip_untouching {
                preparer.prepare_touching(chunk)
            } else {
                let all = chunk.iter().map(|f| (0..f.len()).collect()).collect();
                Ok((preparer.prepare_frames(chunk)?, all))
            }
        };
        self.render_chunks(frames, prepare, |r, (batch, kept)| {
            let frames = r.render_prepared_frames(batch)?;
            Ok(frames
                .into_iter()
                .zip(kept)
                .map(|((frame, truths), kept)| (frame, kept.into_iter().zip(truths).collect()))
                .collect())
        })
    }

    /// Renders several objects pressed into the finger at once, as one frame: the skin is
    /// pushed by whichever object is deepest at each texel, and the elastomer, camera and LED
    /// stages run once over the union of the footprints. One label per press, in order: its
    /// mask is the pressed pixels inside its own footprint's pixel rectangle; `over_pressed`
    /// is the frame's (any object against the shell).
    pub fn render_scene(&mut self, presses: &[Press]) -> Result<(Frame, Vec<GroundTruth>)> {
        let start = Instant::now();
        // Drawn before the presses are checked: a refused scene takes its seed too.
        let seed = self.next_noise_seed();
        let prepared = self.preparer().prepare_scene(presses)?;
        let mut frames = self.render_frames(vec![(prepared, seed)], start.elapsed())?;
        Ok(frames.remove(0))
    }

    /// A frame with no contact, as the camera would take it: the cached reference, with
    /// fresh sensor noise when the sensor has noise (each call draws new noise, like a real
    /// reference frame; without noise it is the reference itself).
    pub fn render_empty(&mut self) -> Result<Frame> {
        if !self.sensor.config.render.noise.any() {
            return Ok(self.reference.clone());
        }
        let seed = self.next_noise_seed();
        let timings = self.timings;
        let frames = self.render_frames(vec![(Vec::new(), seed)], Duration::ZERO);
        self.timings = timings;
        Ok(frames?.remove(0).0)
    }

    /// The seed of the next frame's sensor noise: the sensor's seed, mixed with a count of
    /// the frames drawn so far.
    fn next_noise_seed(&mut self) -> u32 {
        self.seed_counter = self.seed_counter.wrapping_add(1);
        self.sensor.config.render.noise_seed ^ self.seed_counter.wrapping_mul(0x9E37_79B9)
    }

    /// What the GPU needs before it renders a contact's object: the contact pipeline of its
    /// kind (`kind`) and, for a mesh, its baked SDF grid.
    fn ready_object(&mut self, kind: u32, object: &Arc<Object>) -> Result<()> {
        self.pipelines.ready_contact(self.ctx, kind)?;
        self.resources.upload_grid(self.ctx, object);
        Ok(())
    }

    /// The rect of the image a frame can change: its pixel rect, or every pixel when the
    /// sensor adds noise. The rest of the frame is the reference's, which the CPU keeps, so
    /// only this rect is copied, cleared and read back (its rows
    /// [`crate::render::uniforms::image_pitch`] apart).
    fn changed_rect(&self, pixel_rect: Option<Rect>) -> Option<Rect> {
        if self.sensor.config.render.noise.any() {
            return Some(whole_image(&self.sensor));
        }
        pixel_rect.filter(|r| r.w > 0 && r.h > 0)
    }

    /// A buffer of frame uniform `u` alone, bound as a dispatch's frames (the first).
    fn uniform_buffer(&self, u: &FrameUniform) -> wgpu::Buffer {
        let mut contents = vec![0u8; bindings::FRAMES_BOUND_BYTES as usize];
        contents[..std::mem::size_of::<FrameUniform>()].copy_from_slice(bytemuck::bytes_of(u));
        self.ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("geltip frame uniform"),
                contents: &contents,
                usage: wgpu::BufferUsages::UNIFORM,
            })
    }

    /// After a failed frame the heightfield's state is unknown (the recorded clears may
    /// never have run, or run in part): the next frame clears all of it.
    fn forget_heightfield_on_error<T>(&mut self, result: Result<T>) -> Result<T> {
        if result.is_err() {
            let whole = self.resources.heightfield.whole();
            self.dirty.iter_mut().for_each(|d| *d = Some(whole));
        }
        result
    }
}
