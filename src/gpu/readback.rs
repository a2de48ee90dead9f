//! Copying textures and buffers back to the CPU.
//!
//! Texture-to-buffer copies need `bytes_per_row` padded to
//! [`wgpu::COPY_BYTES_PER_ROW_ALIGNMENT`] (256 bytes); the helpers here pad on the GPU side
//! and return tightly packed rows. One-off reads: [`read_texture`], [`read_texture_region`],
//! [`read_buffer`] (buffer ranges live in `readback/buffers.rs`). Batched rendering: a
//! [`Readback`] owns its staging buffer, so the copy can be recorded with the render work
//! and the map timed on its own.

use std::sync::mpsc;

use super::context::GpuContext;
use super::one_line;
use crate::error::{GeltipError, Result};

mod buffers;
pub use buffers::{
    map_ranges, read_buffer, read_ranges, read_ranges_with, record_ranges, staging_bytes,
    staging_or_fresh, unpack_ranges,
};

/// Bytes per row of a `width`-pixel row, padded to [`wgpu::COPY_BYTES_PER_ROW_ALIGNMENT`].
///
/// ```
/// assert_eq!(geltip::gpu::padded_bytes_per_row(317, 4), 1280);
/// assert_eq!(geltip::gpu::padded_bytes_per_row(64, 4), 256);
/// ```
pub fn padded_bytes_per_row(width: u32, bytes_per_pixel: u32) -> u32 {
    let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    (width * bytes_per_pixel).div_ceil(align) * align
}

/// The rows of a copy whose rows lie `pitch` bytes apart (padded, e.g. to
/// [`wgpu::COPY_BYTES_PER_ROW_ALIGNMENT`]), each without its padding: its first
/// `row_bytes`. The one place padding is stripped from what is read back.
///
/// ```
/// let padded = [1u8, 2, 0, 0, 3, 4, 0, 0];
/// let rows: Vec<&[u8]> = geltip::gpu::readback::unpadded_rows(&padded, 2, 4).collect();
/// assert_eq!(rows, [&[1u8, 2][..], &[3, 4][..]]);
/// ```
pub fn unpadded_rows(padded: &[u8], row_bytes: usize, pitch: usize) -> impl Iterator<Item = &[u8]> {
    padded
        .chunks_exact(pitch.max(1))
        .map(move |row| &row[..row_bytes.min(row.len())])
}

/// Bytes per texel of `format` for copies, or an error for formats a plain copy cannot read
/// (block-compressed, combined depth-stencil, multi-planar).
pub fn bytes_per_pixel(format: wgpu::TextureFormat) -> Result<u32> {
    let unsupported = || {
        GeltipError::input(
            "texture readback",
            format!("format {format:?} cannot be read back as plain texels"),
        )
    };
    if format.block_dimensions() != (1, 1) {
        return Err(unsupported());
    }
    format
        .block_copy_size(Some(wgpu::TextureAspect::All))
        .ok_or_else(unsupported)
}

/// Reads mip level 0 of the whole `texture` (all array layers) as tightly packed bytes:
/// row after row, layer after layer, `width * bytes_per_pixel` bytes a row.
///
/// The texture needs `TextureUsages::COPY_SRC`.
pub fn read_texture(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<u8>> {
    read_texture_region(ctx, texture, wgpu::Origin3d::ZERO, texture.size())
}

/// Reads the `size` texels at `origin` of mip level 0 of `texture`, tightly packed.
pub fn read_texture_region(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    origin: wgpu::Origin3d,
    size: wgpu::Extent3d,
) -> Result<Vec<u8>> {
    let layout = CopyLayout::new(texture.format(), size)?;
    check_texture_copy(texture, origin, size)?;
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("geltip readback staging"),
        size: layout.buffer_size(),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("geltip read_texture"),
        });
    layout.encode(&mut encoder, texture, origin, &staging);
    let submission = ctx.submit("texture readback copy", encoder)?;
    let mut out = Vec::new();
    map_and_unpack(ctx, &staging, &layout, submission, &mut out)?;
    Ok(out)
}

/// A reusable staging buffer for reading back `width x height` textures of one format,
/// for batched rendering: record [`Readback::enqueue_copy`] with the frame's work, submit,
/// then [`Readback::finish`].
#[derive(Debug)]
pub struct Readback {
    staging: wgpu::Buffer,
    layout: CopyLayout,
}

