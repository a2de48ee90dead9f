//! Every buffer, texture and sampler the renderer uses, and its bind group layout, made in
//! one place ([`Resources::new`]) once the device is known to hold them.

use super::bindings::{layout_entries, FRAMES_BOUND_BYTES};
use super::layout::{
    COUNTER_HEADER_BYTES, DISPATCH_ARGS_BYTES, PROBES_BYTES_PER_PIXEL, PROBE_TILE_BYTES,
};
use crate::error::{GeltipError, Result};
use crate::gpu::GpuContext;
use crate::object::Object;
use crate::render::touched::tile_grid;
use crate::render::uniforms::{image_pitch, FrameUniform, SensorUniform};
use crate::render::{HeightfieldGrid, Rect};
use crate::sensor::Sensor;
use std::collections::HashMap;
use std::sync::Arc;
use wgpu::util::DeviceExt;

/// Baked SDF grids of loaded meshes kept on the GPU at most.
const MAX_CACHED_GRIDS: usize = 16;

pub(super) struct Resources {
    pub layout: wgpu::BindGroupLayout,
    pub pipeline_layout: wgpu::PipelineLayout,
    pub sensor: wgpu::Buffer,
    /// A heightfield per lane, in one set of buffers and map arrays: the frames of a
    /// submission whose stages are recorded side by side each work on their own
    /// ([`super::Renderer::set_lanes`]), and each stage runs over all of them at once.
    pub heightfield: Heightfield,
    /// Per pixel, where its ray crosses the shell (written by the reference frame); then
    /// per tile of pixels, the texels those crossings read (`probe_tiles_of_rays`).
    pub probes: wgpu::Buffer,
    /// `probes` as the passes read it: pixel (x, y)'s two vec4 are texels (2x, y), (2x+1, y).
    pub probe_map: MapTexture,
    /// Nearest, clamped: the maps' textureGather (see `shaders/shared/common.wgsl`).
    pub map_sampler: wgpu::Sampler,
    /// The image and indentation of each frame of a submission over the rect it holds,
    /// packed in order ([`super::bindings::packed_offsets`]; `slot_bytes` a frame at most).
    pub image: wgpu::Buffer,
    pub indentation: wgpu::Buffer,
    /// The frames' counters and lists, `counter_bytes` a frame: a wave's from its first
    /// frame's slot on, their counters side by side and their lists after them.
    pub counters: wgpu::Buffer,
    /// Per wave, at its first frame's slot, the indirect dispatches' arguments, copied from
    /// `counters` ([`super::layout::dispatch_args_at`]).
    pub dispatch_args: wgpu::Buffer,
    /// The empty finger's image, from which a frame copies the rect it can change.
    pub reference_texture: wgpu::Texture,
    pub reference_view: wgpu::TextureView,
    /// Kept for reading a submission back (its images, indentation rows and counters),
    /// grown to the largest submission read so far.
    pub staging: wgpu::Buffer,
    /// A submission's frame uniforms, [`UNIFORM_STRIDE`] bytes apart, written before it.
    pub frame_uniforms: wgpu::Buffer,
    /// Frames of a submission the image, indentation, counters and dispatch buffers hold.
    pub frames: usize,
    /// What a frame without a loaded mesh binds as its SDF grid.
    pub empty_grid: wgpu::Buffer,
    /// Baked SDF grids of loaded meshes, by object (the Arc keeps the address unique).
    grids: HashMap<usize, (Arc<Object>, wgpu::Buffer)>,
    /// Bytes of one frame's slice of `image` and `indentation`: the whole image with rows
    /// [`image_pitch`] apart (a contact frame's rect takes less).
    pub slot_bytes: u64,
    /// Bytes of one frame's slice of `counters`: the counters, the touched list and the
    /// tile list.
    pub counter_bytes: u64,
}

