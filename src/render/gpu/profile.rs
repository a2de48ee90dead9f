//! Where a frame's time goes: one contact's frame recorded by the frame path itself, each
//! stage timed (for the render benchmark's breakdown).

use super::prepare::Prepared;
use super::record::Recorder;
use super::Renderer;
use crate::error::Result;
use crate::render::Press;
use std::time::{Duration, Instant};

impl Renderer {
    /// Renders one press and returns each stage's time, then the readback's (slower than
    /// [`Renderer::render`]). Where the device writes timestamps between commands (lavapipe
    /// does), the frame is recorded and submitted once, as [`Renderer::render`] does, with a
    /// timestamp after each stage: a stage's time is then its own work, not a submission's
    /// and a wait's (the skin normals end their pass, which a frame shares with the tile
    /// list). Elsewhere each stage is submitted and waited for on its own, and its wall time
    /// includes both. The readback is timed on the CPU either way.
    pub fn profile_stages(&mut self, press: &Press) -> Result<Vec<(&'static str, Duration)>> {
        let prepared: Vec<Prepared> = self
            .preparer()
            .prepare(std::slice::from_ref(press))?
            .0
            .into_iter()
            .flatten()
            .collect();
        for p in &prepared {
            self.ready_object(p.uniform.object_kind, &p.press.object)?;
        }
        let profiled = self.profile_frame(&prepared);
        self.forget_heightfield_on_error(profiled)
    }

    fn profile_frame(&mut self, contacts: &[Prepared]) -> Result<Vec<(&'static str, Duration)>> {
        let offsets = self.field_offsets(&contacts.iter().collect::<Vec<_>>())?;
        let plan = self.plan(0, contacts, 0);
        let plans = std::slice::from_ref(&plan);
        let (groups, waves) = self.waves(plans, &[contacts], &offsets);
        let mut rec = Recorder::profiling(self.ctx, &self.resources.dispatch_args);
        if let Some(wave) = waves.first() {
            self.record_wave(&mut rec, wave, &groups)?;
        }
        let mut out: Vec<(&'static str, Duration)> = rec
            .finish_profile()?
            .into_iter()
            .map(|(stage, time)| (stage.name(), time))
            .collect();
        let start = Instant::now();
        let encoder = self.ctx.device.create_command_encoder(&Default::default());
        self.read_frames("profile readback", encoder, &[plan.holding], &[])?;
        out.push(("readback", start.elapsed()));
        if let (Some(t), Some(r)) = (plan.texels.first(), plan.pixels) {
            log::info!("texel rect {}x{}, pixel rect {}x{}", t.w, t.h, r.w, r.h);
        }
        Ok(out)
    }
}