impl Readback {
    /// A staging buffer for `width x height` textures of `format` (e.g. `Rgba8Unorm`, `R32Float`).
    pub fn new(
        ctx: &GpuContext,
        width: u32,
        height: u32,
        format: wgpu::TextureFormat,
    ) -> Result<Readback> {
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let layout = CopyLayout::new(format, size)?;
        let staging = ctx.scoped("creating the readback staging buffer", || {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("geltip Readback staging"),
                size: layout.buffer_size(),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        })?;
        Ok(Readback { staging, layout })
    }

    /// Width and height of the images this reads back.
    pub fn size(&self) -> (u32, u32) {
        (self.layout.size.width, self.layout.size.height)
    }

    /// Bytes of one tightly packed image (what [`Readback::finish`] returns).
    pub fn packed_len(&self) -> usize {
        self.layout.packed_len()
    }

    /// Records the copy of mip level 0, layer 0 of `texture` into the staging buffer.
    ///
    /// Errors if `texture`'s size or texel size differs from this readback's, or it lacks
    /// `COPY_SRC`.
    pub fn enqueue_copy(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
    ) -> Result<()> {
        let bpp = bytes_per_pixel(texture.format())?;
        if bpp != self.layout.bytes_per_pixel {
            return Err(GeltipError::input(
                "readback",
                format!(
                    "texture format {:?} has {bpp} bytes per texel, the readback {}",
                    texture.format(),
                    self.layout.bytes_per_pixel
                ),
            ));
        }
        check_texture_copy(texture, wgpu::Origin3d::ZERO, self.layout.size)?;
        self.layout
            .encode(encoder, texture, wgpu::Origin3d::ZERO, &self.staging);
        Ok(())
    }

    /// Waits for `submission` (which must contain the copy), maps the staging buffer and
    /// returns the image, tightly packed.
    pub fn finish(&self, ctx: &GpuContext, submission: wgpu::SubmissionIndex) -> Result<Vec<u8>> {
        let mut out = Vec::with_capacity(self.packed_len());
        self.finish_into(ctx, submission, &mut out)?;
        Ok(out)
    }

    /// [`Readback::finish`] into `out` (cleared first), to reuse its allocation.
    pub fn finish_into(
        &self,
        ctx: &GpuContext,
        submission: wgpu::SubmissionIndex,
        out: &mut Vec<u8>,
    ) -> Result<()> {
        map_and_unpack(ctx, &self.staging, &self.layout, submission, out)
    }

    /// Copies `texture` in an encoder of its own, submits and returns the image.
    pub fn read(&self, ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<u8>> {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("geltip Readback::read"),
            });
        self.enqueue_copy(&mut encoder, texture)?;
        let submission = ctx.submit("texture readback copy", encoder)?;
        self.finish(ctx, submission)
    }
}

/// Sizes of a texture-to-buffer copy with padded rows.
#[derive(Debug, Clone, Copy)]
struct CopyLayout {
    size: wgpu::Extent3d,
    bytes_per_pixel: u32,
    padded_row: u32,
}

impl CopyLayout {
    fn new(format: wgpu::TextureFormat, size: wgpu::Extent3d) -> Result<CopyLayout> {
        let bytes_per_pixel = bytes_per_pixel(format)?;
        if size.width == 0 || size.height == 0 || size.depth_or_array_layers == 0 {
            return Err(GeltipError::input(
                "texture readback",
                format!(
                    "empty region {}x{}x{}",
                    size.width, size.height, size.depth_or_array_layers
                ),
            ));
        }
        let row = u64::from(size.width) * u64::from(bytes_per_pixel);
        if row > u64::from(u32::MAX / 2) {
            return Err(GeltipError::input(
                "texture readback",
                format!("rows of {row} bytes are too long"),
            ));
        }
        Ok(CopyLayout {
            size,
            bytes_per_pixel,
            padded_row: padded_bytes_per_row(size.width, bytes_per_pixel),
        })
    }

    fn row_bytes(&self) -> usize {
        (self.size.width * self.bytes_per_pixel) as usize
    }

    fn rows(&self) -> usize {
        self.size.height as usize * self.size.depth_or_array_layers as usize
    }

    fn packed_len(&self) -> usize {
        self.row_bytes() * self.rows()
    }

    fn buffer_size(&self) -> u64 {
        u64::from(self.padded_row) * self.rows() as u64
    }

    fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
        origin: wgpu::Origin3d,
        staging: &wgpu::Buffer,
    ) {
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: Some(self.size.height),
                },
            },
            self.size,
        );
    }
}

