//! Reading frames back: the copies ride in the submission of the work they read, so a
//! submission costs one round trip, and each frame's image and indentation are read over
//! the rect its buffers hold (the reference's pixels and zero indentation elsewhere). The
//! frames' rects, a wave's counters and the contacts' fields each lie packed, so the copies
//! are a few a submission, not a few a frame.

use super::bindings::packed_offsets;
use super::layout::COUNTER_HEADER_BYTES;
use super::resources::{held_bytes, Map};
use super::Renderer;
use crate::error::{GeltipError, Result};
use crate::gpu::readback::{map_ranges, read_buffer, record_ranges, staging_bytes, unpadded_rows};
use crate::render::uniforms::image_pitch;
use crate::render::Rect;
use rayon::prelude::*;
use std::time::Instant;

/// A frame's data as read back.
pub(super) struct FrameParts {
    pub rgba: Vec<u8>,
    pub indentation: Vec<f32>,
    /// The counters before the touched list (`super::layout`).
    pub counters: Vec<u32>,
}

/// What [`Renderer::read_frames`] gives: each frame's parts, each contact's penetration
/// field, and when the submission's work was done and mapped (render time ends there).
pub(super) struct ReadFrames {
    pub frames: Vec<FrameParts>,
    pub fields: Vec<Vec<f32>>,
    pub mapped: Instant,
    /// When the work was submitted.
    pub submitted: Instant,
    /// The copies that read the frames back.
    pub copies: u64,
}

impl Renderer {
    /// Submits `encoder` (the work that renders frames `0..rects.len()` of a submission)
    /// with the copies that read them back appended, waits once and unpacks: per frame, its
    /// image and indentation (read over its rect, which its buffers hold) and its counters;
    /// then the contacts' penetration fields over `fields` (byte ranges among the contacts'
    /// fields, packed in order after the lanes' heights; an empty field for `None`).
    pub(super) fn read_frames(
        &mut self,
        what: &str,
        mut encoder: wgpu::CommandEncoder,
        rects: &[Option<Rect>],
        fields: &[Option<(u64, u64)>],
    ) -> Result<ReadFrames> {
        let (width, height) = (self.sensor.width, self.sensor.height);
        if let Some(r) = rects
            .iter()
            .flatten()
            .find(|r| r.x + r.w > width || r.y + r.h > height)
        {
            return Err(GeltipError::Gpu(format!(
                "a frame's rect {r:?} reaches beyond the {width}x{height} image"
            )));
        }
        // The kept staging buffer grows to the largest submission read.
        let total = staging_bytes(&self.frame_ranges(rects, fields))?;
        self.resources.reserve_staging(self.ctx, total);
        let ranges = self.frame_ranges(rects, fields);
        let copies = ranges.iter().filter(|r| r.2 > 0).count() as u64;
        let staging = &self.resources.staging;
        record_ranges(&mut encoder, staging, &ranges)?;
        let submission = self.ctx.submit(what, encoder)?;
        let submitted = Instant::now();
        // Each frame as the reference's pixels and zero indentation, laid out while the GPU
        // works: this thread would only wait, and after the wait only the rects read are
        // left to copy over them.
        let pixels = width as usize * height as usize;
        let raw_reference = match &self.softness {
            Some((_, raw)) => raw,
            None => &self.reference.rgba,
        };
        let mut frames: Vec<FrameParts> = rects
            .par_iter()
            .map(|_| FrameParts {
                rgba: raw_reference.clone(),
                indentation: vec![0.0; pixels],
                counters: Vec::new(),
            })
            .collect();
        let (offsets, _) = packed_offsets(rects);
        let (mapped, read_fields) = map_ranges(self.ctx, staging, &ranges, submission, |all| {
            let mapped = Instant::now();
            let waves = rects.len().div_ceil(self.lanes);
            let (images, indentations, all_fields) = (all[0], all[1], all[2 + waves]);
            let counters: Vec<&[u8]> = all[2..2 + waves]
                .iter()
                .flat_map(|w| w.chunks(COUNTER_HEADER_BYTES as usize))
                .collect();
            frames
                .par_iter_mut()
                .zip(counters)
                .zip(rects.par_iter().zip(&offsets))
                .for_each(|((frame, counters), (rect, &at))| {
                    if let Some(r) = *rect {
                        let held = at as usize..(at + held_bytes(r)) as usize;
                        let rgba = bytemuck::cast_slice_mut::<u8, [u8; 4]>(&mut frame.rgba);
                        paste_rows(rgba, width, r, &images[held.clone()], |b| b);
                        paste_rows(
                            &mut frame.indentation,
                            width,
                            r,
                            &indentations[held],
                            f32::from_ne_bytes,
                        );
                    }
                    frame.counters = bytemuck::pod_collect_to_vec(counters);
                });
            let fields: Vec<Vec<f32>> = fields
                .par_iter()
                .map(|f| {
                    let (at, bytes) = f.unwrap_or((0, 0));
                    bytemuck::pod_collect_to_vec(&all_fields[at as usize..(at + bytes) as usize])
                })
                .collect();
            (mapped, fields)
        })?;
        // The camera's softness, where each frame's contacts changed it.
        if let Some((softness, _)) = &self.softness {
            let soft_reference = &self.reference.rgba;
            frames.par_iter_mut().zip(rects).for_each(|(frame, rect)| {
                let mut out = soft_reference.clone();
                if let Some(r) = *rect {
                    softness.soften_changed(&frame.rgba, &mut out, r);
                }
                frame.rgba = out;
            });
        }
        Ok(ReadFrames {
            frames,
            fields: read_fields,
            mapped,
            submitted,
            copies,
        })
    }

