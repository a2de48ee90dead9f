//! The GPU renderer: the four stages as compute pipelines over one bind group layout
//! (bindings in `shaders/shared/common.wgsl`). The empty finger is rendered once; each
//! contact copies it and re-renders only the pixels that can see the contact's footprint:
//! of the footprint's pixel rectangle, a first pass lists the pixels whose rays the
//! deformation reaches, and one pass casts and shades that list alone, sized on the
//! GPU (indirect dispatch).
//! Frames of a batch are recorded into one submission, each into its own slice of the
//! output buffers, and read back together.

use super::camera::{tile_grid, tiles_over};
use super::contact::Footprint;
use super::uniforms::{image_pitch, object_kind, FrameUniform, SensorUniform};
use super::{
    contact, elastomer, Contact, ContactPose, Frame, GroundTruth, HeightfieldGrid, Hold, Press,
    Rect,
};
use crate::error::{GeltipError, Result};
use crate::gpu::readback::{
    read_buffer, record_ranges, staging_bytes, staging_or_fresh, unpack_ranges,
};
use crate::gpu::shaders::create_compute_pipeline_with;
use crate::gpu::GpuContext;
use crate::object::Object;
use crate::sensor::Sensor;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};
use wgpu::util::DeviceExt;

/// Side of the 2D compute workgroups (`@workgroup_size(8, 8)` in every stage; 16x16 measured
/// no faster on lavapipe).
const WORKGROUP: u32 = 8;

/// Baked SDF grids of loaded meshes kept on the GPU at most.
const MAX_CACHED_GRIDS: usize = 16;

/// Frames recorded into one submission at most.
pub const MAX_BATCH: usize = 8;

struct Pipelines {
    blend_meridian: wgpu::ComputePipeline,
    blend_azimuth: wgpu::ComputePipeline,
    skin_normals: wgpu::ComputePipeline,
    camera: wgpu::ComputePipeline,
    select_touched: wgpu::ComputePipeline,
    probe_tiles_of_rays: wgpu::ComputePipeline,
    select_tiles: wgpu::ComputePipeline,
    select_listed: wgpu::ComputePipeline,
    camera_shallow: wgpu::ComputePipeline,
    camera_deep: wgpu::ComputePipeline,
    add_noise: wgpu::ComputePipeline,
    unproject_pixels: wgpu::ComputePipeline,
}

/// A frame's data as read back (see [`Renderer::read_frames`]).
struct FrameParts {
    rgba: Vec<u8>,
    indentation: Vec<f32>,
    counters: Vec<u32>,
}

/// What [`Renderer::read_frames`] gives: each frame's parts, each contact's penetration
/// field, and when the submission's work was done and mapped (render time ends there).
struct ReadFrames {
    frames: Vec<FrameParts>,
    fields: Vec<PenetrationField>,
    mapped: Instant,
}

/// One contact's penetration over its texel rect's rows, as read back.
type PenetrationField = Vec<f32>;

/// A compute dispatch's workgroups: a count, or the indirect arguments at a byte offset.
enum Groups {
    Direct((u32, u32)),
    Indirect(u64),
}

impl Groups {
    /// One invocation a texel or pixel of `r`, in [`WORKGROUP`]-square workgroups.
    fn over(r: Rect) -> Self {
        Groups::Direct((groups(r.w, WORKGROUP), groups(r.h, WORKGROUP)))
    }
}

/// Where a frame's touched pixels can be: pixel rects (`pieces`, each with a bind group
/// whose uniform holds it as its pixel rect) within `span` (its bind group's uniform holds
/// it as its pixel rect, and as its texel rect the texels that can be displaced); `camera`
/// is the bind group the touched pixels are cast with. Only the selection without the tile
/// list reads the pieces (a scene leaves them out when the list is on).
struct Touched<'a> {
    span: (Rect, &'a wgpu::BindGroup),
    pieces: Vec<(Rect, &'a wgpu::BindGroup)>,
    camera: &'a wgpu::BindGroup,
}

/// What [`Renderer::run`] gives back: each frame with how many texels its object pressed
/// beyond the shell, and each contact's penetration field.
struct Ran {
    frames: Vec<(Frame, u32)>,
    fields: Vec<PenetrationField>,
}

/// What the CPU prepared for one contact of a batch or a scene.
struct Prepared {
    uniform: FrameUniform,
    press: Press,
    pose: ContactPose,
    /// The heightfield texels it moves, presses and blends along meridians, and the pixels
    /// that can see them move; `None` when it touches nothing.
    footprint: Option<Footprint>,
}

impl Prepared {
    /// The pixels it can change; `None` when the lens sees none of its footprint.
    fn pixel_rect(&self) -> Option<Rect> {
        self.footprint.and_then(|f| f.pixels)
    }

    /// Where this contact's own penetration goes in `penetration_fields` when it starts at
    /// byte `offset`: (offset, bytes) of its pressed rect's rows, or `None` without a rect.
    fn field_range(&self, offset: u64, texels: u32) -> Option<(u64, u64)> {
        self.footprint
            .map(|f| (offset, f.pressed.h as u64 * texels as u64 * 4))
    }
}

/// Which of a footprint's texel rects a blend stage runs over.
#[derive(Debug, Clone, Copy)]
enum Over {
    Meridians,
    Texels,
}

impl Over {
    fn of(self, footprint: Footprint) -> Rect {
        match self {
            Over::Meridians => footprint.meridians,
            Over::Texels => footprint.texels,
        }
    }
}

/// Contacts prepared for the GPU (poses, footprints, uniforms): made by a [`Preparer`],
/// rendered by [`Renderer::render_prepared`].
pub struct PreparedBatch(Vec<Prepared>);

/// The CPU half of rendering, which needs no GPU: a contact's pose (its first-touch search)
/// and footprint. Cheap to clone; `Send`, so a pipeline can prepare the next batch while
/// the renderer renders this one.
#[derive(Debug, Clone)]
pub struct Preparer {
    sensor: Sensor,
    grid: HeightfieldGrid,
}

impl Preparer {
    /// Prepares up to [`MAX_BATCH`] contacts for one submission.
    pub fn prepare(&self, contacts: &[Contact]) -> Result<PreparedBatch> {
        prepare_batch(&self.sensor, &self.grid, contacts)
    }
}

/// Poses, footprints and uniforms of `contacts` (noise seeds are set when rendered).
fn prepare_batch(
    sensor: &Sensor,
    grid: &HeightfieldGrid,
    contacts: &[Contact],
) -> Result<PreparedBatch> {
    contacts
        .iter()
        .map(|c| prepare_contact(sensor, grid, &Press::from(c), 0))
        .collect::<Result<Vec<_>>>()
        .map(PreparedBatch)
}

/// Pose, footprint and frame uniform of one press (its noise seed as given).
fn prepare_contact(
    sensor: &Sensor,
    grid: &HeightfieldGrid,
    press: &Press,
    noise_seed: u32,
) -> Result<Prepared> {
    let pose = press.pose(sensor)?;
    let reach = elastomer::blend_reach_mm(&sensor.config.elastomer);
    let footprint = contact::footprint(sensor, grid, &pose, &press.object, reach);
    let max_depth = pose.trace_depth_mm;
    let uniform = FrameUniform::contact(&pose, &press.object, max_depth, footprint, noise_seed);
    Ok(Prepared {
        uniform,
        press: press.clone(),
        pose,
        footprint,
    })
}

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
    /// Pixels the camera and LED stages re-rendered (the touched lists' lengths), summed.
    pub touched_pixels: u64,
    /// Tiles of 8 x 8 pixels whose pixels the touched lists were chosen from (the tile
    /// lists' lengths: [`Renderer::set_tile_list`]), summed; 0 with the tile list off.
    pub listed_tiles: u64,
}

impl Timings {
    /// Adds `other`'s phases and pixels to these (totals over several batches or frames).
    pub fn add(&mut self, other: &Timings) {
        self.prepare += other.prepare;
        self.render += other.render;
        self.readback += other.readback;
        self.touched_pixels += other.touched_pixels;
        self.listed_tiles += other.listed_tiles;
    }
}