/// Checks what wgpu would otherwise report as a validation error.
fn check_texture_copy(
    texture: &wgpu::Texture,
    origin: wgpu::Origin3d,
    size: wgpu::Extent3d,
) -> Result<()> {
    if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
        return Err(GeltipError::input(
            "texture readback",
            format!("the texture's usage {:?} lacks COPY_SRC", texture.usage()),
        ));
    }
    let full = texture.size();
    let fits = |o: u32, s: u32, f: u32| o.checked_add(s).is_some_and(|end| end <= f);
    if !fits(origin.x, size.width, full.width)
        || !fits(origin.y, size.height, full.height)
        || !fits(
            origin.z,
            size.depth_or_array_layers,
            full.depth_or_array_layers,
        )
    {
        return Err(GeltipError::input(
            "texture readback",
            format!(
                "region {}x{}x{} at ({}, {}, {}) exceeds the {}x{}x{} texture",
                size.width,
                size.height,
                size.depth_or_array_layers,
                origin.x,
                origin.y,
                origin.z,
                full.width,
                full.height,
                full.depth_or_array_layers
            ),
        ));
    }
    Ok(())
}

/// Maps `staging` once `submission` is done and appends its rows, padding stripped, to `out`.
fn map_and_unpack(
    ctx: &GpuContext,
    staging: &wgpu::Buffer,
    layout: &CopyLayout,
    submission: wgpu::SubmissionIndex,
    out: &mut Vec<u8>,
) -> Result<()> {
    let what = "texture readback";
    let size = layout.buffer_size();
    map_read(ctx, staging, size, submission, what)?;
    let result = staging
        .get_mapped_range(..size)
        .map(|view| {
            out.clear();
            out.reserve(layout.packed_len());
            for row in unpadded_rows(&view, layout.row_bytes(), layout.padded_row as usize) {
                out.extend_from_slice(row);
            }
        })
        .map_err(|e| GeltipError::Gpu(format!("{what}: {}", one_line(&e.to_string()))));
    staging.unmap();
    result
}

/// Maps `buffer[..size]` for reading after `submission` and waits for the map, with the
/// context's timeout. On error the buffer is left unmapped.
fn map_read(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    size: u64,
    submission: wgpu::SubmissionIndex,
    what: &str,
) -> Result<()> {
    let (tx, rx) = mpsc::channel();
    ctx.scoped(what, || {
        buffer.map_async(wgpu::MapMode::Read, ..size, move |result| {
            // The receiver may be gone after a timeout; nothing to report then.
            let _ = tx.send(result);
        })
    })
    .inspect_err(|_| buffer.unmap())?;
    if let Err(e) = ctx.wait(submission, what) {
        buffer.unmap();
        return Err(e);
    }
    // The wait usually returns after our callback has run, but when several threads share
    // the device, another thread's poll may have taken the callback and not yet called it:
    // keep polling, briefly, until it arrives (bounded by the GPU timeout all the same).
    let start = std::time::Instant::now();
    let result = loop {
        match rx.recv_timeout(std::time::Duration::from_millis(1)) {
            Ok(r) => break r,
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                buffer.unmap();
                return Err(GeltipError::Gpu(format!(
                    "{what}: the buffer map was dropped without an answer"
                )));
            }
            Err(mpsc::RecvTimeoutError::Timeout) if start.elapsed() > ctx.timeout() => {
                buffer.unmap();
                return Err(GeltipError::Gpu(format!(
                    "{what}: the buffer map did not complete within {:.0} s of the submission \
                     finishing",
                    ctx.timeout().as_secs_f64()
                )));
            }
            Err(mpsc::RecvTimeoutError::Timeout) => ctx.poll_now()?,
        }
    };
    result.map_err(|e| {
        buffer.unmap();
        GeltipError::Gpu(format!("{what}: mapping the staging buffer failed: {e}"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_padded_to_256_bytes() {
        assert_eq!(padded_bytes_per_row(1, 4), 256);
        assert_eq!(padded_bytes_per_row(64, 4), 256);
        assert_eq!(padded_bytes_per_row(65, 4), 512);
        assert_eq!(padded_bytes_per_row(317, 4), 1280);
        assert_eq!(padded_bytes_per_row(317, 1), 512);
    }

    #[test]
    fn texel_sizes() {
        assert_eq!(bytes_per_pixel(wgpu::TextureFormat::Rgba8Unorm).unwrap(), 4);
        assert_eq!(bytes_per_pixel(wgpu::TextureFormat::R32Float).unwrap(), 4);
        assert_eq!(
            bytes_per_pixel(wgpu::TextureFormat::Rgba32Float).unwrap(),
            16
        );
        assert!(bytes_per_pixel(wgpu::TextureFormat::Bc1RgbaUnorm).is_err());
        assert!(bytes_per_pixel(wgpu::TextureFormat::Depth24PlusStencil8).is_err());
    }
}
