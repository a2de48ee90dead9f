//! The lens rays on the GPU, for tests: the undeformed surface point each pixel sees.

use super::bindings::{FrameBinding, WaveRange};
use super::layout::{groups, LIST_WORKGROUP};
use super::record::{Groups, Recorder};
use super::resources::Map;
use super::Renderer;
use crate::error::{GeltipError, Result};
use crate::gpu::readback::read_buffer;
use crate::render::uniforms::FrameUniform;

impl Renderer {
    /// The undeformed surface points the GPU's lens rays meet for `pixels` (None beyond the
    /// lens): the GPU half of the CPU/GPU projection comparison (`shaders/lens_rays.wgsl`).
    /// The pixels go through the elastomer's scratch buffer, so the next frame clears all
    /// of the heightfield.
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
        let scratch = self.resources.heightfield.buffer(Map::Elastomer);
        self.ctx
            .queue
            .write_buffer(scratch, 0, bytemuck::cast_slice(&input));
        let mut uniform = FrameUniform::reference(&self.sensor, 0);
        uniform.pixel_rect = [0, 0, pixels.len() as u32, 1];
        let uniform = self.uniform_buffer(&uniform);
        let res = &self.resources;
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
        let pipeline = self.pipelines.lens_rays(self.ctx)?;
        let res = &self.resources;
        let mut rec = Recorder::new(self.ctx, &res.dispatch_args);
        let g = Groups::Direct(groups(pixels.len() as u32, LIST_WORKGROUP), 1, 1);
        rec.dispatch(pipeline, &bind, g);
        self.ctx
            .submit_and_wait("unprojecting pixels", rec.finish())?;
        let scratch = res.heightfield.buffer(Map::Elastomer);
        let out: Vec<[f32; 4]> = read_buffer(self.ctx, scratch, 0, pixels.len())?;
        self.dirty[0] = Some(res.heightfield.whole());
        Ok(out
            .into_iter()
            .map(|v| (v[3] != 0.0).then(|| glam::DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)))
            .collect())
    }
}