/// A renderer for one sensor.
pub struct Renderer {
    ctx: &'static GpuContext,
    sensor: Sensor,
    grid: HeightfieldGrid,
    pipelines: Pipelines,
    /// The contact stage's pipeline per object kind (FrameUniform `object_kind`), built when
    /// a kind is first rendered: the kind is a pipeline constant (shaders/contact.wgsl).
    contact_pipelines: HashMap<u32, wgpu::ComputePipeline>,
    /// What those are built with: the renderer's pipeline layout and the sensor's constants.
    pipeline_layout: wgpu::PipelineLayout,
    constants: [(&'static str, f64); 7],
    layout: wgpu::BindGroupLayout,
    sensor_buffer: wgpu::Buffer,
    penetration: wgpu::Buffer,
    elastomer_scratch: wgpu::Buffer,
    height: wgpu::Buffer,
    /// Each contact's own penetration over its texel rect's rows, copied out of `height`
    /// right after its contact pass (the labels are computed from it: see `contact.wgsl`).
    penetration_fields: wgpu::Buffer,
    /// The heightfield as the samplers read it: textures refreshed from the three buffers
    /// above after each stage that writes them (see `shaders/shared/common.wgsl`).
    maps: [MapTexture; 3],
    /// Texels the maps may hold non-zero (the last contact's texel rect).
    dirty: Option<Rect>,
    /// Per pixel, where its ray crosses the shell (written by the reference frame); then
    /// per tile of pixels, the texels those crossings read (`probe_tiles_of_rays`).
    probes: wgpu::Buffer,
    /// `probes` as the passes read it: pixel (x, y)'s two vec4 are texels (2x, y), (2x+1, y).
    probe_map: MapTexture,
    /// Whether contact frames select their touched pixels over the tiles `select_tiles`
    /// lists (the default) or over every pixel of their rect: [`Renderer::set_tile_list`].
    list_tiles: bool,
    /// Nearest, clamped: the maps' textureGather (see `shaders/shared/common.wgsl`).
    map_sampler: wgpu::Sampler,
    image: wgpu::Buffer,
    indentation: wgpu::Buffer,
    counters: wgpu::Buffer,
    /// Per frame of a batch, the touched-list passes' workgroups (copied from `counters`:
    /// a buffer bound for storage cannot also feed an indirect dispatch).
    dispatch_args: wgpu::Buffer,
    /// The empty finger's image, from which a frame copies the rect it can change into its
    /// own buffers' layout ([`Self::copy_reference`]).
    reference_texture: wgpu::Texture,
    /// Kept for reading batches back (a batch's images, indentation rows and counters).
    staging: wgpu::Buffer,
    empty_grid: wgpu::Buffer,
    /// Baked SDF grids of loaded meshes, by object (the Arc keeps the address unique).
    grids: HashMap<usize, (Arc<Object>, wgpu::Buffer)>,
    /// Bytes of one frame's slice of `image` and `indentation`: the whole image with rows
    /// [`image_pitch`] apart (a contact frame's rect takes less).
    slot_bytes: u64,
    /// Bytes of one frame's slice of `counters`: the counters and the touched list.
    counter_bytes: u64,
    reference: Frame,
    seed_counter: u32,
    timings: Timings,
}

/// A texture copy of a buffer the shaders sample (see `shaders/shared/common.wgsl` for why)
/// and the bytes per texel of both.
struct MapTexture {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    texel_bytes: u32,
}

/// The maps, in the order of their bindings (10, 11, 12) and of `Renderer::maps`.
#[derive(Clone, Copy)]
enum Map {
    Penetration = 0,
    Elastomer = 1,
    Height = 2,
}

fn map_texture(
    ctx: &GpuContext,
    label: &str,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
) -> MapTexture {
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let view = texture.create_view(&Default::default());
    MapTexture {
        texture,
        view,
        texel_bytes: format.block_copy_size(None).unwrap_or(4),
    }
}

/// Words of a frame's `counters` slice (shaders/shared/common.wgsl).
const OVER_PRESSED: usize = 0;
const SHALLOW_COUNT: usize = 1;
const DEEP_COUNT: usize = 2;
/// The shallow and the deep pass's indirect dispatch arguments: three words each, at a
/// 16-byte stride from here.
const SHALLOW_DISPATCH: u64 = 4;
const TOUCHED_LIST: u64 = 64;
/// Bytes of the counters before the touched list.
const COUNTER_HEADER_BYTES: u64 = TOUCHED_LIST * 4;
/// Tiles on the tile list, and select_listed's indirect dispatch arguments (three words).
const TILE_COUNT: usize = 3;
const SELECT_DISPATCH: u64 = 12;
/// Bytes of one frame's indirect dispatch arguments: the shallow pass's three words, at 16
/// bytes the deep pass's, at 32 bytes select_listed's.
const DISPATCH_ARGS_BYTES: u64 = 48;
/// Where select_listed's arguments lie in a frame's.
const SELECT_ARGS_OFFSET: u64 = 32;
/// Bytes per tile of the tiles' texel ranges at the end of `probes` (WGSL
/// `PROBE_TILE_STRIDE` vec4<i32>).
const PROBE_TILE_BYTES: u64 = 3 * 16;
/// Invocations (tiles) per workgroup of `select_tiles`: one SIMD group on llvmpipe, so the
/// tiles of a small rect still spread over the cores.
const SELECT_TILES_WORKGROUP: u32 = 8;

/// Pixels on a frame's touched list (both kinds), from its counters.
fn touched_pixels(counters: &[u32]) -> u64 {
    counters[SHALLOW_COUNT] as u64 + counters[DEEP_COUNT] as u64
}

/// Two vec4 per pixel (shaders/shared/common.wgsl `PROBES_STRIDE`).
const PROBES_BYTES_PER_PIXEL: u64 = 2 * 16;

/// Bytes a frame's image (or indentation) buffer takes to hold rect `r` of the image: its
/// rows, [`image_pitch`] pixels apart.
fn held_bytes(r: Rect) -> u64 {
    r.h as u64 * image_pitch(r.w) as u64 * 4
}

/// Where a copy to or from `texture` starts for `rect`: its corner (the copy's extent is the
/// rect's size).
fn rect_of(texture: &wgpu::Texture, rect: Rect) -> wgpu::TexelCopyTextureInfo<'_> {
    wgpu::TexelCopyTextureInfo {
        texture,
        mip_level: 0,
        origin: wgpu::Origin3d {
            x: rect.x,
            y: rect.y,
            z: 0,
        },
        aspect: wgpu::TextureAspect::All,
    }
}

fn storage(ctx: &GpuContext, label: &str, size: u64, extra: wgpu::BufferUsages) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC
            | extra,
        mapped_at_creation: false,
    })
}

fn layout_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn map_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

fn groups(n: u32, size: u32) -> u32 {
    n.div_ceil(size)
}

impl Renderer {
    /// Compiles the pipelines, allocates the buffers and renders the empty finger once, on
    /// the process's shared device.
    pub fn new(sensor: &Sensor) -> Result<Renderer> {
        Renderer::on(sensor, GpuContext::shared()?)
    }

    /// One renderer per render stream 0..`streams` ([`GpuContext::stream`]: each on a
    /// device of its own, so they render at the same time), started side by side, each with
    /// the contact pipelines of `objects` built ([`Renderer::ready_objects`]).
    pub fn on_streams(
        sensor: &Sensor,
        streams: usize,
        objects: &[Arc<Object>],
    ) -> Result<Vec<Renderer>> {
        std::thread::scope(|scope| {
            let started: Vec<_> = (0..streams)
                .map(|i| {
                    scope.spawn(move || {
                        let mut renderer = Renderer::on(sensor, GpuContext::stream(i)?)?;
                        renderer.ready_objects(objects)?;
                        Ok(renderer)
                    })
                })
                .collect();
            started
                .into_iter()
                .map(|s| {
                    s.join().unwrap_or_else(|_| {
                        Err(GeltipError::Gpu(
                            "a render stream panicked at start-up".into(),
                        ))
                    })
                })
                .collect()
        })
    }