/// The heightfield's three buffers, which the stages write, and their maps, which the
/// samplers read (see `shaders/shared/common.wgsl` for why both): `lanes` heightfields, a
/// lane's texels after the lane before's in the buffers and a layer each in the maps. After
/// the lanes' heights, the height buffer holds the contacts' own penetration fields
/// ([`Self::fields_at`]).
pub(super) struct Heightfield {
    buffers: [wgpu::Buffer; 3],
    maps: [MapTexture; 3],
    texels: u32,
    lanes: u32,
}

/// Lanes of the heightfield, from the first to the last, over the texels of `rect`: what a
/// wave of frames clears and refreshes at once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct LaneSpan {
    pub first: u32,
    pub last: u32,
    pub rect: Rect,
}

/// A texture copy of a buffer the shaders sample, and the bytes per texel of both.
pub(super) struct MapTexture {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    pub texel_bytes: u32,
}

/// The heightfield's buffers and maps, in the order of their bindings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Map {
    Penetration = 0,
    Elastomer = 1,
    Height = 2,
}

impl Map {
    pub const ALL: [Map; 3] = [Map::Penetration, Map::Elastomer, Map::Height];
}

/// Bytes a frame's image (or indentation) buffer takes to hold rect `r` of the image: its
/// rows, [`image_pitch`] pixels apart.
pub(super) fn held_bytes(r: Rect) -> u64 {
    r.h as u64 * image_pitch(r.w) as u64 * 4
}

/// The size of `rect` as a copy's extent.
pub(super) fn extent(rect: Rect) -> wgpu::Extent3d {
    wgpu::Extent3d {
        width: rect.w,
        height: rect.h,
        depth_or_array_layers: 1,
    }
}