    /// What [`Self::read_frames`] reads: the frames' images and indentations (their rects,
    /// packed in order: [`packed_offsets`]), a copy each; each frame's counters; and the
    /// contacts' fields, packed in order in the height buffer, in one copy.
    fn frame_ranges(
        &self,
        rects: &[Option<Rect>],
        fields: &[Option<(u64, u64)>],
    ) -> Vec<(&wgpu::Buffer, u64, u64)> {
        let res = &self.resources;
        let (_, held) = packed_offsets(rects);
        let mut ranges = Vec::with_capacity(3 + rects.len());
        ranges.push((&res.image, 0, held));
        ranges.push((&res.indentation, 0, held));
        // A wave's frames' counters lie side by side from its first slot's place.
        for first in (0..rects.len()).step_by(self.lanes) {
            let frames = (rects.len() - first).min(self.lanes) as u64;
            let at = first as u64 * res.counter_bytes;
            ranges.push((&res.counters, at, frames * COUNTER_HEADER_BYTES));
        }
        let height = res.heightfield.buffer(Map::Height);
        let fields_at = res.heightfield.fields_at() * 4;
        let end = fields.iter().flatten().map(|&(at, bytes)| at + bytes).max();
        ranges.push((height, fields_at, end.unwrap_or(0)));
        ranges
    }

    /// The image in the first frame's slice of the image buffer, all of it (rows
    /// [`image_pitch`] apart there).
    pub(super) fn read_whole_image(&self) -> Result<Vec<u8>> {
        let (w, h) = (self.sensor.width as usize, self.sensor.height as usize);
        let pitch = image_pitch(self.sensor.width) as usize * 4;
        let padded: Vec<u8> = read_buffer(self.ctx, &self.resources.image, 0, h * pitch)?;
        Ok(unpadded_rows(&padded, w * 4, pitch)
            .flatten()
            .copied()
            .collect())
    }
}

/// Each row of rect `r` as read back (`bytes`: its rows [`image_pitch`] pixels apart) into
/// its place in `image`, a whole image `width` pixels wide, a pixel from each 4 bytes.
fn paste_rows<T>(image: &mut [T], width: u32, r: Rect, bytes: &[u8], pixel: impl Fn([u8; 4]) -> T) {
    let pitch = image_pitch(r.w) as usize * 4;
    for (j, row) in (r.y as usize..).zip(unpadded_rows(bytes, r.w as usize * 4, pitch)) {
        let at = j * width as usize + r.x as usize;
        let to = image.get_mut(at..).unwrap_or_default();
        for (p, b) in to.iter_mut().zip(row.chunks_exact(4)) {
            *p = pixel([b[0], b[1], b[2], b[3]]);
        }
    }
}
