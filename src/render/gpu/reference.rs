//! The empty finger: every pixel ray-cast once per renderer, which also leaves each ray's
//! probes and each tile's texel ranges for the contact frames after it.

use super::bindings::{FrameBinding, WaveRange};
use super::record::Recorder;
use super::resources::{extent, whole_image, Map};
use super::{Renderer, Timings};
use crate::error::Result;
use crate::render::uniforms::{image_pitch, FrameUniform};
use std::time::{Duration, Instant};

impl Renderer {
    /// Renders the empty finger again, every pixel (the renderer does this once at start-up;
    /// public for benchmarks).
    pub fn render_reference(&mut self) -> Result<()> {
        let rendered = self.record_reference();
        self.forget_heightfield_on_error(rendered)?;
        // Every lane was cleared.
        self.dirty.iter_mut().for_each(|d| *d = None);
        let start = Instant::now();
        let rgba = self.read_whole_image()?;
        let (w, h) = (self.sensor.width, self.sensor.height);
        let render = self.timings.render;
        self.reference.rgba = match &mut self.softness {
            Some((softness, raw)) => {
                let soft = softness.soften(&rgba);
                *raw = rgba;
                soft
            }
            None => rgba,
        };
        self.reference.indentation = vec![0.0; (w * h) as usize];
        self.timings = Timings {
            prepare: Duration::ZERO,
            render,
            readback: start.elapsed(),
            record: Duration::ZERO,
            touched_pixels: (w * h) as u64,
            ..Timings::default()
        };
        Ok(())
    }

    /// Records and runs the reference frame: the heightfield and its maps zeroed, every
    /// pixel cast and shaded, the rays' probes kept, and the image kept as the reference
    /// texture (its time in the timings' `render`).
    fn record_reference(&mut self) -> Result<()> {
        let start = Instant::now();
        let uniform = self.uniform_buffer(&FrameUniform::reference(&self.sensor, 0));
        let (res, p) = (&self.resources, &self.pipelines);
        let binding = FrameBinding {
            uniform: &uniform,
            uniform_offset: 0,
            wave: WaveRange {
                first_slot: 0,
                slots: 1,
                image_offset: 0,
                image_bytes: res.slot_bytes,
            },
            grid: &res.empty_grid,
        };
        let bind = res.bind_group(&self.ctx.device, binding);
        let whole = whole_image(&self.sensor);
        let mut rec = Recorder::new(self.ctx, &res.dispatch_args);
        let everything = res.heightfield.everything();
        res.heightfield.clear(rec.encoder(), everything);
        for map in Map::ALL {
            res.heightfield.refresh(rec.encoder(), map, everything);
        }
        p.camera.record_reference(&mut rec, &bind, whole);
        p.touched
            .record_probe_tiles(&mut rec, res, &bind, (whole.w, whole.h));
        rec.encoder().copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: &res.image,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(image_pitch(whole.w) * 4),
                    rows_per_image: None,
                },
            },
            res.reference_texture.as_image_copy(),
            extent(whole),
        );
        self.ctx
            .submit_and_wait("rendering the reference frame", rec.finish())?;
        self.timings.render = start.elapsed();
        Ok(())
    }
}
