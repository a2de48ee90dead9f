//! The one frame path: a submission of up to [`Renderer::batch_frames`] frames, each a scene
//! of one or more contacts (a batch's frame is a scene of one). Per frame, every object's
//! contact pass over its own pressed rect (each texel keeps the deepest press); the
//! elastomer's passes over the union of the footprints, split into disjoint rectangles (the
//! cost follows the footprints' area, not the number of objects); then the touched pixels of
//! the union of their pixel rects, cast, shaded and given noise. Each contact's labels come
//! from its own penetration field, read back with the frames. The frames of a wave
//! ([`Renderer::lanes`] of them) are recorded stage by stage, each on its own heightfield.

use super::bindings::FrameBinding;
use super::layout::{COUNTER_HEADER_BYTES, DEEP_COUNT, OVER_PRESSED, SHALLOW_COUNT, TILE_COUNT};
use super::prepare::{too_many, Prepared};
use super::readback::ReadFrames;
use super::record::{Recorder, Stage};
use super::resources::{held_bytes, Heightfield, Map, UNIFORM_STRIDE};
use super::stages::ContactPass;
use super::stages::{copy_dispatch_args, TILE_LIST_ARGS, TOUCHED_LIST_ARGS};
use super::{Renderer, Timings};
use crate::error::Result;
use crate::object::Object;
use crate::render::uniforms::{rect4, FrameUniform};
use crate::render::{Frame, GroundTruth, Rect};
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// A frame to render: its contacts and its noise seed.
pub(super) type Scene = (Vec<Prepared>, u32);

/// Where a frame's work lies, from its contacts' footprints.
pub(super) struct FramePlan {
    /// Its place in the submission: its slices of the image, indentation and counters.
    pub slot: u64,
    /// The heightfield texels its contacts can move (the parallels pass and the skin
    /// normals run over these), and those the meridians pass runs over: disjoint pieces.
    pub texels: Vec<Rect>,
    pub meridians: Vec<Rect>,
    /// The pixels that can see those texels: the span the tile list is chosen from.
    pub pixels: Option<Rect>,
    /// The rect of the image the frame's buffers hold ([`Renderer::changed_rect`]).
    pub holding: Option<Rect>,
    /// The texels cleared before its contact passes, whose maps each stage refreshes: its
    /// texels' span and whatever the maps still hold from the frame before, so that they
    /// are zero outside its texels afterwards.
    pub region: Option<Rect>,
    /// Its frame uniform: the first contact's, holding its image rect, its noise seed, and
    /// as its rects the spans of the pieces. A piece's pass binds it with the piece as its
    /// rect (each stage reads only the rect it runs over: `shaders/shared/common.wgsl`).
    pub uniform: FrameUniform,
}

/// A frame's bind groups, as indices into [`BindGroups::groups`].
pub(super) struct FrameBinds {
    contacts: Vec<usize>,
    frame: usize,
    texels: Vec<usize>,
    meridians: Vec<usize>,
}

/// A submission's bind groups. The frame uniforms go into one buffer, written once
/// ([`super::resources::Resources::write_uniforms`]), each group binding its own; the passes
/// of a frame whose uniforms are equal share one: a frame of one contact binds one for all
/// its passes.
#[derive(Default)]
pub(super) struct BindGroups {
    pub groups: Vec<wgpu::BindGroup>,
}

/// The bind groups of a submission, planned before any is made: per group, its frame's
/// slot, its uniform and the object whose SDF grid it binds (a contact's) or none.
#[derive(Default)]
struct BindPlan<'c> {
    groups: Vec<(u64, FrameUniform, Option<&'c Object>)>,
}

/// The smallest rect covering `rects`.
fn span(rects: &[Rect]) -> Option<Rect> {
    rects.iter().copied().reduce(|a, b| a.union(&b))
}

impl<'c> BindPlan<'c> {
    /// A contact's: its own, as it binds its object's SDF grid.
    fn contact(&mut self, slot: u64, u: FrameUniform, object: &'c Object) -> usize {
        self.groups.push((slot, u, Some(object)));
        self.groups.len() - 1
    }