    /// As [`Renderer::new`], on the device of `ctx` (e.g. [`GpuContext::stream`]: renderers
    /// on different devices render at the same time).
    pub fn on(sensor: &Sensor, ctx: &'static GpuContext) -> Result<Renderer> {
        let grid = HeightfieldGrid::for_sensor(sensor);
        let texels = grid.texels as u64 * grid.texels as u64;
        let pixels = sensor.width as u64 * sensor.height as u64;
        let slot_bytes = held_bytes(Rect {
            x: 0,
            y: 0,
            w: sensor.width,
            h: sensor.height,
        });
        let (tiles_x, tiles_y) = tile_grid(sensor.width, sensor.height);
        let tiles = tiles_x as u64 * tiles_y as u64;
        // The counters, the touched list (a pixel each) and the tile list (a tile each).
        let counter_bytes = (COUNTER_HEADER_BYTES + pixels * 4 + tiles * 4).next_multiple_of(256);
        let downlevel = ctx.adapter.get_downlevel_capabilities();
        if !downlevel
            .flags
            .contains(wgpu::DownlevelFlags::INDIRECT_EXECUTION)
        {
            return Err(GeltipError::Gpu(format!(
                "adapter {} cannot dispatch compute work indirectly, which the renderer needs",
                ctx.adapter_info.name
            )));
        }
        let limits = ctx.device.limits();
        let allowed = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let probes_bytes = pixels * PROBES_BYTES_PER_PIXEL + tiles * PROBE_TILE_BYTES;
        let image_bytes = probes_bytes.max(slot_bytes * MAX_BATCH as u64);
        if image_bytes > allowed {
            return Err(GeltipError::input(
                "image",
                format!(
                    "{}x{} needs {image_bytes} byte GPU buffers; this device allows {allowed}",
                    sensor.width, sensor.height
                ),
            ));
        }
        let side = limits.max_texture_dimension_2d;
        if 2 * sensor.width > side || sensor.height > side {
            return Err(GeltipError::input(
                "image",
                format!(
                    "{}x{} needs a {}x{} texture; this device allows {side} per side",
                    sensor.width,
                    sensor.height,
                    2 * sensor.width,
                    sensor.height
                ),
            ));
        }
        if grid.texels > side {
            return Err(GeltipError::config(
                "render.heightfield_texels",
                format!(
                    "{} exceeds this device's {side} texels per texture side",
                    grid.texels
                ),
            ));
        }
        if texels * 16 > allowed {
            return Err(GeltipError::config(
                "render.heightfield_texels",
                format!(
                    "{} texels per side need {} byte GPU buffers; this device allows {allowed}",
                    grid.texels,
                    texels * 16
                ),
            ));
        }
        use wgpu::BufferBindingType::{Storage, Uniform};
        let entries = [
            layout_entry(0, Uniform),
            layout_entry(1, Uniform),
            layout_entry(2, Storage { read_only: false }),
            layout_entry(3, Storage { read_only: false }),
            layout_entry(4, Storage { read_only: false }),
            layout_entry(5, Storage { read_only: false }),
            layout_entry(6, Storage { read_only: false }),
            layout_entry(7, Storage { read_only: false }),
            layout_entry(8, Storage { read_only: true }),
            layout_entry(9, Storage { read_only: false }),
            map_entry(10),
            map_entry(11),
            map_entry(12),
            map_entry(13),
            wgpu::BindGroupLayoutEntry {
                binding: 14,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
                count: None,
            },
        ];
        let (layout, pipeline_layout) = ctx.scoped("creating the renderer's layout", || {
            let layout = ctx
                .device
                .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("geltip renderer"),
                    entries: &entries,
                });
            let pipeline_layout =
                ctx.device
                    .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some("geltip renderer"),
                        bind_group_layouts: &[Some(&layout)],
                        immediate_size: 0,
                    });
            (layout, pipeline_layout)
        })?;
        let sensor_uniform = SensorUniform::new(sensor, &grid);
        let constants = sensor_uniform.pipeline_constants();
        let p = |stage: &str, entry: &str| {
            create_compute_pipeline_with(ctx, stage, entry, Some(&pipeline_layout), &constants)
        };
        let pipelines = Pipelines {
            blend_meridian: p("elastomer", "blend_meridian")?,
            blend_azimuth: p("elastomer", "blend_azimuth")?,
            skin_normals: p("camera", "skin_normals")?,
            camera: p("camera", "camera")?,
            select_touched: p("camera", "select_touched")?,
            probe_tiles_of_rays: p("camera", "probe_tiles_of_rays")?,
            select_tiles: p("camera", "select_tiles")?,
            select_listed: p("camera", "select_listed")?,
            camera_shallow: p("camera", "camera_shallow")?,
            camera_deep: p("camera", "camera_deep")?,
            add_noise: p("leds", "add_noise")?,
            unproject_pixels: p("camera", "unproject_pixels")?,
        };
        let sensor_buffer = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("geltip sensor"),
                contents: bytemuck::bytes_of(&sensor_uniform),
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let none = wgpu::BufferUsages::empty();
        let mut renderer = Renderer {
            ctx,
            sensor: sensor.clone(),
            grid,
            pipelines,
            contact_pipelines: HashMap::new(),
            pipeline_layout,
            constants,
            layout,
            sensor_buffer,
            penetration: storage(ctx, "geltip penetration", texels * 4, none),
            elastomer_scratch: storage(ctx, "geltip elastomer scratch", texels * 16, none),
            height: storage(ctx, "geltip height", texels * 4, none),
            penetration_fields: storage(
                ctx,
                "geltip contact penetration fields",
                texels * 4 * MAX_BATCH as u64,
                none,
            ),
            maps: [
                ("geltip penetration map", wgpu::TextureFormat::R32Float),
                ("geltip elastomer map", wgpu::TextureFormat::Rgba32Float),
                ("geltip height map", wgpu::TextureFormat::R32Float),
            ]
            .map(|(label, format)| map_texture(ctx, label, (grid.texels, grid.texels), format)),
            probe_map: map_texture(
                ctx,
                "geltip ray probes map",
                (2 * sensor.width, sensor.height),
                wgpu::TextureFormat::Rgba32Float,
            ),
            dirty: None,
            map_sampler: ctx.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("geltip map sampler"),
                ..Default::default()
            }),
            probes: storage(ctx, "geltip ray probes", probes_bytes, none),
            list_tiles: true,
            image: storage(ctx, "geltip image", slot_bytes * MAX_BATCH as u64, none),
            indentation: storage(
                ctx,
                "geltip indentation",
                slot_bytes * MAX_BATCH as u64,
                none,
            ),
            counters: storage(
                ctx,
                "geltip counters and touched pixels",
                counter_bytes * MAX_BATCH as u64,
                none,
            ),
            dispatch_args: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("geltip touched dispatch"),
                size: DISPATCH_ARGS_BYTES * MAX_BATCH as u64,
                usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            reference_texture: ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("geltip reference texture"),
                size: wgpu::Extent3d {
                    width: sensor.width,
                    height: sensor.height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R32Uint,
                usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            }),
            staging: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("geltip batch readback"),
                size: (2 * slot_bytes + COUNTER_HEADER_BYTES + texels * 4) * MAX_BATCH as u64,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            empty_grid: storage(ctx, "geltip empty grid", 16, none),
            grids: HashMap::new(),
            slot_bytes,
            counter_bytes,
            reference: Frame {
                width: sensor.width,
                height: sensor.height,
                rgba: Vec::new(),
                indentation: Vec::new(),
            },
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

    fn bind_group(
        &self,
        uniform: &wgpu::Buffer,
        slot: u64,
        object: Option<&Object>,
    ) -> wgpu::BindGroup {
        let grid = match object {
            Some(o @ Object::Mesh { .. }) => &self.grids[&(o as *const Object as usize)].1,
            _ => &self.empty_grid,
        };
        fn slice(buffer: &wgpu::Buffer, offset: u64, size: u64) -> wgpu::BindingResource<'_> {
            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer,
                offset,
                size: std::num::NonZeroU64::new(size),
            })
        }
        fn whole(b: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
            b.as_entire_binding()
        }
        let map = |m: Map| wgpu::BindingResource::TextureView(&self.maps[m as usize].view);
        let resources = [
            whole(&self.sensor_buffer),
            whole(uniform),
            whole(&self.penetration),
            whole(&self.elastomer_scratch),
            whole(&self.height),
            whole(&self.probes),
            slice(&self.image, slot * self.slot_bytes, self.slot_bytes),
            slice(&self.indentation, slot * self.slot_bytes, self.slot_bytes),
            whole(grid),
            slice(
                &self.counters,
                slot * self.counter_bytes,
                self.counter_bytes,
            ),
            map(Map::Penetration),
            map(Map::Elastomer),
            map(Map::Height),
            wgpu::BindingResource::TextureView(&self.probe_map.view),
            wgpu::BindingResource::Sampler(&self.map_sampler),
        ];
        let entries: Vec<wgpu::BindGroupEntry> = resources
            .into_iter()
            .enumerate()
            .map(|(i, resource)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource,
            })
            .collect();
        self.ctx
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("geltip frame"),
                layout: &self.layout,
                entries: &entries,
            })
    }

    /// A bind group over a uniform buffer of its own for each of `uniforms` (a scene's pieces;
    /// the bind group keeps its buffer alive).
    fn bind_uniforms(
        &self,
        uniforms: impl IntoIterator<Item = FrameUniform>,
    ) -> Vec<wgpu::BindGroup> {
        uniforms
            .into_iter()
            .map(|u| self.bind_group(&self.uniform_buffer(&u), 0, None))
            .collect()
    }

    fn uniform_buffer(&self, u: &FrameUniform) -> wgpu::Buffer {
        self.ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("geltip frame uniform"),
                contents: bytemuck::bytes_of(u),
                usage: wgpu::BufferUsages::UNIFORM,
            })
    }

    fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        bind: &wgpu::BindGroup,
        groups: (u32, u32),
    ) {
        self.record_pass(encoder, &[(pipeline, bind, Groups::Direct(groups))]);
    }

    /// Records `dispatches` in one compute pass (none without a dispatch that does work),
    /// the indirect ones sized from `dispatch_args`. Why one pass for as many as the copies
    /// between stages allow: lavapipe charges each pass of this renderer about 70 µs beyond
    /// its dispatch (README, eighth round), a dispatch within a pass about 25 µs.
    fn record_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        dispatches: &[(&wgpu::ComputePipeline, &wgpu::BindGroup, Groups)],
    ) {
        let works = |g: &Groups| !matches!(g, Groups::Direct((x, y)) if *x == 0 || *y == 0);
        if !dispatches.iter().any(|(_, _, g)| works(g)) {
            return;
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: None,
            timestamp_writes: None,
        });
        for (pipeline, bind, g) in dispatches.iter().filter(|(_, _, g)| works(g)) {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, *bind, &[]);
            match g {
                Groups::Direct((x, y)) => pass.dispatch_workgroups(*x, *y, 1),
                Groups::Indirect(offset) => {
                    pass.dispatch_workgroups_indirect(&self.dispatch_args, *offset)
                }
            }
        }
    }

    /// What a contact frame runs once its height map is ready, in as few compute passes as
    /// the copies between them allow: the skin normals over `normals` (texel rects with
    /// their bind groups, and the rect of their map to refresh) beside the selection of
    /// frame `slot`'s touched pixels from `touched`, then the passes over those.
    fn record_after_height(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slot: u64,
        normals: Option<(&[(Rect, &wgpu::BindGroup)], Rect)>,
        touched: Option<&Touched>,
    ) {
        self.record_normals_and_select(encoder, slot, normals, touched);
        if let Some(touched) = touched {
            self.record_touched_passes(encoder, slot, touched.camera);
        }
    }

    /// The skin normals over `normals` (copied into their map over its rect) and frame
    /// `slot`'s touched list from `touched`, both of which read the height map alone: one
    /// pass holds the normals and the first step of the selection. With the tile list on,
    /// `select_tiles` lists the span's tiles whose probes see displaced texels and
    /// `select_listed` runs over those alone (its own pass, sized by the list); otherwise
    /// `select_touched` runs over every pixel of each piece.
    fn record_normals_and_select(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slot: u64,
        normals: Option<(&[(Rect, &wgpu::BindGroup)], Rect)>,
        touched: Option<&Touched>,
    ) {
        let p = &self.pipelines;
        let (normals, region) = match normals {
            Some((n, region)) => (n, Some(region)),
            None => (&[][..], None),
        };
        let mut first: Vec<(&wgpu::ComputePipeline, &wgpu::BindGroup, Groups)> = normals
            .iter()
            .map(|(t, bind)| (&p.skin_normals, *bind, Groups::over(*t)))
            .collect();
        if let Some(Touched { span, pieces, .. }) = touched {
            if self.list_tiles {
                let (columns, rows) = tiles_over(span.0);
                let tiles = columns.len() as u32 * rows.len() as u32;
                let g = (groups(tiles, SELECT_TILES_WORKGROUP), 1);
                first.push((&p.select_tiles, span.1, Groups::Direct(g)));
            } else {
                first.extend(
                    pieces
                        .iter()
                        .map(|(r, bind)| (&p.select_touched, *bind, Groups::over(*r))),
                );
            }
        }
        self.record_pass(encoder, &first);
        if region.is_some() {
            self.copy_to_map(encoder, Map::Elastomer, region);
        }
        if let (Some(Touched { span, .. }), true) = (touched, self.list_tiles) {
            let args = slot * DISPATCH_ARGS_BYTES + SELECT_ARGS_OFFSET;
            encoder.copy_buffer_to_buffer(
                &self.counters,
                slot * self.counter_bytes + SELECT_DISPATCH * 4,
                &self.dispatch_args,
                args,
                Some(12),
            );
            self.record_pass(
                encoder,
                &[(&p.select_listed, span.1, Groups::Indirect(args))],
            );
        }
    }

    /// Frame `slot`'s passes over its touched list, sized by it: the shallow pixels', then
    /// the deep ones', in one pass.
    fn record_touched_passes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slot: u64,
        bind: &wgpu::BindGroup,
    ) {
        let args = slot * DISPATCH_ARGS_BYTES;
        encoder.copy_buffer_to_buffer(
            &self.counters,
            slot * self.counter_bytes + SHALLOW_DISPATCH * 4,
            &self.dispatch_args,
            args,
            Some(SELECT_ARGS_OFFSET),
        );
        let p = &self.pipelines;
        self.record_pass(
            encoder,
            &[
                (&p.camera_shallow, bind, Groups::Indirect(args)),
                (&p.camera_deep, bind, Groups::Indirect(args + 16)),
            ],
        );
    }

    /// Whether contact frames list the tiles of pixels that can be touched first and select
    /// over those alone (on, the default), or select over every pixel of their rects (the
    /// renderer before the tile list; the frames are the same: `tests/render.rs`). For
    /// benchmarks and tests.
    pub fn set_tile_list(&mut self, on: bool) {
        self.list_tiles = on;
    }

    /// Zeroes the heightfield buffers' rows `rect` spans (all of them without a rect).
    fn clear_heightfield(&self, encoder: &mut wgpu::CommandEncoder, rect: Option<Rect>) {
        let row = self.grid.texels as u64;
        for (buffer, bytes) in [
            (&self.penetration, 4),
            (&self.elastomer_scratch, 16),
            (&self.height, 4),
        ] {
            match rect {
                Some(r) => encoder.clear_buffer(
                    buffer,
                    r.y as u64 * row * bytes,
                    Some(r.h as u64 * row * bytes),
                ),
                None => encoder.clear_buffer(buffer, 0, None),
            }
        }
    }

    /// Copies `rect` of the buffer behind `map` into the map (all of it without a rect).
    fn copy_to_map(&self, encoder: &mut wgpu::CommandEncoder, map: Map, rect: Option<Rect>) {
        let n = self.grid.texels;
        let r = rect.unwrap_or(Rect {
            x: 0,
            y: 0,
            w: n,
            h: n,
        });
        let target = &self.maps[map as usize];
        let buffer = match map {
            Map::Penetration => &self.penetration,
            Map::Elastomer => &self.elastomer_scratch,
            Map::Height => &self.height,
        };
        let bytes = target.texel_bytes;
        encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: (r.y as u64 * n as u64 + r.x as u64) * bytes as u64,
                    bytes_per_row: Some(n * bytes),
                    rows_per_image: None,
                },
            },
            rect_of(&target.texture, r),
            wgpu::Extent3d {
                width: r.w,
                height: r.h,
                depth_or_array_layers: 1,
            },
        );
    }

    /// Copies the rays' probe positions into `probe_map`: in one copy when a row of them
    /// is a whole number of 256-byte copy rows, else row by row (once per renderer).
    fn copy_probes_to_map(&self, encoder: &mut wgpu::CommandEncoder) {
        let (w, h) = (self.sensor.width, self.sensor.height);
        let row_bytes = w * PROBES_BYTES_PER_PIXEL as u32;
        let (rows_per_copy, copies) =
            if row_bytes.is_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) {
                (h, 1)
            } else {
                (1, h)
            };
        for k in 0..copies {
            encoder.copy_buffer_to_texture(
                wgpu::TexelCopyBufferInfo {
                    buffer: &self.probes,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: k as u64 * row_bytes as u64,
                        bytes_per_row: Some(row_bytes).filter(|_| rows_per_copy > 1),
                        rows_per_image: None,
                    },
                },
                wgpu::TexelCopyTextureInfo {
                    texture: &self.probe_map.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x: 0, y: k, z: 0 },
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::Extent3d {
                    width: 2 * w,
                    height: rows_per_copy,
                    depth_or_array_layers: 1,
                },
            );
        }
    }

    /// A contact's heightfield stages up to its height map: the penetration over its pressed
    /// rect, then the elastomer's two passes (meridians over its meridian rect, parallels over
    /// its texel rect `t`), each followed by the copy of what it wrote into its map (the
    /// skin's normals follow in [`Self::record_after_height`]). `region` covers `t` and
    /// whatever the maps still hold from the last contact, so the maps are zero outside `t`
    /// afterwards.
    fn record_heightfield(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (bind, kind): (&wgpu::BindGroup, u32),
        footprint: Footprint,
        region: Rect,
        field_offset: u64,
    ) -> Result<()> {
        let contact = self.contact_pipeline(kind)?;
        self.record_texels(
            encoder,
            bind,
            contact,
            Map::Penetration,
            footprint.pressed,
            region,
        );
        self.copy_field(encoder, footprint.pressed, field_offset);
        for (_, pipeline, map, over) in self.blend_stages() {
            self.record_texels(encoder, bind, pipeline, map, over.of(footprint), region);
        }
        Ok(())
    }

    /// Copies the contact pass's own penetration (left in `height` over the rows of `t`, its
    /// pressed rect) to byte `offset` of `penetration_fields`, before the parallels pass
    /// overwrites it. (Outside `t` those rows may hold another contact's penetration.)
    fn copy_field(&self, encoder: &mut wgpu::CommandEncoder, t: Rect, offset: u64) {
        let row = self.grid.texels as u64 * 4;
        encoder.copy_buffer_to_buffer(
            &self.height,
            t.y as u64 * row,
            &self.penetration_fields,
            offset,
            Some(t.h as u64 * row),
        );
    }

    /// Makes `penetration_fields` hold at least `bytes` (a scene may have many contacts).
    fn reserve_fields(&mut self, bytes: u64) {
        if self.penetration_fields.size() < bytes {
            self.penetration_fields = storage(
                self.ctx,
                "geltip contact penetration fields",
                bytes,
                wgpu::BufferUsages::empty(),
            );
        }
    }

    /// Byte offsets in `penetration_fields` of each prepared contact's field, packed.
    fn field_offsets(&self, prepared: &[Prepared]) -> (Vec<u64>, u64) {
        let mut at = 0;
        let offsets = prepared
            .iter()
            .map(|p| {
                let here = at;
                at += p.field_range(0, self.grid.texels).map_or(0, |r| r.1);
                here
            })
            .collect();
        (offsets, at)
    }

    /// The labels of each prepared contact from its penetration field as read back.
    fn truths(&self, prepared: Vec<Prepared>, fields: Vec<Vec<f32>>) -> Vec<GroundTruth> {
        prepared
            .into_iter()
            .zip(fields)
            .map(|(p, field)| {
                let labels = p.footprint.map(|f| f.pressed).map(|rect| {
                    contact::indentation_labels(&self.sensor.finger, &self.grid, &field, rect)
                });
                ground_truth(&self.sensor, &p.press, &p.pose, labels)
            })
            .collect()
    }

    /// The heightfield stages between the contact stage (whose pipeline is its object's:
    /// [`Self::contact_pipeline`]) and the skin normals, in order: name, pipeline, the map
    /// its output refreshes, and the texels it runs over.
    fn blend_stages(&self) -> [(&'static str, &wgpu::ComputePipeline, Map, Over); 2] {
        let p = &self.pipelines;
        [
            (
                "elastomer: meridians",
                &p.blend_meridian,
                Map::Elastomer,
                Over::Meridians,
            ),
            (
                "elastomer: parallels",
                &p.blend_azimuth,
                Map::Height,
                Over::Texels,
            ),
        ]
    }

    /// One heightfield stage over `t`, then the copy of `region` of its output into `map`.
    fn record_texels(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bind: &wgpu::BindGroup,
        pipeline: &wgpu::ComputePipeline,
        map: Map,
        t: Rect,
        region: Rect,
    ) {
        self.record_pass(encoder, &[(pipeline, bind, Groups::over(t))]);
        self.copy_to_map(encoder, map, Some(region));
    }

    /// Renders the empty finger again, every pixel (the renderer does this once at start-up;
    /// public for benchmarks).
    pub fn render_reference(&mut self) -> Result<()> {
        let start = Instant::now();
        let uniform = self.uniform_buffer(&FrameUniform::reference(&self.sensor, 0));
        let bind = self.bind_group(&uniform, 0, None);
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        self.clear_heightfield(&mut encoder, None);
        for map in [Map::Penetration, Map::Elastomer, Map::Height] {
            self.copy_to_map(&mut encoder, map, None);
        }
        self.dirty = None;
        let (w, h) = (self.sensor.width, self.sensor.height);
        self.dispatch(
            &mut encoder,
            &self.pipelines.camera,
            &bind,
            (groups(w, WORKGROUP), groups(h, WORKGROUP)),
        );
        self.copy_probes_to_map(&mut encoder);
        let (tx, ty) = tile_grid(w, h);
        self.dispatch(
            &mut encoder,
            &self.pipelines.probe_tiles_of_rays,
            &bind,
            (groups(tx * ty, 64), 1),
        );
        encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: &self.image,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(image_pitch(w) * 4),
                    rows_per_image: None,
                },
            },
            self.reference_texture.as_image_copy(),
            self.reference_texture.size(),
        );
        self.ctx
            .submit_and_wait("rendering the reference frame", encoder)?;
        let render = start.elapsed();
        let pixels = (w * h) as usize;
        let packed = self.read_whole_image(&self.image)?;
        self.reference.rgba = bytemuck::cast_slice(&packed).to_vec();
        self.reference.indentation = vec![0.0; pixels];
        self.timings = Timings {
            prepare: Duration::ZERO,
            render,
            readback: start.elapsed() - render,
            touched_pixels: (w * h) as u64,
            listed_tiles: 0,
        };
        Ok(())
    }

    /// A whole image's pixels from the start of `buffer` (rows [`image_pitch`] apart there).
    fn read_whole_image(&self, buffer: &wgpu::Buffer) -> Result<Vec<u32>> {
        let (w, h) = (self.sensor.width as usize, self.sensor.height as usize);
        let pitch = image_pitch(self.sensor.width) as usize;
        let pitched: Vec<u32> = read_buffer(self.ctx, buffer, 0, h * pitch)?;
        Ok(pitched
            .chunks_exact(pitch)
            .flat_map(|row| &row[..w])
            .copied()
            .collect())
    }

    fn prepare(&mut self, press: &Press, noise_seed: u32) -> Result<Prepared> {
        let prepared = prepare_contact(&self.sensor, &self.grid, press, noise_seed)?;
        self.ready_object(&prepared)?;
        Ok(prepared)
    }

    /// What the GPU needs before it renders a prepared contact's object: the contact
    /// pipeline for its kind and, for a mesh, its baked SDF grid.
    fn ready_object(&mut self, prepared: &Prepared) -> Result<()> {
        self.build_contact_pipeline(prepared.uniform.object_kind)?;
        self.upload_grid(&prepared.press.object);
        Ok(())
    }

    /// Builds the contact stage's pipelines for `objects` now rather than at their first
    /// frame (each kind of object has its own: 25-130 ms on lavapipe with and without Mesa's
    /// shader cache). For runs that time their frames, such as `geltip dataset`.
    pub fn ready_objects(&mut self, objects: &[Arc<Object>]) -> Result<()> {
        for object in objects {
            self.build_contact_pipeline(object_kind(object))?;
        }
        Ok(())
    }

    fn build_contact_pipeline(&mut self, kind: u32) -> Result<()> {
        if !self.contact_pipelines.contains_key(&kind) {
            let mut constants = self.constants.to_vec();
            constants.push(("OBJECT_KIND", kind as f64));
            let pipeline = create_compute_pipeline_with(
                self.ctx,
                "contact",
                "contact",
                Some(&self.pipeline_layout),
                &constants,
            )?;
            self.contact_pipelines.insert(kind, pipeline);
        }
        Ok(())
    }

    /// The contact stage's pipeline for object kind `kind` (built by [`Self::ready_object`]).
    fn contact_pipeline(&self, kind: u32) -> Result<&wgpu::ComputePipeline> {
        self.contact_pipelines
            .get(&kind)
            .ok_or_else(|| GeltipError::Gpu(format!("no contact pipeline for object kind {kind}")))
    }

    /// A mesh's baked SDF grid on the GPU, uploaded once per mesh.
    fn upload_grid(&mut self, object: &Arc<Object>) {
        if let Object::Mesh { grid, .. } = object.as_ref() {
            let key = Arc::as_ptr(object) as usize;
            if !self.grids.contains_key(&key) {
                // A bound on the cache: a long run may load many meshes.
                if self.grids.len() >= MAX_CACHED_GRIDS {
                    self.grids.clear();
                }
                let buffer =
                    self.ctx
                        .device
                        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                            label: Some("geltip sdf grid"),
                            contents: bytemuck::cast_slice(&grid.values),
                            usage: wgpu::BufferUsages::STORAGE,
                        });
                self.grids.insert(key, (object.clone(), buffer));
            }
        }
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

    /// A frame with no contact, as the camera would take it: the cached reference, with
    /// fresh sensor noise when the sensor has noise (each call draws new noise, like a real
    /// reference frame; without noise it is the reference itself).
    pub fn render_empty(&mut self) -> Result<Frame> {
        if self.sensor.config.render.noise <= 0.0 {
            return Ok(self.reference.clone());
        }
        self.seed_counter = self.seed_counter.wrapping_add(1);
        let seed =
            self.sensor.config.render.noise_seed ^ self.seed_counter.wrapping_mul(0x9E37_79B9);
        let uniform = self.uniform_buffer(&FrameUniform::reference(&self.sensor, seed));
        let bind = self.bind_group(&uniform, 0, None);
        let (w, h) = (self.sensor.width, self.sensor.height);
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        self.copy_reference(&mut encoder, 0, self.whole_image());
        self.dispatch(
            &mut encoder,
            &self.pipelines.add_noise,
            &bind,
            (groups(w, WORKGROUP), groups(h, WORKGROUP)),
        );
        self.ctx
            .submit_and_wait("rendering an empty frame", encoder)?;
        let packed = self.read_whole_image(&self.image)?;
        Ok(Frame {
            width: w,
            height: h,
            rgba: bytemuck::cast_slice(&packed).to_vec(),
            indentation: vec![0.0; (w * h) as usize],
        })
    }

    /// Renders one contact.
    pub fn render(&mut self, contact: &Contact) -> Result<(Frame, GroundTruth)> {
        let mut out = self.render_batch(std::slice::from_ref(contact))?;
        Ok(out.remove(0))
    }

    /// Renders contacts in batches of up to [`MAX_BATCH`] per submission.
    pub fn render_batch(&mut self, contacts: &[Contact]) -> Result<Vec<(Frame, GroundTruth)>> {
        let mut out = Vec::with_capacity(contacts.len());
        let mut total = Timings::default();
        for chunk in contacts.chunks(MAX_BATCH) {
            let start = Instant::now();
            let batch = prepare_batch(&self.sensor, &self.grid, chunk)?;
            total.prepare += start.elapsed();
            out.extend(self.render_prepared(batch)?);
            total.add(&self.timings);
        }
        self.timings = total;
        Ok(out)
    }

    /// Renders a batch a [`Preparer`] prepared (at most [`MAX_BATCH`] contacts, in one
    /// submission). The sensor noise's seeds follow the renderer's own count, as in
    /// [`Renderer::render_batch`].
    pub fn render_prepared(&mut self, batch: PreparedBatch) -> Result<Vec<(Frame, GroundTruth)>> {
        let mut prepared = batch.0;
        if prepared.len() > MAX_BATCH {
            return Err(GeltipError::input(
                "batch",
                format!(
                    "{} contacts, at most {MAX_BATCH} a submission",
                    prepared.len()
                ),
            ));
        }
        let mut total = Timings::default();
        for p in &mut prepared {
            self.seed_counter = self.seed_counter.wrapping_add(1);
            p.uniform.noise_seed =
                self.sensor.config.render.noise_seed ^ self.seed_counter.wrapping_mul(0x9E37_79B9);
        }
        for p in &prepared {
            self.ready_object(p)?;
        }
        let mut out = Vec::with_capacity(prepared.len());
        let ran = self.run(&prepared, &mut total);
        let Ran { frames, fields } = self.forget_heightfield_on_error(ran)?;
        let labelled = Instant::now();
        // Only a contact's pixel rect is ever indented: its mask is counted there.
        let pixel_rects: Vec<Option<Rect>> = prepared.iter().map(|p| p.pixel_rect()).collect();
        let truths = self.truths(prepared, fields);
        for (((frame, over_pressed_texels), mut truth), rect) in
            frames.into_iter().zip(truths).zip(pixel_rects)
        {
            let (count, bbox) = rect.map_or((0, None), |r| frame.mask_in(r));
            truth.mask_pixels = count;
            truth.mask_bbox = bbox;
            truth.over_pressed = over_pressed_texels > 0;
            out.push((frame, truth));
        }
        total.readback += labelled.elapsed();
        self.timings = total;
        Ok(out)
    }

    /// Records and runs the prepared frames; returns each frame with its over-pressed texels,
    /// and each contact's own penetration over its texel rect's rows.
    fn run(&mut self, prepared: &[Prepared], timings: &mut Timings) -> Result<Ran> {
        let start = Instant::now();
        let (field_offsets, field_bytes) = self.field_offsets(prepared);
        self.reserve_fields(field_bytes);
        let (w, h) = (self.sensor.width, self.sensor.height);
        let uniforms: Vec<wgpu::Buffer> = prepared
            .iter()
            .map(|p| self.uniform_buffer(&p.uniform.holding(self.changed_rect(p.pixel_rect()))))
            .collect();
        let binds: Vec<wgpu::BindGroup> = prepared
            .iter()
            .zip(&uniforms)
            .enumerate()
            .map(|(slot, (p, u))| self.bind_group(u, slot as u64, Some(&p.press.object)))
            .collect();
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        for (slot, (p, bind)) in prepared.iter().zip(&binds).enumerate() {
            self.record_frame_start(&mut encoder, slot as u64, p.pixel_rect());
            let mut normals = None;
            if let Some(footprint) = p.footprint {
                let t = footprint.texels;
                let region = self.dirty.map_or(t, |d| d.union(&t));
                self.clear_heightfield(&mut encoder, Some(region));
                self.record_heightfield(
                    &mut encoder,
                    (bind, p.uniform.object_kind),
                    footprint,
                    region,
                    field_offsets[slot],
                )?;
                self.dirty = Some(t);
                normals = Some(([(t, bind)], region));
            }
            let touched = p.pixel_rect().map(|r| Touched {
                span: (r, bind),
                pieces: vec![(r, bind)],
                camera: bind,
            });
            let normals = normals.as_ref().map(|(n, region)| (&n[..], *region));
            self.record_after_height(&mut encoder, slot as u64, normals, touched.as_ref());
            if self.sensor.config.render.noise > 0.0 {
                self.dispatch(
                    &mut encoder,
                    &self.pipelines.add_noise,
                    bind,
                    (groups(w, WORKGROUP), groups(h, WORKGROUP)),
                );
            }
        }
        let rects: Vec<Option<Rect>> = prepared
            .iter()
            .map(|p| self.changed_rect(p.pixel_rect()))
            .collect();
        let field_ranges: Vec<Option<(u64, u64)>> = prepared
            .iter()
            .zip(&field_offsets)
            .map(|(p, &at)| p.field_range(at, self.grid.texels))
            .collect();
        let read = self.read_frames("rendering contacts", encoder, &rects, &field_ranges)?;
        let rendered = read.mapped;
        timings.render += rendered - start;
        let fields = read.fields;
        let mut frames = Vec::with_capacity(prepared.len());
        for part in read.frames {
            let c = part.counters;
            timings.touched_pixels += touched_pixels(&c);
            timings.listed_tiles += c[TILE_COUNT] as u64;
            let frame = Frame {
                width: w,
                height: h,
                rgba: part.rgba,
                indentation: part.indentation,
            };
            frames.push((frame, c[OVER_PRESSED]));
        }
        if frames.len() != prepared.len() {
            return Err(GeltipError::Gpu(format!(
                "read back {} of {} frames",
                frames.len(),
                prepared.len()
            )));
        }
        timings.readback += rendered.elapsed();
        Ok(Ran { frames, fields })
    }

    /// Frame `slot`'s start: its image buffers hold the rect of the image it can change
    /// (`pixel_rect`'s, or every pixel with noise: [`Self::changed_rect`]), the reference's
    /// pixels there and zero indentation; and zero counters (the touched list itself needs
    /// no clearing: only the places its counts hold are read).
    fn record_frame_start(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slot: u64,
        pixel_rect: Option<Rect>,
    ) {
        if let Some(r) = self.changed_rect(pixel_rect) {
            let offset = slot * self.slot_bytes;
            self.copy_reference(encoder, offset, r);
            encoder.clear_buffer(&self.indentation, offset, Some(held_bytes(r)));
        }
        encoder.clear_buffer(
            &self.counters,
            slot * self.counter_bytes,
            Some(COUNTER_HEADER_BYTES),
        );
    }

    /// The reference's pixels over `r` into `image` from byte `offset`, rows
    /// [`image_pitch`] apart: a frame's buffers' layout for that rect.
    fn copy_reference(&self, encoder: &mut wgpu::CommandEncoder, offset: u64, r: Rect) {
        encoder.copy_texture_to_buffer(
            rect_of(&self.reference_texture, r),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.image,
                layout: wgpu::TexelCopyBufferLayout {
                    offset,
                    bytes_per_row: Some(image_pitch(r.w) * 4),
                    rows_per_image: None,
                },
            },
            wgpu::Extent3d {
                width: r.w,
                height: r.h,
                depth_or_array_layers: 1,
            },
        );
    }

    /// Every pixel of the image, as a rect.
    fn whole_image(&self) -> Rect {
        Rect {
            x: 0,
            y: 0,
            w: self.sensor.width,
            h: self.sensor.height,
        }
    }

    /// The rect of the image a contact frame can change: its pixel rect, or every pixel when
    /// the sensor adds noise. The rest of the frame is the reference's, which the CPU keeps,
    /// so only this rect is copied, cleared and read back (its rows [`image_pitch`] apart).
    fn changed_rect(&self, pixel_rect: Option<Rect>) -> Option<Rect> {
        if self.sensor.config.render.noise > 0.0 {
            return Some(self.whole_image());
        }
        pixel_rect.filter(|r| r.w > 0 && r.h > 0)
    }

    /// Submits `encoder` (the work that renders frames `0..rects.len()` of a batch) with the
    /// copies that read them back appended, waits once and unpacks: per frame, its image and
    /// its indentation (read over its rect, which its buffers hold; the reference's image
    /// and zero elsewhere), and its counters; then the contacts' penetration fields over
    /// `fields` (byte ranges of `penetration_fields`; an empty field for `None`).
    fn read_frames(
        &self,
        what: &str,
        mut encoder: wgpu::CommandEncoder,
        rects: &[Option<Rect>],
        fields: &[Option<(u64, u64)>],
    ) -> Result<ReadFrames> {
        enum Part {
            Rgba(Vec<u8>),
            Indentation(Vec<f32>),
            Counters(Vec<u32>),
            Field(Vec<f32>),
            // A range that does not fit the frame built for it (never, as the ranges are
            // made): reported as an incomplete readback.
            Incomplete,
        }
        let mut ranges: Vec<(&wgpu::Buffer, u64, u64)> =
            Vec::with_capacity(3 * rects.len() + fields.len());
        for (k, rect) in rects.iter().enumerate() {
            let slot = k as u64 * self.slot_bytes;
            let bytes = rect.map_or(0, held_bytes);
            ranges.push((&self.image, slot, bytes));
            ranges.push((&self.indentation, slot, bytes));
            ranges.push((
                &self.counters,
                k as u64 * self.counter_bytes,
                COUNTER_HEADER_BYTES,
            ));
        }
        for &(offset, bytes) in fields.iter().map(|f| f.as_ref().unwrap_or(&(0, 0))) {
            ranges.push((&self.penetration_fields, offset, bytes));
        }
        let frame_ranges = 3 * rects.len();
        let width = self.sensor.width as usize;
        let pixels = width * self.sensor.height as usize;
        // The copies ride in the submission of the work they read: one round trip. (The
        // kept staging buffer holds a full batch; a scene of very many contacts may need
        // more for its fields.)
        let mut fresh = None;
        let total = staging_bytes(&ranges)?;
        let staging = staging_or_fresh(self.ctx, Some(&self.staging), total, &mut fresh);
        record_ranges(&mut encoder, staging, &ranges)?;
        let submission = self.ctx.submit(what, encoder)?;
        // Each frame's image and indentation as the reference's pixels and zeros, laid out
        // while the GPU works: this thread would only wait, and after the wait only the
        // rects read are left to copy over them.
        let (mut images, mut indentations): (Vec<_>, Vec<_>) = rects
            .iter()
            .map(|_| {
                (
                    Some(self.reference.rgba.clone()),
                    Some(vec![0.0f32; pixels]),
                )
            })
            .unzip();
        let mut mapped = None;
        let parts = unpack_ranges(self.ctx, staging, &ranges, submission, |k, bytes| {
            mapped.get_or_insert_with(Instant::now);
            if k >= frame_ranges {
                return Part::Field(bytemuck::pod_collect_to_vec(bytes));
            }
            let frame = k / 3;
            // The rect's rows, each `pitch` pixels of the bytes read, into the frame's rows.
            let rows = |pixel_bytes: usize| -> Option<Vec<(usize, std::ops::Range<usize>)>> {
                let Some(r) = rects[frame] else {
                    return Some(Vec::new());
                };
                let (x, y, w) = (r.x as usize, r.y as usize, r.w as usize);
                let pitch = image_pitch(r.w) as usize * pixel_bytes;
                if x + w > width || (y + r.h as usize) * width > pixels {
                    return None;
                }
                Some(
                    (0..r.h as usize)
                        .map(|j| ((y + j) * width + x, j * pitch..j * pitch + w * pixel_bytes))
                        .collect(),
                )
            };
            match (k % 3, rows(4)) {
                (0, Some(rows)) => match images[frame].take() {
                    Some(mut rgba) => {
                        for (at, from) in rows {
                            let n = from.len();
                            rgba[at * 4..at * 4 + n].copy_from_slice(&bytes[from]);
                        }
                        Part::Rgba(rgba)
                    }
                    None => Part::Incomplete,
                },
                (1, Some(rows)) => match indentations[frame].take() {
                    Some(mut indentation) => {
                        for (at, from) in rows {
                            for (depth, b) in indentation[at..]
                                .iter_mut()
                                .zip(bytes[from].chunks_exact(4))
                            {
                                *depth = f32::from_ne_bytes([b[0], b[1], b[2], b[3]]);
                            }
                        }
                        Part::Indentation(indentation)
                    }
                    None => Part::Incomplete,
                },
                (2, _) => Part::Counters(bytemuck::pod_collect_to_vec(bytes)),
                _ => Part::Incomplete,
            }
        })?;
        let mut frames = Vec::with_capacity(rects.len());
        let mut out_fields = Vec::with_capacity(fields.len());
        let mut parts = parts.into_iter();
        while frames.len() < rects.len() {
            match (parts.next(), parts.next(), parts.next()) {
                (
                    Some(Part::Rgba(rgba)),
                    Some(Part::Indentation(indentation)),
                    Some(Part::Counters(counters)),
                ) => frames.push(FrameParts {
                    rgba,
                    indentation,
                    counters,
                }),
                _ => {
                    return Err(GeltipError::Gpu(
                        "a frame's readback is incomplete".to_string(),
                    ))
                }
            }
        }
        for part in parts {
            if let Part::Field(field) = part {
                out_fields.push(field);
            }
        }
        if out_fields.len() != fields.len() {
            return Err(GeltipError::Gpu(format!(
                "read back {} of {} penetration fields",
                out_fields.len(),
                fields.len()
            )));
        }
        Ok(ReadFrames {
            frames,
            fields: out_fields,
            mapped: mapped.unwrap_or_else(Instant::now),
        })
    }

    /// Renders one contact and returns each stage's time (for the benchmark's breakdown;
    /// slower than [`Renderer::render`]). Where the device writes timestamps between
    /// commands (lavapipe does), the frame is recorded and submitted once, as
    /// [`Renderer::render`] does, with a timestamp after each stage: a stage's time is then
    /// its own work, not a submission's and a wait's. Elsewhere each stage is submitted and
    /// waited for on its own, and its wall time includes both. The readback is timed on the
    /// CPU either way.
    pub fn profile_stages(&mut self, contact: &Contact) -> Result<Vec<(&'static str, Duration)>> {
        let p = self.prepare(&Press::from(contact), 0)?;
        let uniform = self.uniform_buffer(&p.uniform.holding(self.changed_rect(p.pixel_rect())));
        let bind = self.bind_group(&uniform, 0, Some(&p.press.object));
        let region = match (self.dirty, p.footprint.map(|f| f.texels)) {
            (Some(d), Some(t)) => Some(d.union(&t)),
            (d, t) => d.or(t),
        };
        enum Step<'a> {
            Clear,
            Contact(&'a wgpu::ComputePipeline),
            Texels(&'a wgpu::ComputePipeline, Map, Over),
            Normals,
            Select,
            Touched,
        }
        let mut stages = vec![
            ("copy reference + clear", Step::Clear),
            (
                "contact",
                Step::Contact(self.contact_pipeline(p.uniform.object_kind)?),
            ),
        ];
        for (name, pipeline, map, over) in self.blend_stages() {
            stages.push((name, Step::Texels(pipeline, map, over)));
        }
        stages.extend([
            ("elastomer: skin normals", Step::Normals),
            ("camera: select touched", Step::Select),
            ("camera + leds: touched pixels", Step::Touched),
        ]);
        let record = |encoder: &mut wgpu::CommandEncoder, step: &Step| match *step {
            Step::Clear => {
                self.record_frame_start(encoder, 0, p.pixel_rect());
                if let Some(region) = region {
                    self.clear_heightfield(encoder, Some(region));
                }
            }
            Step::Contact(pipeline) => {
                if let (Some(pressed), Some(region)) = (p.footprint.map(|f| f.pressed), region) {
                    self.record_texels(encoder, &bind, pipeline, Map::Penetration, pressed, region);
                    self.copy_field(encoder, pressed, 0);
                }
            }
            Step::Texels(pipeline, map, over) => {
                if let (Some(f), Some(region)) = (p.footprint, region) {
                    self.record_texels(encoder, &bind, pipeline, map, over.of(f), region);
                }
            }
            // A frame records the normals and the selection's first step in one pass; here
            // each is timed on its own.
            Step::Normals => {
                if let (Some(t), Some(region)) = (p.footprint.map(|f| f.texels), region) {
                    self.record_normals_and_select(encoder, 0, Some((&[(t, &bind)], region)), None);
                }
            }
            Step::Select => {
                if let Some(r) = p.pixel_rect() {
                    let touched = Touched {
                        span: (r, &bind),
                        pieces: vec![(r, &bind)],
                        camera: &bind,
                    };
                    self.record_normals_and_select(encoder, 0, None, Some(&touched));
                }
            }
            Step::Touched => {
                if p.pixel_rect().is_some() {
                    self.record_touched_passes(encoder, 0, &bind);
                }
            }
        };
        let mut out = Vec::new();
        if self.ctx.has_timestamps() {
            let marks = stages.len() as u32 + 1;
            let queries = self.ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("geltip stage timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: marks,
            });
            let resolved = storage(
                self.ctx,
                "geltip stage timestamps",
                marks as u64 * 8,
                wgpu::BufferUsages::QUERY_RESOLVE,
            );
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            encoder.write_timestamp(&queries, 0);
            for (k, (_, step)) in stages.iter().enumerate() {
                record(&mut encoder, step);
                encoder.write_timestamp(&queries, k as u32 + 1);
            }
            encoder.resolve_query_set(&queries, 0..marks, &resolved, 0);
            self.ctx.submit_and_wait("profiling a frame", encoder)?;
            let ticks: Vec<u64> = read_buffer(self.ctx, &resolved, 0, marks as usize)?;
            let ns = self.ctx.queue.get_timestamp_period() as f64;
            for (k, (name, _)) in stages.iter().enumerate() {
                let elapsed = ticks[k + 1].saturating_sub(ticks[k]) as f64 * ns;
                out.push((*name, Duration::from_nanos(elapsed as u64)));
            }
        } else {
            for (name, step) in &stages {
                let start = Instant::now();
                let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
                record(&mut encoder, step);
                self.ctx.submit_and_wait(name, encoder)?;
                out.push((*name, start.elapsed()));
            }
        }
        let start = Instant::now();
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        self.read_frames(
            "profile readback",
            encoder,
            &[self.changed_rect(p.pixel_rect())],
            &[],
        )?;
        out.push(("readback", start.elapsed()));
        if let (Some(f), Some(r)) = (p.footprint, p.pixel_rect()) {
            let t = f.texels;
            log::info!("texel rect {}x{}, pixel rect {}x{}", t.w, t.h, r.w, r.h);
        }
        if let Some(f) = p.footprint {
            self.dirty = Some(f.texels);
        }
        Ok(out)
    }

    /// The undeformed surface points the GPU's lens rays meet for `pixels` (None beyond the
    /// lens): the GPU half of the CPU/GPU projection comparison.
    pub fn unproject_pixels(&mut self, pixels: &[glam::DVec2]) -> Result<Vec<Option<glam::DVec3>>> {
        let max = (self.grid.texels as usize).pow(2);
        if pixels.len() > max {
            return Err(GeltipError::input(
                "unproject_pixels",
                format!("at most {max} pixels at once"),
            ));
        }
        let input: Vec<[f32; 4]> = pixels
            .iter()
            .map(|p| [p.x as f32, p.y as f32, 0.0, 0.0])
            .collect();
        self.ctx
            .queue
            .write_buffer(&self.elastomer_scratch, 0, bytemuck::cast_slice(&input));
        let mut uniform = FrameUniform::reference(&self.sensor, 0);
        uniform.pixel_rect = [0, 0, pixels.len() as u32, 1];
        let ub = self.uniform_buffer(&uniform);
        let bind = self.bind_group(&ub, 0, None);
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        self.dispatch(
            &mut encoder,
            &self.pipelines.unproject_pixels,
            &bind,
            (groups(pixels.len() as u32, 64), 1),
        );
        self.ctx.submit_and_wait("unprojecting pixels", encoder)?;
        let out: Vec<[f32; 4]> = read_buffer(self.ctx, &self.elastomer_scratch, 0, pixels.len())?;
        Ok(out
            .into_iter()
            .map(|v| (v[3] != 0.0).then(|| glam::DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)))
            .collect())
    }
}

