//! Reading byte ranges of buffers back: checked, copied into one staging buffer in one
//! submission (or recorded with the work they read) and mapped once.

use super::map_read;
use crate::error::{GeltipError, Result};
use crate::gpu::context::GpuContext;
use crate::gpu::one_line;

/// Reads `count` values of `T` starting `offset` bytes into `buffer`.
///
/// The buffer needs `BufferUsages::COPY_SRC`; `offset` must be a multiple of 4
/// ([`wgpu::COPY_BUFFER_ALIGNMENT`]). The data go through a `MAP_READ` staging buffer.
pub fn read_buffer<T: bytemuck::Pod>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    offset: u64,
    count: usize,
) -> Result<Vec<T>> {
    let elem = std::mem::size_of::<T>() as u64;
    if elem == 0 {
        return Err(GeltipError::input(
            "buffer readback",
            "cannot read zero-sized values",
        ));
    }
    let bytes = (count as u64)
        .checked_mul(elem)
        .ok_or_else(|| GeltipError::input("buffer readback", format!("{count} values overflow")))?;
    let raw = read_ranges(ctx, &[(buffer, offset, bytes)])?;
    let mut values = vec![T::zeroed(); count];
    bytemuck::cast_slice_mut::<T, u8>(&mut values).copy_from_slice(&raw[0]);
    Ok(values)
}

/// Reads byte ranges `(buffer, offset, bytes)` of one or more buffers with a single copy
/// submission and a single map, so that a batch of frames costs one round trip. Each
/// buffer needs `BufferUsages::COPY_SRC`; offsets must be multiples of 4
/// ([`wgpu::COPY_BUFFER_ALIGNMENT`]). Returns the bytes of each range, in order.
pub fn read_ranges(ctx: &GpuContext, ranges: &[(&wgpu::Buffer, u64, u64)]) -> Result<Vec<Vec<u8>>> {
    read_ranges_with(ctx, None, ranges, |_, bytes| bytes.to_vec())
}

/// [`read_ranges`] handing each range's bytes, still mapped, to `unpack(index, bytes)`, so
/// that the caller copies them once, straight into what it keeps; through `staging`
/// (`MAP_READ | COPY_DST`, unmapped) when it is big enough, else through a fresh staging
/// buffer: a caller that reads the same amount again and again keeps one and saves the
/// allocation (megabytes of fresh pages per read on a software device).
pub fn read_ranges_with<R>(
    ctx: &GpuContext,
    staging: Option<&wgpu::Buffer>,
    ranges: &[(&wgpu::Buffer, u64, u64)],
    unpack: impl FnMut(usize, &[u8]) -> R,
) -> Result<Vec<R>> {
    let total = staging_bytes(ranges)?;
    if total == 0 {
        let mut unpack = unpack;
        return Ok((0..ranges.len()).map(|k| unpack(k, &[])).collect());
    }
    let mut fresh = None;
    let staging = staging_or_fresh(ctx, staging, total, &mut fresh);
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("geltip readback"),
        });
    record_ranges(&mut encoder, staging, ranges)?;
    let submission = ctx.submit("buffer readback copy", encoder)?;
    unpack_ranges(ctx, staging, ranges, submission, unpack)
}

/// Bytes a staging buffer needs for `ranges` (each checked as [`read_ranges`] says).
pub fn staging_bytes(ranges: &[(&wgpu::Buffer, u64, u64)]) -> Result<u64> {
    let what = "buffer readback";
    let mut total = 0u64;
    for &(buffer, offset, bytes) in ranges {
        if !buffer.usage().contains(wgpu::BufferUsages::COPY_SRC) {
            return Err(GeltipError::input(
                what,
                format!("the buffer's usage {:?} lacks COPY_SRC", buffer.usage()),
            ));
        }
        if !offset.is_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT) {
            return Err(GeltipError::input(
                what,
                format!(
                    "offset {offset} is not a multiple of {}",
                    wgpu::COPY_BUFFER_ALIGNMENT
                ),
            ));
        }
        let copy_size = bytes.next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
        if offset
            .checked_add(copy_size)
            .is_none_or(|end| end > buffer.size())
        {
            return Err(GeltipError::input(
                what,
                format!(
                    "{bytes} bytes at offset {offset} run past the buffer's {} bytes",
                    buffer.size()
                ),
            ));
        }
        total += copy_size;
    }
    Ok(total)
}