    /// One for uniform `u` in frame `slot`: the frame's group of an equal uniform if it has
    /// one (whatever SDF grid it binds: only the contact passes read it).
    fn shared(&mut self, slot: u64, u: FrameUniform) -> usize {
        let same = |(s, v, _): &(u64, FrameUniform, Option<&Object>)| {
            *s == slot && bytemuck::bytes_of(v) == bytemuck::bytes_of(&u)
        };
        match self.groups.iter().position(same) {
            Some(k) => k,
            None => {
                self.groups.push((slot, u, None));
                self.groups.len() - 1
            }
        }
    }

    /// The bind groups of `plan`'s frame of `contacts`.
    fn frame(&mut self, plan: &FramePlan, contacts: &'c [Prepared]) -> FrameBinds {
        let slot = plan.slot;
        let contacts = contacts
            .iter()
            .map(|p| {
                let mut u = p.uniform.holding(plan.holding);
                u.noise_seed = plan.uniform.noise_seed;
                self.contact(slot, u, &p.press.object)
            })
            .collect();
        let frame = self.shared(slot, plan.uniform);
        let mut piece = |f: &dyn Fn(&mut FrameUniform)| {
            let mut u = plan.uniform;
            f(&mut u);
            self.shared(slot, u)
        };
        let texels = plan
            .texels
            .iter()
            .map(|&t| piece(&|u| u.texel_rect = rect4(Some(t))))
            .collect();
        let meridians = plan
            .meridians
            .iter()
            .map(|&m| piece(&|u| u.meridian_rect = rect4(Some(m))))
            .collect();
        FrameBinds {
            contacts,
            frame,
            texels,
            meridians,
        }
    }
}