/// The labels of one press, from its pose and (on the CPU, over its footprint's texels) the
/// contact stage's penetration field; the mask and over-press are filled in after rendering.
fn ground_truth(
    sensor: &Sensor,
    press: &Press,
    pose: &ContactPose,
    labels: Option<contact::IndentationLabels>,
) -> GroundTruth {
    let f = &sensor.finger;
    let (place, azimuth_deg, spin_deg, tilt_deg, tilt_towards_deg) = match press.hold {
        Hold::Surface {
            place,
            azimuth_deg,
            spin_deg,
            tilt_deg,
            tilt_towards_deg,
            ..
        } => (
            place.label(),
            azimuth_deg,
            spin_deg,
            tilt_deg,
            tilt_towards_deg,
        ),
        Hold::Pose { .. } => (
            "pose".to_string(),
            pose.coord.phi.to_degrees(),
            0.0,
            0.0,
            0.0,
        ),
    };
    GroundTruth {
        object: press.object.name().to_string(),
        place,
        point: pose.point,
        pixel: sensor.project(pose.point).map_err(|why| why.to_string()),
        normal: pose.normal,
        depth_mm: pose.depth_mm,
        region: pose.region,
        s_mm: pose.coord.s,
        azimuth_deg,
        spin_deg,
        mask_pixels: 0,
        mask_bbox: None,
        over_pressed: false,
        contact_indentation_mm: contact::penetration(
            pose,
            &press.object,
            &f.point_at(pose.coord),
            pose.trace_depth_mm,
            sensor.config.elastomer.drape_mm,
            contact::TRACE_EPSILON_MM,
        ),
        tilt_deg,
        tilt_towards_deg,
        pose: pose.matrix_row_major(),
        first_touch_offset_mm: pose.first_touch_offset_mm,
        first_touch: pose.first_touch.clone(),
        indentation_reached_mm: labels.as_ref().map_or(0.0, |l| l.reached_mm),
        deepest_point: labels.as_ref().and_then(|l| l.deepest),
        contact_centre: labels.as_ref().and_then(|l| l.centre),
        indented_area_mm2: labels.as_ref().map_or(0.0, |l| l.area_mm2),
    }
}