/// `staging` when it can take `total` bytes, else a fresh staging buffer of that size, kept
/// in `fresh` for the caller's scope.
pub fn staging_or_fresh<'a>(
    ctx: &GpuContext,
    staging: Option<&'a wgpu::Buffer>,
    total: u64,
    fresh: &'a mut Option<wgpu::Buffer>,
) -> &'a wgpu::Buffer {
    match staging {
        Some(s) if fits(s, total) => s,
        _ => fresh.insert(ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("geltip readback staging"),
            size: total,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })),
    }
}

/// Whether `staging` can take `total` bytes as a readback staging buffer.
fn fits(staging: &wgpu::Buffer, total: u64) -> bool {
    staging.size() >= total
        && staging
            .usage()
            .contains(wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST)
}

/// Records the copies of `ranges` into `staging`, one after another, in `encoder`: the
/// readback half of a submission that also holds the work it reads, so a frame costs one
/// round trip. Then [`unpack_ranges`] after submitting. `staging` must hold
/// [`staging_bytes`] (`MAP_READ | COPY_DST`).
pub fn record_ranges(
    encoder: &mut wgpu::CommandEncoder,
    staging: &wgpu::Buffer,
    ranges: &[(&wgpu::Buffer, u64, u64)],
) -> Result<()> {
    let total = staging_bytes(ranges)?;
    if !fits(staging, total) {
        return Err(GeltipError::input(
            "buffer readback",
            format!(
                "a staging buffer of {} bytes ({:?}) cannot take {total} bytes",
                staging.size(),
                staging.usage()
            ),
        ));
    }
    let mut at = 0u64;
    for &(buffer, offset, bytes) in ranges {
        let copy_size = bytes.next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
        if copy_size > 0 {
            encoder.copy_buffer_to_buffer(buffer, offset, staging, at, Some(copy_size));
        }
        at += copy_size;
    }
    Ok(())
}

/// Waits for `submission` (which holds [`record_ranges`]'s copies), maps `staging` and hands
/// each range's bytes to `unpack(index, bytes)`.
pub fn unpack_ranges<R>(
    ctx: &GpuContext,
    staging: &wgpu::Buffer,
    ranges: &[(&wgpu::Buffer, u64, u64)],
    submission: wgpu::SubmissionIndex,
    mut unpack: impl FnMut(usize, &[u8]) -> R,
) -> Result<Vec<R>> {
    map_ranges(ctx, staging, ranges, submission, |all| {
        all.iter().enumerate().map(|(k, b)| unpack(k, b)).collect()
    })
}

/// As [`unpack_ranges`], handing every range's bytes to `unpack` at once (in order), so the
/// caller can unpack them side by side.
pub fn map_ranges<R>(
    ctx: &GpuContext,
    staging: &wgpu::Buffer,
    ranges: &[(&wgpu::Buffer, u64, u64)],
    submission: wgpu::SubmissionIndex,
    unpack: impl FnOnce(&[&[u8]]) -> R,
) -> Result<R> {
    let what = "buffer readback";
    let total = staging_bytes(ranges)?;
    if total == 0 {
        ctx.wait(submission, what)?;
        return Ok(unpack(&vec![&[][..]; ranges.len()]));
    }
    map_read(ctx, staging, total, submission, what)?;
    let result = staging
        .get_mapped_range(..total)
        .map(|view| {
            let mut at = 0usize;
            let slices: Vec<&[u8]> = ranges
                .iter()
                .map(|&(_, _, bytes)| {
                    let slice = &view[at..at + bytes as usize];
                    at += (bytes as usize).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT as usize);
                    slice
                })
                .collect();
            unpack(&slices)
        })
        .map_err(|e| GeltipError::Gpu(format!("{what}: {}", one_line(&e.to_string()))));
    staging.unmap();
    result
}
