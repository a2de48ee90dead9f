//! Where a frame's time goes: one contact's frame recorded by the frame path itself, each
//! stage timed (for the render benchmark's breakdown).

use super::prepare::Prepared;
use super::record::Recorder;
use super::Renderer;
use crate::error::{GeltipError, Result};
use crate::render::{Press, Rect};
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
        self.profile_wave(std::slice::from_ref(press))
    }

    /// The same for a wave of frames, a press each, recorded side by side as a submission's
    /// wave records them (at most [`Renderer::lanes`] presses): each stage's time is the
    /// wave's.
    pub fn profile_wave(&mut self, presses: &[Press]) -> Result<Vec<(&'static str, Duration)>> {
        if presses.is_empty() || presses.len() > self.lanes {
            return Err(GeltipError::input(
                "profile",
                format!(
                    "a wave holds 1 to {} frames (the lanes), got {}",
                    self.lanes,
                    presses.len()
                ),
            ));
        }
        let scenes = self.preparer().prepare(presses)?.0;
        for p in scenes.iter().flatten() {
            self.ready_object(p.uniform.object_kind, &p.press.object)?;
        }
        let profiled = self.profile_frames(&scenes);
        self.forget_heightfield_on_error(profiled)
    }

    fn profile_frames(
        &mut self,
        scenes: &[Vec<Prepared>],
    ) -> Result<Vec<(&'static str, Duration)>> {
        let contacts: Vec<&Prepared> = scenes.iter().flatten().collect();
        let offsets = self.field_offsets(&contacts)?;
        let plans = self.plan_frames(scenes.iter().map(|c| (&c[..], 0)));
        let rects: Vec<Option<Rect>> = plans.iter().map(|p| p.holding).collect();
        let scene_contacts: Vec<&[Prepared]> = scenes.iter().map(|c| &c[..]).collect();
        let (groups, waves) = self.waves(&plans, &scene_contacts, &offsets);
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
        self.read_frames("profile readback", encoder, &rects, &[])?;
        out.push(("readback", start.elapsed()));
        Ok(out)
    }
}