impl Renderer {
    /// Renders several objects pressed into the finger at once, as one frame: the skin is
    /// pushed by whichever object is deepest at each texel (the contact stage runs once per
    /// object over its own footprint, keeping the maximum), and the elastomer, camera and LED
    /// stages run once over the union of the footprints (split into disjoint rectangles, so
    /// the cost follows the footprints' area, not the number of objects). One label per
    /// press, in order: its mask is the pressed pixels inside its own footprint's pixel
    /// rectangle; `over_pressed` is the frame's (any object against the shell).
    pub fn render_scene(&mut self, presses: &[Press]) -> Result<(Frame, Vec<GroundTruth>)> {
        let rendered = self.render_scene_once(presses);
        self.forget_heightfield_on_error(rendered)
    }

    /// After a failed frame the heightfield's state is unknown (the recorded clears may
    /// never have run, or run in part): the next frame clears all of it.
    fn forget_heightfield_on_error<T>(&mut self, result: Result<T>) -> Result<T> {
        if result.is_err() {
            let n = self.grid.texels;
            self.dirty = Some(Rect {
                x: 0,
                y: 0,
                w: n,
                h: n,
            });
        }
        result
    }

    /// [`Renderer::render_scene`], leaving the heightfield's bookkeeping to its caller on
    /// error.
    fn render_scene_once(&mut self, presses: &[Press]) -> Result<(Frame, Vec<GroundTruth>)> {
        if presses.is_empty() {
            return Err(GeltipError::input("scene", "no contacts to render"));
        }
        let start = Instant::now();
        self.seed_counter = self.seed_counter.wrapping_add(1);
        let seed =
            self.sensor.config.render.noise_seed ^ self.seed_counter.wrapping_mul(0x9E37_79B9);
        // The contacts side by side on rayon's threads (each scan inside is parallel too,
        // but a contact's own serial steps, such as its first-touch refinement, are not).
        let (sensor, grid) = (&self.sensor, &self.grid);
        let prepared: Vec<Prepared> = presses
            .par_iter()
            .map(|p| prepare_contact(sensor, grid, p, seed))
            .collect::<Result<_>>()?;
        for p in &prepared {
            self.ready_object(p)?;
        }
        let (field_offsets, field_bytes) = self.field_offsets(&prepared);
        self.reserve_fields(field_bytes);
        let texel_pieces = Rect::disjoint(
            prepared
                .iter()
                .filter_map(|p| p.footprint.map(|f| f.texels)),
        );
        let meridian_pieces = Rect::disjoint(
            prepared
                .iter()
                .filter_map(|p| p.footprint.map(|f| f.meridians)),
        );
        let pixel_pieces = Rect::disjoint(prepared.iter().filter_map(|p| p.pixel_rect()));
        let mut timings = Timings {
            prepare: start.elapsed(),
            ..Timings::default()
        };
        let render_start = Instant::now();
        let (w, h) = (self.sensor.width, self.sensor.height);
        let texel_span = texel_pieces.iter().copied().reduce(|a, b| a.union(&b));
        // The pixels the scene can change (every pixel with noise), as `run` has per contact.
        let pixel_span = pixel_pieces.iter().copied().reduce(|a, b| a.union(&b));
        let holding = self.changed_rect(pixel_span);
        let piece_uniform = |t: Option<Rect>, r: Option<Rect>| {
            let mut u = prepared[0].uniform.holding(holding);
            u.texel_rect = t.map_or([0; 4], |t| [t.x, t.y, t.w, t.h]);
            u.pixel_rect = r.map_or([0; 4], |r| [r.x, r.y, r.w, r.h]);
            u
        };
        let contact_uniforms: Vec<wgpu::Buffer> = prepared
            .iter()
            .map(|p| self.uniform_buffer(&p.uniform))
            .collect();
        let contact_binds: Vec<wgpu::BindGroup> = prepared
            .iter()
            .zip(&contact_uniforms)
            .map(|(p, u)| self.bind_group(u, 0, Some(&p.press.object)))
            .collect();
        let texel_binds =
            self.bind_uniforms(texel_pieces.iter().map(|&t| piece_uniform(Some(t), None)));
        let meridian_binds = self.bind_uniforms(meridian_pieces.iter().map(|m| {
            let mut u = piece_uniform(None, None);
            u.meridian_rect = [m.x, m.y, m.w, m.h];
            u
        }));
        // Only the selection without the tile list runs over the pixel pieces one by one.
        let pixel_binds = self.bind_uniforms(
            pixel_pieces
                .iter()
                .filter(|_| !self.list_tiles)
                .map(|&r| piece_uniform(None, Some(r))),
        );
        let whole_uniform = self.uniform_buffer(&piece_uniform(None, None));
        let whole_bind = self.bind_group(&whole_uniform, 0, None);
        let span_uniform = self.uniform_buffer(&piece_uniform(texel_span, pixel_span));
        let span_bind = self.bind_group(&span_uniform, 0, None);
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        self.record_frame_start(&mut encoder, 0, pixel_span);
        let mut normals = None;
        if let Some(span) = texel_span {
            // The contact stage keeps the deepest penetration: it must start from zero, and
            // the maps must lose what the last frame left outside this one.
            let region = self.dirty.map_or(span, |d| d.union(&span));
            self.clear_heightfield(&mut encoder, Some(region));
            // Each object's contact pass over its own pressed rect, with its own pipeline.
            for ((p, bind), &at) in prepared.iter().zip(&contact_binds).zip(&field_offsets) {
                if let Some(r) = p.footprint.map(|f| f.pressed) {
                    let g = (groups(r.w, WORKGROUP), groups(r.h, WORKGROUP));
                    let contact = self.contact_pipeline(p.uniform.object_kind)?;
                    self.dispatch(&mut encoder, contact, bind, g);
                    self.copy_field(&mut encoder, r, at);
                }
            }
            self.copy_to_map(&mut encoder, Map::Penetration, Some(region));
            for (_, pipeline, map, over) in self.blend_stages() {
                let (rects, binds) = match over {
                    Over::Meridians => (&meridian_pieces, &meridian_binds),
                    Over::Texels => (&texel_pieces, &texel_binds),
                };
                let pieces: Vec<_> = rects
                    .iter()
                    .zip(binds)
                    .map(|(t, bind)| (pipeline, bind, Groups::over(*t)))
                    .collect();
                self.record_pass(&mut encoder, &pieces);
                self.copy_to_map(&mut encoder, map, Some(region));
            }
            self.dirty = Some(span);
            normals = Some(region);
        }
        let texel_pieces: Vec<(Rect, &wgpu::BindGroup)> =
            texel_pieces.iter().copied().zip(&texel_binds).collect();
        let touched = pixel_span.map(|span| Touched {
            span: (span, &span_bind),
            pieces: pixel_pieces.iter().copied().zip(&pixel_binds).collect(),
            camera: &whole_bind,
        });
        let normals = normals.map(|region| (&texel_pieces[..], region));
        self.record_after_height(&mut encoder, 0, normals, touched.as_ref());
        if self.sensor.config.render.noise > 0.0 {
            self.dispatch(
                &mut encoder,
                &self.pipelines.add_noise,
                &whole_bind,
                (groups(w, WORKGROUP), groups(h, WORKGROUP)),
            );
        }
        let field_ranges: Vec<Option<(u64, u64)>> = prepared
            .iter()
            .zip(&field_offsets)
            .map(|(p, &at)| p.field_range(at, self.grid.texels))
            .collect();
        let rects = [self.changed_rect(pixel_span)];
        let read = self.read_frames("rendering a scene", encoder, &rects, &field_ranges)?;
        let rendered = read.mapped;
        timings.render = rendered - render_start;
        let fields = read.fields;
        let Some(part) = read.frames.into_iter().next() else {
            return Err(GeltipError::Gpu("read back no scene frame".to_string()));
        };
        let c = part.counters;
        timings.touched_pixels = touched_pixels(&c);
        timings.listed_tiles = c[TILE_COUNT] as u64;
        let frame = Frame {
            width: w,
            height: h,
            rgba: part.rgba,
            indentation: part.indentation,
        };
        let over_pressed = c[OVER_PRESSED] > 0;
        let pixel_rects: Vec<Option<Rect>> = prepared.iter().map(|p| p.pixel_rect()).collect();
        let truths = self
            .truths(prepared, fields)
            .into_iter()
            .zip(pixel_rects)
            .map(|(mut truth, pixel_rect)| {
                let (count, bbox) = pixel_rect.map_or((0, None), |r| frame.mask_in(r));
                truth.mask_pixels = count;
                truth.mask_bbox = bbox;
                truth.over_pressed = over_pressed;
                truth
            })
            .collect();
        timings.readback = rendered.elapsed();
        self.timings = timings;
        Ok((frame, truths))
    }
}