pub(super) fn storage(
    ctx: &GpuContext,
    label: &str,
    size: u64,
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
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

/// A buffer for `count` frame uniforms, [`UNIFORM_STRIDE`] bytes apart, bound from any of
/// them ([`FRAMES_BOUND_BYTES`] a binding).
pub(super) fn uniforms(ctx: &GpuContext, count: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("geltip frame uniforms"),
        size: count * UNIFORM_STRIDE + FRAMES_BOUND_BYTES,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A map of `width` x `height` texels; with `layers`, an array of that many (viewed as an
/// array even of one).
fn map_texture(
    ctx: &GpuContext,
    label: &str,
    (width, height): (u32, u32),
    layers: Option<u32>,
    format: wgpu::TextureFormat,
) -> MapTexture {
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: layers.unwrap_or(1),
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let dimension = match layers {
        Some(_) => wgpu::TextureViewDimension::D2Array,
        None => wgpu::TextureViewDimension::D2,
    };
    let view = texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(dimension),
        ..Default::default()
    });
    MapTexture {
        texture,
        view,
        texel_bytes: format.block_copy_size(None).unwrap_or(4),
    }
}

/// Bytes of the probes buffer: the pixels' probes, then the tiles' texel ranges.
fn probes_bytes(sensor: &Sensor) -> u64 {
    let (tiles_x, tiles_y) = tile_grid(sensor.width, sensor.height);
    let pixels = sensor.width as u64 * sensor.height as u64;
    pixels * PROBES_BYTES_PER_PIXEL + tiles_x as u64 * tiles_y as u64 * PROBE_TILE_BYTES
}

/// Refuses a device that cannot hold or run the renderer for `sensor`, naming what is short.
fn check_device(ctx: &GpuContext, sensor: &Sensor, grid: &HeightfieldGrid) -> Result<()> {
    check_frames(ctx, sensor, 1)?;
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
    if limits.max_uniform_buffer_binding_size < FRAMES_BOUND_BYTES {
        return Err(GeltipError::Gpu(format!(
            "adapter {} binds {} bytes of uniforms at most; the renderer needs {FRAMES_BOUND_BYTES}",
            ctx.adapter_info.name, limits.max_uniform_buffer_binding_size
        )));
    }
    let allowed = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    let (w, h) = (sensor.width, sensor.height);
    let side = limits.max_texture_dimension_2d;
    if 2 * w > side || h > side {
        return Err(GeltipError::input(
            "image",
            format!(
                "{w}x{h} needs a {}x{h} texture; this device allows {side} per side",
                2 * w
            ),
        ));
    }
    let n = grid.texels;
    if n > side {
        return Err(GeltipError::config(
            "render.heightfield_texels",
            format!("{n} exceeds this device's {side} texels per texture side"),
        ));
    }
    let texel_bytes = n as u64 * n as u64 * 16;
    if texel_bytes > allowed {
        return Err(GeltipError::config(
            "render.heightfield_texels",
            format!(
                "{n} texels per side need {texel_bytes} byte GPU buffers; this device allows {allowed}"
            ),
        ));
    }
    Ok(())
}

/// Refuses a submission of `frames` frames of `sensor` that this device cannot hold, naming
/// what is short.
pub(super) fn check_frames(ctx: &GpuContext, sensor: &Sensor, frames: usize) -> Result<()> {
    let limits = ctx.device.limits();
    let slot_bytes = held_bytes(whole_image(sensor));
    let (w, h) = (sensor.width, sensor.height);
    let allowed = limits.max_storage_buffer_binding_size;
    let image_bytes = probes_bytes(sensor).max(slot_bytes);
    if image_bytes > allowed {
        return Err(GeltipError::input(
            "image",
            format!("{w}x{h} needs {image_bytes} byte GPU buffers; this device allows {allowed}"),
        ));
    }
    let batch_bytes = slot_bytes * frames as u64;
    let allowed = limits.max_buffer_size;
    if batch_bytes > allowed {
        return Err(GeltipError::input(
            "batch",
            format!(
                "{frames} frames of {w}x{h} need {batch_bytes} byte GPU buffers; this device allows {allowed}"
            ),
        ));
    }
    Ok(())
}

/// Bytes between two frame uniforms of a submission: the uniform offset alignment every
/// device allows.
pub(super) const UNIFORM_STRIDE: u64 = 256;

/// Lanes (frames recorded side by side, [`super::Renderer::set_lanes`]) the device can bind
/// at once for `sensor` and `grid`: every stage binds every lane's heightfield, and the
/// image, indentation and counters of a wave's frames, within one binding each.
pub(super) fn max_lanes(ctx: &GpuContext, sensor: &Sensor, grid: &HeightfieldGrid) -> usize {
    let limits = ctx.device.limits();
    let allowed = limits.max_storage_buffer_binding_size;
    let slot_bytes = held_bytes(whole_image(sensor));
    let pixels = sensor.width as u64 * sensor.height as u64;
    let elastomer = grid.texels as u64 * grid.texels as u64 * 16;
    let per_lane = slot_bytes.max(counter_bytes(sensor, pixels)).max(elastomer);
    (allowed / per_lane)
        .min(limits.max_texture_array_layers as u64)
        .clamp(1, super::MAX_BATCH as u64) as usize
}

/// Bytes of one frame's slice of the counters buffer: the counters, the touched list (a
/// pixel each) and the tile list (a tile each).
fn counter_bytes(sensor: &Sensor, pixels: u64) -> u64 {
    let (tiles_x, tiles_y) = tile_grid(sensor.width, sensor.height);
    let tiles = tiles_x as u64 * tiles_y as u64;
    (COUNTER_HEADER_BYTES + pixels * 4 + tiles * 4).next_multiple_of(256)
}

/// Every pixel of `sensor`'s image, as a rect.
pub(super) fn whole_image(sensor: &Sensor) -> Rect {
    Rect {
        x: 0,
        y: 0,
        w: sensor.width,
        h: sensor.height,
    }
}

impl Resources {
    /// Everything the renderer of `sensor` binds, once [`check_device`] passes.
    // Over 80 lines: one struct literal, every resource in one place.
    /// The frame buffers hold `frames` frames ([`Self::reserve_frames`] grows them).
    pub fn new(
        ctx: &GpuContext,
        sensor: &Sensor,
        grid: &HeightfieldGrid,
        frames: usize,
    ) -> Result<Resources> {
        check_device(ctx, sensor, grid)?;
        check_frames(ctx, sensor, frames)?;
        let texels = grid.texels as u64 * grid.texels as u64;
        let slot_bytes = held_bytes(whole_image(sensor));
        let pixels = sensor.width as u64 * sensor.height as u64;
        let counter_bytes = counter_bytes(sensor, pixels);
        let (layout, pipeline_layout) = ctx.scoped("creating the renderer's layout", || {
            let layout = ctx
                .device
                .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("geltip renderer"),
                    entries: &layout_entries(),
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
        let none = wgpu::BufferUsages::empty();
        let batch = frames as u64;
        let reference_texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("geltip reference texture"),
            size: extent(whole_image(sensor)),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Uint,
            usage: wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let reference_view = reference_texture.create_view(&Default::default());
        Ok(Resources {
            layout,
            pipeline_layout,
            sensor: ctx
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("geltip sensor"),
                    contents: bytemuck::bytes_of(&SensorUniform::new(sensor, grid)),
                    usage: wgpu::BufferUsages::UNIFORM,
                }),
            heightfield: Heightfield::new(ctx, grid.texels, 1, 0),
            probes: storage(ctx, "geltip ray probes", probes_bytes(sensor), none),
            probe_map: map_texture(
                ctx,
                "geltip ray probes map",
                (2 * sensor.width, sensor.height),
                None,
                wgpu::TextureFormat::Rgba32Float,
            ),
            map_sampler: ctx.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("geltip map sampler"),
                ..Default::default()
            }),
            image: storage(ctx, "geltip image", slot_bytes * batch, none),
            indentation: storage(ctx, "geltip indentation", slot_bytes * batch, none),
            counters: storage(
                ctx,
                "geltip counters and touched pixels",
                counter_bytes * batch,
                none,
            ),
            dispatch_args: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("geltip touched dispatch"),
                size: DISPATCH_ARGS_BYTES * batch,
                usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            reference_texture,
            reference_view,
            staging: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("geltip batch readback"),
                size: (2 * slot_bytes + COUNTER_HEADER_BYTES + texels * 4) * batch.min(8),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            frame_uniforms: uniforms(ctx, 4 * batch),
            frames,
            empty_grid: storage(ctx, "geltip empty grid", 16, none),
            grids: HashMap::new(),
            slot_bytes,
            counter_bytes,
        })
    }

    /// The reference's pixels over `r` into `image` from byte `offset`, rows
    /// [`image_pitch`] apart: a frame's buffers' layout for that rect.
    pub fn copy_reference(&self, encoder: &mut wgpu::CommandEncoder, offset: u64, r: Rect) {
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.reference_texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: r.x,
                    y: r.y,
                    z: 0,
                },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &self.image,
                layout: wgpu::TexelCopyBufferLayout {
                    offset,
                    bytes_per_row: Some(image_pitch(r.w) * 4),
                    rows_per_image: None,
                },
            },
            extent(r),
        );
    }

    /// Makes the frame buffers (image, indentation, counters, dispatch arguments) hold a
    /// submission of `frames` frames; what they held is dropped (each frame's start writes
    /// its slices anew).
    pub fn reserve_frames(&mut self, ctx: &GpuContext, frames: usize) {
        if frames <= self.frames {
            return;
        }
        let (n, none) = (frames as u64, wgpu::BufferUsages::empty());
        self.image = storage(ctx, "geltip image", self.slot_bytes * n, none);
        self.indentation = storage(ctx, "geltip indentation", self.slot_bytes * n, none);
        self.counters = storage(
            ctx,
            "geltip counters and touched pixels",
            self.counter_bytes * n,
            none,
        );
        self.dispatch_args = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("geltip touched dispatch"),
            size: DISPATCH_ARGS_BYTES * n,
            usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.frames = frames;
    }

    /// Makes the heightfield hold at least `lanes` lanes; a new one is zero everywhere (as
    /// wgpu makes it), the contacts' fields kept as large.
    pub fn reserve_lanes(&mut self, ctx: &GpuContext, lanes: usize) {
        let h = &self.heightfield;
        if (lanes as u32) > h.lanes {
            let lanes_bytes = h.lane_bytes(Map::Height) * h.lanes as u64;
            let fields = h.buffer(Map::Height).size() - lanes_bytes;
            self.heightfield = Heightfield::new(ctx, h.texels, lanes as u32, fields);
        }
    }

    /// Makes `staging` take `bytes` (kept for the submissions after).
    pub fn reserve_staging(&mut self, ctx: &GpuContext, bytes: u64) {
        if self.staging.size() < bytes {
            self.staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("geltip batch readback"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
        }
    }

    /// Writes a submission's frame uniforms, [`UNIFORM_STRIDE`] bytes apart (uniform `k` at
    /// byte `k * UNIFORM_STRIDE` of `frame_uniforms`), growing the buffer if it must.
    pub fn write_uniforms(&mut self, ctx: &GpuContext, all: &[FrameUniform]) {
        let bytes = all.len() as u64 * UNIFORM_STRIDE + FRAMES_BOUND_BYTES;
        if self.frame_uniforms.size() < bytes {
            self.frame_uniforms = uniforms(ctx, all.len() as u64);
        }
        let mut data = vec![0u8; all.len() * UNIFORM_STRIDE as usize];
        for (chunk, u) in data.chunks_exact_mut(UNIFORM_STRIDE as usize).zip(all) {
            chunk[..std::mem::size_of::<FrameUniform>()].copy_from_slice(bytemuck::bytes_of(u));
        }
        if !data.is_empty() {
            ctx.queue.write_buffer(&self.frame_uniforms, 0, &data);
        }
    }

    /// Makes the height buffer hold `bytes` of contacts' fields after the lanes' heights (a
    /// scene may have many contacts), refusing more than the device binds. A new buffer is
    /// zero, the maps keep what they held: each lane's next frame clears and refreshes the
    /// texels its last one left, as ever.
    pub fn reserve_fields(&mut self, ctx: &GpuContext, bytes: u64) -> Result<()> {
        let h = &mut self.heightfield;
        let total = h.lane_bytes(Map::Height) * h.lanes as u64 + bytes;
        let allowed = ctx.device.limits().max_storage_buffer_binding_size;
        if total > allowed {
            return Err(GeltipError::input(
                "batch",
                format!(
                    "its contacts' penetration fields need {total} byte GPU buffers; this device allows {allowed}"
                ),
            ));
        }
        if h.buffer(Map::Height).size() < total {
            let none = wgpu::BufferUsages::empty();
            h.buffers[Map::Height as usize] = storage(ctx, "geltip height", total, none);
        }
        Ok(())
    }

    /// Uploads a mesh's baked SDF grid, once per mesh (nothing for a built-in solid).
    pub fn upload_grid(&mut self, ctx: &GpuContext, object: &Arc<Object>) {
        if let Object::Mesh { grid, .. } = object.as_ref() {
            let key = Arc::as_ptr(object) as usize;
            if !self.grids.contains_key(&key) {
                // A bound on the cache: a long run may load many meshes.
                if self.grids.len() >= MAX_CACHED_GRIDS {
                    self.grids.clear();
                }
                let buffer = ctx
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

    /// The SDF grid a contact pass binds for `object`: a loaded mesh's (uploaded by
    /// [`Self::upload_grid`]), else the empty one.
    pub fn grid_of(&self, object: &Object) -> &wgpu::Buffer {
        let key = object as *const Object as usize;
        match (object, self.grids.get(&key)) {
            (Object::Mesh { .. }, Some((_, buffer))) => buffer,
            _ => &self.empty_grid,
        }
    }
}

impl Heightfield {
    /// `lanes` heightfields of `texels` per side, and `fields` bytes for the contacts' own
    /// penetration fields after them.
    fn new(ctx: &GpuContext, texels: u32, lanes: u32, fields: u64) -> Heightfield {
        let n = texels as u64 * texels as u64 * lanes as u64;
        let none = wgpu::BufferUsages::empty();
        let map = |label, format| map_texture(ctx, label, (texels, texels), Some(lanes), format);
        Heightfield {
            buffers: [
                storage(ctx, "geltip penetration", n * 4, none),
                storage(ctx, "geltip elastomer scratch", n * 16, none),
                storage(ctx, "geltip height", n * 4 + fields, none),
            ],
            maps: [
                map("geltip penetration map", wgpu::TextureFormat::R32Float),
                map("geltip elastomer map", wgpu::TextureFormat::Rgba32Float),
                map("geltip height map", wgpu::TextureFormat::R32Float),
            ],
            texels,
            lanes,
        }
    }

    /// Bytes of one lane of `map`'s buffer.
    fn lane_bytes(&self, map: Map) -> u64 {
        let n = self.texels as u64;
        n * n * self.map(map).texel_bytes as u64
    }

    /// Lanes held.
    pub fn lanes(&self) -> u32 {
        self.lanes
    }

    /// The word of the height buffer where the contacts' own penetration fields start.
    pub fn fields_at(&self) -> u64 {
        self.lane_bytes(Map::Height) / 4 * self.lanes as u64
    }

    /// Every lane, all of it.
    pub fn everything(&self) -> LaneSpan {
        LaneSpan {
            first: 0,
            last: self.lanes - 1,
            rect: self.whole(),
        }
    }

    pub fn buffer(&self, map: Map) -> &wgpu::Buffer {
        &self.buffers[map as usize]
    }

    pub fn map(&self, map: Map) -> &MapTexture {
        &self.maps[map as usize]
    }

    /// Every texel of the grid, as a rect.
    pub fn whole(&self) -> Rect {
        Rect {
            x: 0,
            y: 0,
            w: self.texels,
            h: self.texels,
        }
    }

    /// Zeroes the buffers from the first lane's row `span.rect.y` to the last lane's row
    /// before `span.rect.y + span.rect.h` (every row of the lanes between): one clear a
    /// buffer however many lanes.
    pub fn clear(&self, encoder: &mut wgpu::CommandEncoder, span: LaneSpan) {
        let n = self.texels as u64;
        let r = span.rect;
        let from = (span.first as u64 * n + r.y as u64) * n;
        let to = (span.last as u64 * n + (r.y + r.h) as u64) * n;
        for map in Map::ALL {
            let bytes = self.map(map).texel_bytes as u64;
            encoder.clear_buffer(self.buffer(map), from * bytes, Some((to - from) * bytes));
        }
    }

    /// Copies `span.rect` of the buffer behind `map` into the map, on each of its lanes: one
    /// copy however many lanes.
    pub fn refresh(&self, encoder: &mut wgpu::CommandEncoder, map: Map, span: LaneSpan) {
        let n = self.texels;
        let r = span.rect;
        let target = self.map(map);
        let bytes = target.texel_bytes as u64;
        let lane = self.lane_bytes(map);
        encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: self.buffer(map),
                layout: wgpu::TexelCopyBufferLayout {
                    offset: span.first as u64 * lane + (r.y as u64 * n as u64 + r.x as u64) * bytes,
                    bytes_per_row: Some(n * bytes as u32),
                    rows_per_image: Some(n),
                },
            },
            wgpu::TexelCopyTextureInfo {
                texture: &target.texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: r.x,
                    y: r.y,
                    z: span.first,
                },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::Extent3d {
                width: r.w,
                height: r.h,
                depth_or_array_layers: span.last - span.first + 1,
            },
        );
    }
}
