//! Every compute pipeline of the renderer, by stage, over its one pipeline layout and with
//! the sensor's pipeline constants (`SensorUniform::pipeline_constants`). The contact
//! stage's pipelines, one per kind of object, and the lens rays' (test support) are built
//! when first needed.

use crate::error::{GeltipError, Result};
use crate::gpu::shaders::create_compute_pipeline_with;
use crate::gpu::GpuContext;
use std::collections::HashMap;

/// A frame's start: its image buffers from the reference, its counters cleared.
pub(super) struct StartPipelines {
    pub frame_start: wgpu::ComputePipeline,
}

/// Stage 1: one pipeline per object kind (FrameUniform `object_kind`), which is a pipeline
/// constant of `shaders/contact.wgsl`.
pub(super) struct ContactPipelines(HashMap<u32, wgpu::ComputePipeline>);

/// Stage 2: the blends along meridians and along parallels, then the skin's normals.
pub(super) struct ElastomerPipelines {
    pub meridians: wgpu::ComputePipeline,
    pub parallels: wgpu::ComputePipeline,
    pub skin_normals: wgpu::ComputePipeline,
}

/// Which pixels a contact touches: the tiles' texel ranges (once, after the reference
/// frame), the tile list, and the touched list from the listed tiles.
pub(super) struct TouchedPipelines {
    pub probe_tiles: wgpu::ComputePipeline,
    pub select_tiles: wgpu::ComputePipeline,
    pub select_listed: wgpu::ComputePipeline,
    pub tile_bases: wgpu::ComputePipeline,
    pub touched_bases: wgpu::ComputePipeline,
}

/// Stage 3: every pixel of the reference frame; a contact frame's shallow and deep pixels.
pub(super) struct CameraPipelines {
    pub reference: wgpu::ComputePipeline,
    pub shallow: wgpu::ComputePipeline,
    pub deep: wgpu::ComputePipeline,
}

/// Stage 4: the sensor's noise over a finished frame.
pub(super) struct LedsPipelines {
    pub add_noise: wgpu::ComputePipeline,
}

pub(super) struct Pipelines {
    pub start: StartPipelines,
    pub contact: ContactPipelines,
    pub elastomer: ElastomerPipelines,
    pub touched: TouchedPipelines,
    pub camera: CameraPipelines,
    pub leds: LedsPipelines,
    /// `shaders/lens_rays.wgsl`, for [`super::Renderer::unproject_pixels`] alone.
    lens_rays: Option<wgpu::ComputePipeline>,
    /// What the lazily built pipelines are built with.
    layout: wgpu::PipelineLayout,
    constants: [(&'static str, f64); 15],
}

impl Pipelines {
    pub fn new(
        ctx: &GpuContext,
        layout: &wgpu::PipelineLayout,
        constants: [(&'static str, f64); 15],
    ) -> Result<Pipelines> {
        let p = |stage: &str, entry: &str| {
            create_compute_pipeline_with(ctx, stage, entry, Some(layout), &constants)
        };
        Ok(Pipelines {
            start: StartPipelines {
                frame_start: p("start", "frame_start")?,
            },
            contact: ContactPipelines(HashMap::new()),
            elastomer: ElastomerPipelines {
                meridians: p("elastomer", "blend_meridian")?,
                parallels: p("elastomer", "blend_azimuth")?,
                skin_normals: p("elastomer", "skin_normals")?,
            },
            touched: TouchedPipelines {
                probe_tiles: p("touched", "probe_tiles_of_rays")?,
                select_tiles: p("touched", "select_tiles")?,
                select_listed: p("touched", "select_listed")?,
                tile_bases: p("touched", "tile_bases")?,
                touched_bases: p("touched", "touched_bases")?,
            },
            camera: CameraPipelines {
                reference: p("camera", "camera")?,
                shallow: p("camera", "camera_shallow")?,
                deep: p("camera", "camera_deep")?,
            },
            leds: LedsPipelines {
                add_noise: p("leds", "add_noise")?,
            },
            lens_rays: None,
            layout: layout.clone(),
            constants,
        })
    }

    /// Builds the contact pipeline of object kind `kind` unless built: 25-130 ms on
    /// lavapipe, with and without Mesa's shader cache.
    pub fn ready_contact(&mut self, ctx: &GpuContext, kind: u32) -> Result<()> {
        if !self.contact.0.contains_key(&kind) {
            let mut constants = self.constants.to_vec();
            constants.push(("OBJECT_KIND", kind as f64));
            let pipeline = create_compute_pipeline_with(
                ctx,
                "contact",
                "contact",
                Some(&self.layout),
                &constants,
            )?;
            self.contact.0.insert(kind, pipeline);
        }
        Ok(())
    }

    /// The lens rays' pipeline, built at its first use.
    pub fn lens_rays(&mut self, ctx: &GpuContext) -> Result<&wgpu::ComputePipeline> {
        let pipeline = match self.lens_rays.take() {
            Some(built) => built,
            None => create_compute_pipeline_with(
                ctx,
                "lens_rays",
                "unproject_pixels",
                Some(&self.layout),
                &self.constants,
            )?,
        };
        Ok(self.lens_rays.insert(pipeline))
    }
}

impl ContactPipelines {
    /// The pipeline for object kind `kind` (built by [`Pipelines::ready_contact`]).
    pub fn of(&self, kind: u32) -> Result<&wgpu::ComputePipeline> {
        self.0
            .get(&kind)
            .ok_or_else(|| GeltipError::Gpu(format!("no contact pipeline for object kind {kind}")))
    }
}