/// A frame of a submission as its recording needs it.
pub(super) struct FrameWork<'a> {
    plan: &'a FramePlan,
    /// Its contacts' passes, those with a footprint.
    contacts: Vec<ContactPass<'a>>,
    /// The bind group of its whole-frame passes, and those of its texel and meridian pieces.
    frame: &'a wgpu::BindGroup,
    texels: Vec<(Rect, &'a wgpu::BindGroup)>,
    meridians: Vec<(Rect, &'a wgpu::BindGroup)>,
    /// Its lane's heightfield.
    heightfield: &'a Heightfield,
}

/// Refreshes `map` over the region of each frame of `wave` that presses the skin.
fn refresh(rec: &mut Recorder, wave: &[FrameWork], map: Map) {
    for f in wave {
        if let Some(region) = f.plan.region {
            f.heightfield.refresh(rec.encoder(), map, Some(region));
        }
    }
}

impl Renderer {
    /// Renders `scenes` in one submission, a frame each: each frame with its contacts'
    /// labels, in order. `prepare` is the CPU's time before (for [`Renderer::timings`]).
    pub(super) fn render_frames(
        &mut self,
        scenes: Vec<Scene>,
        prepare: Duration,
    ) -> Result<Vec<(Frame, Vec<GroundTruth>)>> {
        if scenes.len() > self.batch {
            return Err(too_many(scenes.len(), self.batch));
        }
        for (contacts, _) in &scenes {
            for p in contacts {
                self.ready_object(p.uniform.object_kind, &p.press.object)?;
            }
        }
        let start = Instant::now();
        let ran = self.run_frames(&scenes);
        let read = self.forget_heightfield_on_error(ran)?;
        let mut timings = Timings {
            prepare,
            render: read.mapped - start,
            record: read.submitted.saturating_duration_since(start),
            ..Timings::default()
        };
        for part in &read.frames {
            let c = &part.counters;
            timings.touched_pixels +=
                c[SHALLOW_COUNT as usize] as u64 + c[DEEP_COUNT as usize] as u64;
            timings.listed_tiles += c[TILE_COUNT as usize] as u64;
        }
        // Each frame's contacts' fields start where the frames before left off.
        let firsts = scenes.iter().scan(0, |at, (contacts, _)| {
            let first = *at;
            *at += contacts.len();
            Some(first)
        });
        let firsts: Vec<usize> = firsts.collect();
        let (sensor, grid, fields) = (&self.sensor, &self.grid, &read.fields);
        let out: Vec<(Frame, Vec<GroundTruth>)> = scenes
            .par_iter()
            .zip(read.frames)
            .zip(firsts)
            .map(|(((contacts, _), part), first)| {
                let c = &part.counters;
                let over_pressed = c[OVER_PRESSED as usize] > 0;
                let frame = Frame {
                    width: sensor.width,
                    height: sensor.height,
                    rgba: part.rgba,
                    indentation: part.indentation,
                };
                let truths = contacts
                    .iter()
                    .zip(first..)
                    .map(|(p, k)| {
                        let field = fields.get(k).map_or(&[][..], |f| &f[..]);
                        let mut truth = p.labels(sensor, grid, field);
                        // Only a contact's pixel rect is ever indented: its mask is counted there.
                        let (count, bbox) = p.pixel_rect().map_or((0, None), |r| frame.mask_in(r));
                        truth.mask_pixels = count;
                        truth.mask_bbox = bbox;
                        truth.over_pressed = over_pressed;
                        truth
                    })
                    .collect();
                (frame, truths)
            })
            .collect();
        timings.readback = read.mapped.elapsed();
        self.timings = timings;
        Ok(out)
    }

    /// Plans, records, submits and reads back the frames of `scenes`.
    fn run_frames(&mut self, scenes: &[Scene]) -> Result<ReadFrames> {
        let contacts: Vec<&Prepared> = scenes.iter().flat_map(|(c, _)| c).collect();
        let offsets = self.field_offsets(&contacts);
        let plans: Vec<FramePlan> = (0..)
            .zip(scenes)
            .map(|(slot, (contacts, seed))| self.plan(slot, contacts, *seed))
            .collect();
        let (groups, binds) = self.bind_frames(&plans, scenes.iter().map(|(c, _)| &c[..]));
        let contacts_of = scenes.iter().map(|(c, _)| &c[..]);
        let work = self.frame_work(&plans, contacts_of, &binds, &groups.groups, &offsets);
        // One wave goes into the readback's submission; several are recorded side by side
        // and submitted before it.
        let encoder = if work.len() <= self.lanes {
            let mut rec = Recorder::new(self.ctx, &self.resources.dispatch_args);
            self.record_wave(&mut rec, &work)?;
            rec.finish()
        } else {
            let recorded = self.record_frames(&work)?;
            self.ctx.submit_buffers("rendering contacts", recorded)?;
            self.ctx.device.create_command_encoder(&Default::default())
        };
        drop(work);
        let rects: Vec<Option<Rect>> = plans.iter().map(|p| p.holding).collect();
        let fields: Vec<Option<(u64, u64)>> = contacts
            .iter()
            .zip(offsets)
            .map(|(p, at)| p.footprint.map(|_| (at, p.field_bytes(self.grid.texels))))
            .collect();
        self.read_frames("rendering contacts", encoder, &rects, &fields)
    }

    /// Where each contact's own penetration goes in the penetration fields, packed in order
    /// (which are made to hold them all).
    pub(super) fn field_offsets(&mut self, contacts: &[&Prepared]) -> Vec<u64> {
        let mut offsets = Vec::with_capacity(contacts.len());
        let mut bytes = 0;
        for p in contacts {
            offsets.push(bytes);
            bytes += p.field_bytes(self.grid.texels);
        }
        self.resources.reserve_fields(self.ctx, bytes);
        offsets
    }

    /// The bind groups of the frames `plans` plan, of the contacts of each: their uniforms
    /// written to the frame uniforms' buffer, then a group each.
    pub(super) fn bind_frames<'c>(
        &mut self,
        plans: &[FramePlan],
        contacts: impl Iterator<Item = &'c [Prepared]>,
    ) -> (BindGroups, Vec<FrameBinds>) {
        let mut plan = BindPlan::default();
        let binds = plans
            .iter()
            .zip(contacts)
            .map(|(p, contacts)| plan.frame(p, contacts))
            .collect();
        let uniforms: Vec<FrameUniform> = plan.groups.iter().map(|g| g.1).collect();
        self.resources.write_uniforms(self.ctx, &uniforms);
        let res = &self.resources;
        let groups = (0..)
            .zip(&plan.groups)
            .map(|(k, &(slot, _, object))| {
                let binding = FrameBinding {
                    uniform: &res.frame_uniforms,
                    uniform_offset: k * UNIFORM_STRIDE,
                    slot,
                    lane: self.lane_of(slot),
                    grid: object.map_or(&res.empty_grid, |o| res.grid_of(o)),
                };
                res.bind_group(&self.ctx.device, binding)
            })
            .collect();
        (BindGroups { groups }, binds)
    }

    /// The plan of the frame of `contacts` in `slot`; the heightfield's bookkeeping moves on
    /// to it (the frames of a submission run in order).
    pub(super) fn plan(&mut self, slot: u64, contacts: &[Prepared], seed: u32) -> FramePlan {
        let footprints: Vec<_> = contacts.iter().filter_map(|p| p.footprint).collect();
        let texels = Rect::disjoint(footprints.iter().map(|f| f.texels));
        let meridians = Rect::disjoint(footprints.iter().map(|f| f.meridians));
        let pixels = span(&Rect::disjoint(
            contacts.iter().filter_map(|p| p.pixel_rect()),
        ));
        let texel_span = span(&texels);
        let holding = self.changed_rect(pixels);
        let lane = self.lane_of(slot);
        let region = texel_span.map(|t| {
            let region = self.dirty[lane].map_or(t, |d| d.union(&t));
            self.dirty[lane] = Some(t);
            region
        });
        let mut uniform = contacts
            .first()
            .map_or(FrameUniform::reference(&self.sensor, seed), |p| p.uniform)
            .holding(holding);
        uniform.noise_seed = seed;
        uniform.texel_rect = rect4(texel_span);
        uniform.pixel_rect = rect4(pixels);
        uniform.meridian_rect = rect4(span(&meridians));
        FramePlan {
            slot,
            texels,
            meridians,
            pixels,
            holding,
            region,
            uniform,
        }
    }

    /// What recording the frames `plans` plan needs of each: its contacts' passes (those
    /// with a footprint), its bind groups and its lane's heightfield.
    pub(super) fn frame_work<'a>(
        &'a self,
        plans: &'a [FramePlan],
        scenes: impl Iterator<Item = &'a [Prepared]>,
        binds: &'a [FrameBinds],
        groups: &'a [wgpu::BindGroup],
        field_offsets: &[u64],
    ) -> Vec<FrameWork<'a>> {
        let pieces = |rects: &[Rect], binds: &[usize]| -> Vec<(Rect, &'a wgpu::BindGroup)> {
            rects
                .iter()
                .zip(binds)
                .map(|(&r, &k)| (r, &groups[k]))
                .collect()
        };
        let mut at = field_offsets;
        plans
            .iter()
            .zip(scenes)
            .zip(binds)
            .map(|((plan, contacts), b)| {
                let (mine, rest) = at.split_at(contacts.len().min(at.len()));
                at = rest;
                let passes = contacts
                    .iter()
                    .zip(&b.contacts)
                    .zip(mine)
                    .filter_map(|((c, &k), &field_offset)| {
                        c.footprint.map(|f| ContactPass {
                            bind: &groups[k],
                            kind: c.uniform.object_kind,
                            pressed: f.pressed,
                            field_offset,
                        })
                    })
                    .collect();
                FrameWork {
                    plan,
                    contacts: passes,
                    frame: &groups[b.frame],
                    texels: pieces(&plan.texels, &b.texels),
                    meridians: pieces(&plan.meridians, &b.meridians),
                    heightfield: &self.resources.heightfields[self.lane_of(plan.slot)],
                }
            })
            .collect()
    }

    /// The lane (heightfield) of the frame in `slot`.
    pub(super) fn lane_of(&self, slot: u64) -> usize {
        slot as usize % self.lanes
    }

    /// Records the frames' stages, [`Renderer::lanes`] frames (a wave) to a command buffer,
    /// the waves side by side on rayon's threads (what the CPU does for a frame, recording,
    /// is then shared by the cores), each wave's errors caught on its own thread.
    pub(super) fn record_frames(&self, frames: &[FrameWork]) -> Result<Vec<wgpu::CommandBuffer>> {
        let args = &self.resources.dispatch_args;
        frames
            .par_chunks(self.lanes)
            .map(|wave| {
                let recorded = self.ctx.scoped("recording frames", || {
                    let mut rec = Recorder::new(self.ctx, args);
                    self.record_wave(&mut rec, wave)?;
                    Ok(rec.finish().finish())
                });
                recorded?
            })
            .collect()
    }

    /// Records a wave of frames: each stage of each of them before the next stage, so that
    /// their dispatches share passes and the copies between stages run together; each
    /// stage's end marked for a profile.
    pub(super) fn record_wave<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        wave: &[FrameWork<'a>],
    ) -> Result<()> {
        let (res, p) = (&self.resources, &self.pipelines);
        let pressed = |f: &FrameWork| f.plan.region.is_some();
        let seen = |f: &FrameWork| f.plan.pixels.is_some();
        for f in wave {
            self.record_frame_start(rec.encoder(), f);
        }
        rec.stage_done(Stage::Start)?;
        // Each frame's k-th contact, its own penetration copied out before the next.
        let most = wave.iter().map(|f| f.contacts.len()).max().unwrap_or(0);
        for k in 0..most {
            for c in wave.iter().filter_map(|f| f.contacts.get(k)) {
                p.contact.dispatch(rec, c)?;
            }
            for f in wave {
                if let Some(c) = f.contacts.get(k) {
                    let fields = &res.penetration_fields;
                    f.heightfield
                        .copy_field(rec.encoder(), c.pressed, fields, c.field_offset);
                }
            }
        }
        refresh(rec, wave, Map::Penetration);
        rec.stage_done(Stage::Contact)?;
        for f in wave.iter().filter(|f| pressed(f)) {
            p.elastomer.dispatch_meridians(rec, &f.meridians);
        }
        refresh(rec, wave, Map::Elastomer);
        rec.stage_done(Stage::Meridians)?;
        for f in wave.iter().filter(|f| pressed(f)) {
            p.elastomer.dispatch_parallels(rec, &f.texels);
        }
        refresh(rec, wave, Map::Height);
        rec.stage_done(Stage::Parallels)?;
        for f in wave.iter().filter(|f| pressed(f)) {
            p.elastomer.record_normals(rec, &f.texels);
        }
        rec.stage_done(Stage::SkinNormals)?;
        // The tile lists join the normals' pass (both read the height map alone); the
        // normals' maps are refreshed after it.
        for f in wave {
            if let Some(pixels) = f.plan.pixels {
                p.touched.record_tiles(rec, pixels, f.frame);
            }
        }
        refresh(rec, wave, Map::Elastomer);
        for f in wave.iter().filter(|f| seen(f)) {
            copy_dispatch_args(rec.encoder(), res, f.plan.slot, TILE_LIST_ARGS);
        }
        for f in wave.iter().filter(|f| seen(f)) {
            p.touched.dispatch_listed(rec, f.plan.slot, f.frame);
        }
        rec.stage_done(Stage::Select)?;
        for f in wave.iter().filter(|f| seen(f)) {
            copy_dispatch_args(rec.encoder(), res, f.plan.slot, TOUCHED_LIST_ARGS);
        }
        for f in wave.iter().filter(|f| seen(f)) {
            p.camera.dispatch_touched(rec, f.plan.slot, f.frame);
        }
        if self.sensor.config.render.noise.any() {
            let size = (self.sensor.width, self.sensor.height);
            for f in wave {
                p.leds.record_noise(rec, f.frame, size);
            }
        }
        rec.stage_done(Stage::Touched)?;
        Ok(())
    }

    /// A frame's start: its image buffers hold its rect of the image, the reference's
    /// pixels there and zero indentation; its counters are zero (the touched list itself
    /// needs no clearing: only the places its counts hold are read); and the heightfield is
    /// zero over its region.
    fn record_frame_start(&self, encoder: &mut wgpu::CommandEncoder, frame: &FrameWork) {
        let (res, plan) = (&self.resources, frame.plan);
        if let Some(r) = plan.holding {
            let offset = plan.slot * res.slot_bytes;
            res.copy_reference(encoder, offset, r);
            encoder.clear_buffer(&res.indentation, offset, Some(held_bytes(r)));
        }
        encoder.clear_buffer(
            &res.counters,
            plan.slot * res.counter_bytes,
            Some(COUNTER_HEADER_BYTES),
        );
        if let Some(region) = plan.region {
            frame.heightfield.clear(encoder, Some(region));
        }
    }
}
