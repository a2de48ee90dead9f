//! The one frame path: a submission of up to [`Renderer::batch_frames`] frames, each a scene
//! of one or more contacts (a batch's frame is a scene of one). Per frame, every object's
//! contact pass over its own pressed rect (each texel keeps the deepest press); the
//! elastomer's passes over the union of the footprints, split into disjoint rectangles (the
//! cost follows the footprints' area, not the number of objects); then the touched pixels of
//! the union of their pixel rects, cast, shaded and given noise. Each contact's labels come
//! from its own penetration field, read back with the frames.
//!
//! The frames of a wave ([`Renderer::lanes`] of them, each on its own heightfield) are
//! recorded stage by stage, each stage one dispatch over all of them sized by the sum of
//! their work: a frame's (or a piece's) workgroups follow the one before's, its uniform (at
//! its place of the dispatch's bind group) says where its share starts, and a workgroup
//! finds its frame by bisection (`use_frame_of` in `shaders/shared/common.wgsl`); a pass
//! over lists the GPU fills (tiles, touched pixels) gets its shares and its size from a
//! one-invocation pass once the lists are whole (`wave_bases` in `shaders/touched.wgsl`).
//! On a GPU the copies between stages (the maps' refreshes, the heightfield's clears, the
//! indirect dispatches' arguments) are one each for the wave; on a software device, where
//! a copy is a memory copy, the heightfield's are a lane's own. Why: wgpu puts a barrier
//! before every dispatch and copy that writes, and on a GPU those barriers, not the work,
//! were a frame's time; on llvmpipe a workgroup with nothing to do still runs.

use super::bindings::{packed_offsets, FrameBinding, WaveRange, FRAMES_BOUND};
use super::layout::{
    groups, COUNTER_HEADER_BYTES, OVER_PRESSED, SELECT_TILES_WORKGROUP, WORKGROUP,
};
use super::layout::{DEEP_COUNT, SHALLOW_COUNT, TILE_COUNT};
use super::prepare::{too_many, Prepared};
use super::readback::ReadFrames;
use super::record::{Groups, Recorder, Stage};
use super::resources::{held_bytes, LaneSpan, Map, UNIFORM_STRIDE};
use super::stages::{copy_dispatch_args, Batch, TILE_LIST_ARGS, TOUCHED_LIST_ARGS};
use super::{Renderer, Timings};
use crate::error::Result;
use crate::object::Object;
use crate::render::touched::tiles_over;
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
    /// The rect of the image the frame's buffers hold ([`Renderer::changed_rect`]), and
    /// where in the image and indentation buffers ([`packed_offsets`]).
    pub holding: Option<Rect>,
    pub image_offset: u64,
    /// Its frame uniform: the first contact's, holding its image rect, its noise seed, and
    /// as its rects the spans of the pieces. A piece's pass reads it with the piece as its
    /// rect (each stage reads only the rect it runs over: `shaders/shared/common.wgsl`).
    pub uniform: FrameUniform,
}

impl FramePlan {
    /// The span of its texels: whether (and where) its contacts press the skin.
    fn texel_span(&self) -> Option<Rect> {
        span(&self.texels)
    }
}

/// The smallest rect covering `rects`.
fn span(rects: &[Rect]) -> Option<Rect> {
    rects.iter().copied().reduce(|a, b| a.union(&b))
}

/// Workgroups over the largest of `rects` (one invocation a texel or pixel, at least
/// `least` workgroups a side), for `frames` frames.
fn over_largest(rects: impl Iterator<Item = Rect>, least: u32, frames: u32) -> Groups {
    let (w, h) = rects.fold((0, 0), |(w, h), r| (r.w.max(w), r.h.max(h)));
    let side = |n| groups(n, WORKGROUP).max(least);
    Groups::Direct(side(w), side(h), frames)
}

/// How a wave's frames start ([`Renderer::record_wave`]).
pub(super) enum Start {
    /// Copies and clears, the frames' image offsets and held rects. For a frame
    /// alone, and for every wave on a software device, where these are memory copies and a
    /// pass writes pixel by pixel (8 of the paper's taps: 1.2 ms of copies against 5.6 for
    /// the pass, `cargo bench --bench render -- --wave-stages 8`).
    Copies(Vec<(u64, Option<Rect>)>),
    /// Several: the start pass over all of them (`shaders/start.wgsl`).
    Pass(Dispatches),
}

impl Default for Start {
    fn default() -> Self {
        Start::Pass(Vec::new())
    }
}

/// A stage's dispatches, as bind groups' indices and workgroups.
type Dispatches = Vec<(usize, Groups)>;

/// What a wave of frames records, its bind groups as indices into the submission's.
#[derive(Default)]
pub(super) struct Wave {
    /// Its first frame's slot: the indirect dispatches' arguments are there.
    first_slot: u64,
    /// The heightfield its frames clear and refresh (none if no frame presses it).
    spans: Vec<LaneSpan>,
    start: Start,
    /// Per round (each frame's k-th contact), the dispatches of each kind of object.
    contacts: Vec<Vec<(u32, usize, Groups)>>,
    meridians: Dispatches,
    texels: Dispatches,
    /// The tile lists' dispatch, and the bind group of the passes sized by them.
    listed: Option<(usize, Groups)>,
    noise: Dispatches,
}

/// A submission's frame uniforms, grouped into the bind groups its dispatches bind: per
/// group, its first uniform, its wave, and the object whose SDF grid it binds (a contact's)
/// or none.
#[derive(Default)]
struct Binds<'c> {
    uniforms: Vec<FrameUniform>,
    groups: Vec<(usize, WaveRange, Option<&'c Object>)>,
}

impl<'c> Binds<'c> {
    /// Bind groups for a dispatch over `items` of the wave `slots`: as many as it takes to
    /// hold them, [`FRAMES_BOUND`] each, with how many each holds.
    fn add(
        &mut self,
        items: &[FrameUniform],
        slots: WaveRange,
        grid: Option<&'c Object>,
    ) -> Vec<(usize, u32)> {
        items
            .chunks(FRAMES_BOUND as usize)
            .map(|chunk| (self.group_of(chunk, slots, grid), chunk.len() as u32))
            .collect()
    }

    /// A group of the uniforms `chunk`: an earlier one that binds the same (a frame of one
    /// contact binds one group for all its passes: lavapipe charges each change of group),
    /// else a new one.
    fn group_of(
        &mut self,
        chunk: &[FrameUniform],
        slots: WaveRange,
        grid: Option<&'c Object>,
    ) -> usize {
        // Only a loaded mesh's grid tells groups apart (any other binds the empty one).
        let grid = grid.filter(|o| matches!(o, Object::Mesh { .. }));
        let bytes: &[u8] = bytemuck::cast_slice(chunk);
        let same = |&(first, w, g): &(usize, WaveRange, Option<&Object>)| {
            let held = self.uniforms.get(first..first + chunk.len());
            w == slots
                && g.map(|o| o as *const Object) == grid.map(|o| o as *const Object)
                && held.is_some_and(|h| bytemuck::cast_slice::<_, u8>(h) == bytes)
        };
        if let Some(k) = self.groups.iter().position(same) {
            return k;
        }
        self.groups.push((self.uniforms.len(), slots, grid));
        self.uniforms.extend_from_slice(chunk);
        self.groups.len() - 1
    }

    /// Dispatches over `items` (uniforms and the workgroups each needs) side by side: as many
    /// as [`FRAMES_BOUND`] a dispatch, each frame's workgroups after the one before's (its
    /// uniform given its first workgroup and the dispatch's frames), the dispatch sized by
    /// their sum (`shaders/shared/common.wgsl` use_frame_of).
    fn spread(
        &mut self,
        items: &[(FrameUniform, u32)],
        slots: WaveRange,
        grid: Option<&'c Object>,
    ) -> Vec<(usize, Groups)> {
        items
            .chunks(FRAMES_BOUND as usize)
            .map(|chunk| {
                let mut base = 0;
                let uniforms: Vec<FrameUniform> = chunk
                    .iter()
                    .map(|&(mut u, n)| {
                        u.group_base = base;
                        u.group_items = chunk.len() as u32;
                        base += n;
                        u
                    })
                    .collect();
                (self.group_of(&uniforms, slots, grid), Groups::spread(base))
            })
            .collect()
    }

    /// [`Self::spread`] over items with the rects their passes run over, a square
    /// workgroup a [`WORKGROUP`]-square of each rect.
    fn over_rects(
        &mut self,
        items: &[(FrameUniform, Rect)],
        slots: WaveRange,
        grid: Option<&'c Object>,
    ) -> Vec<(usize, Groups)> {
        let sized: Vec<(FrameUniform, u32)> = items
            .iter()
            .map(|&(u, r)| (u, groups(r.w, WORKGROUP) * groups(r.h, WORKGROUP)))
            .collect();
        self.spread(&sized, slots, grid)
    }

    /// A dispatch each for `items` (with the rects their passes run over), sized by the
    /// largest rect.
    fn over(&mut self, items: &[(FrameUniform, Rect)], slots: WaveRange) -> Dispatches {
        let uniforms: Vec<FrameUniform> = items.iter().map(|i| i.0).collect();
        let added = self.add(&uniforms, slots, None);
        let mut rects = items.iter().map(|i| i.1);
        added
            .into_iter()
            .map(|(k, n)| (k, over_largest(rects.by_ref().take(n as usize), 0, n)))
            .collect()
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
        let (read, commands) = self.forget_heightfield_on_error(ran)?;
        let mut timings = Timings {
            prepare,
            render: read.mapped - start,
            record: read.submitted.saturating_duration_since(start),
            dispatches: commands.0,
            copies: commands.1,
            readback_copies: read.copies,
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

    /// Plans, records, submits and reads back the frames of `scenes`; with the dispatches
    /// and copies recorded.
    fn run_frames(&mut self, scenes: &[Scene]) -> Result<(ReadFrames, (u64, u64))> {
        let contacts: Vec<&Prepared> = scenes.iter().flat_map(|(c, _)| c).collect();
        let offsets = self.field_offsets(&contacts)?;
        let plans = self.plan_frames(scenes.iter().map(|(c, seed)| (&c[..], *seed)));
        let rects: Vec<Option<Rect>> = plans.iter().map(|p| p.holding).collect();
        let scene_contacts: Vec<&[Prepared]> = scenes.iter().map(|(c, _)| &c[..]).collect();
        let (groups, waves) = self.waves(&plans, &scene_contacts, &offsets);
        // One wave goes into the readback's submission; several are recorded side by side
        // and submitted before it.
        let (encoder, commands) = if waves.len() <= 1 {
            let mut rec = Recorder::new(self.ctx, &self.resources.dispatch_args);
            if let Some(wave) = waves.first() {
                self.record_wave(&mut rec, wave, &groups)?;
            }
            let commands = rec.commands();
            (rec.finish(), commands)
        } else {
            let (recorded, commands) = self.record_frames(&waves, &groups)?;
            self.ctx.submit_buffers("rendering contacts", recorded)?;
            let encoder = self.ctx.device.create_command_encoder(&Default::default());
            (encoder, commands)
        };
        let fields: Vec<Option<(u64, u64)>> = contacts
            .iter()
            .zip(offsets)
            .map(|(p, at)| p.footprint.map(|_| (at, p.field_bytes(self.grid.texels))))
            .collect();
        let read = self.read_frames("rendering contacts", encoder, &rects, &fields)?;
        Ok((read, commands))
    }

    /// Where each contact's own penetration goes among the contacts' fields (after the
    /// lanes' heights in the height buffer), packed in order; the buffer is made to hold
    /// them all.
    pub(super) fn field_offsets(&mut self, contacts: &[&Prepared]) -> Result<Vec<u64>> {
        let mut offsets = Vec::with_capacity(contacts.len());
        let mut bytes = 0;
        for p in contacts {
            offsets.push(bytes);
            bytes += p.field_bytes(self.grid.texels);
        }
        self.resources.reserve_fields(self.ctx, bytes)?;
        Ok(offsets)
    }

    /// The plans of a submission's frames (their contacts and noise seeds), in slots from
    /// 0, their image rects packed in order.
    pub(super) fn plan_frames<'s>(
        &self,
        scenes: impl Iterator<Item = (&'s [Prepared], u32)>,
    ) -> Vec<FramePlan> {
        let mut plans: Vec<FramePlan> = (0..)
            .zip(scenes)
            .map(|(slot, (contacts, seed))| self.plan(slot, contacts, seed))
            .collect();
        let rects: Vec<Option<Rect>> = plans.iter().map(|p| p.holding).collect();
        for (p, at) in plans.iter_mut().zip(packed_offsets(&rects).0) {
            p.image_offset = at;
        }
        plans
    }

    /// The plan of the frame of `contacts` in `slot`.
    pub(super) fn plan(&self, slot: u64, contacts: &[Prepared], seed: u32) -> FramePlan {
        let footprints: Vec<_> = contacts.iter().filter_map(|p| p.footprint).collect();
        let texels = Rect::disjoint(footprints.iter().map(|f| f.texels));
        let meridians = Rect::disjoint(footprints.iter().map(|f| f.meridians));
        let pixels = span(&Rect::disjoint(
            contacts.iter().filter_map(|p| p.pixel_rect()),
        ));
        let holding = self.changed_rect(pixels);
        let mut uniform = contacts
            .first()
            .map_or(FrameUniform::reference(&self.sensor, seed), |p| p.uniform)
            .holding(holding);
        uniform.noise_seed = seed;
        uniform.texel_rect = rect4(span(&texels));
        uniform.pixel_rect = rect4(pixels);
        uniform.meridian_rect = rect4(span(&meridians));
        FramePlan {
            slot,
            texels,
            meridians,
            pixels,
            holding,
            image_offset: 0,
            uniform,
        }
    }

    /// The heightfield a wave of frames (`plans`, on lanes in order) clears and refreshes:
    /// every texel their frames press and every texel their lanes' maps may hold non-zero
    /// (their last frames'), so that the maps are zero outside the texels their frames press
    /// afterwards (clearing and refreshing a zero texel changes nothing). On a GPU one span,
    /// from the first lane its frames press to the last, over the union of those texels (a
    /// copy each, however many lanes: each copy waits on a barrier); on a software device a
    /// span a lane, over that lane's own texels (copies are memory copies there, and the
    /// union of a wave's mixed contacts is most of every lane). The heightfield's
    /// bookkeeping moves on to the wave (the waves of a submission run in order).
    fn wave_spans(&mut self, plans: &[FramePlan]) -> Vec<LaneSpan> {
        if self.software() {
            let mut spans = Vec::new();
            for p in plans {
                let lane = self.lane_of(p.slot);
                let rect = [p.texel_span(), self.dirty[lane]]
                    .into_iter()
                    .flatten()
                    .reduce(|a, b| a.union(&b));
                self.dirty[lane] = p.texel_span();
                if let Some(rect) = rect {
                    let lane = lane as u32;
                    spans.push(LaneSpan {
                        first: lane,
                        last: lane,
                        rect,
                    });
                }
            }
            return spans;
        }
        let pressed = || {
            plans
                .iter()
                .filter_map(|p| Some((self.lane_of(p.slot), p.texel_span()?)))
        };
        let (Some(first), Some(last)) = (
            pressed().map(|(l, _)| l).min(),
            pressed().map(|(l, _)| l).max(),
        ) else {
            return Vec::new();
        };
        let texels = pressed().map(|(_, t)| t);
        let dirty = self.dirty[first..=last].iter().flatten().copied();
        let Some(rect) = texels.chain(dirty).reduce(|a, b| a.union(&b)) else {
            return Vec::new();
        };
        for p in plans {
            let lane = self.lane_of(p.slot);
            if (first..=last).contains(&lane) {
                self.dirty[lane] = p.texel_span();
            }
        }
        vec![LaneSpan {
            first: first as u32,
            last: last as u32,
            rect,
        }]
    }

    /// The waves of the frames `plans` plan, of the contacts of each (their fields at
    /// `field_offsets`), and the bind groups they bind: the frame uniforms written to the
    /// frame uniforms' buffer, then a group per dispatch.
    pub(super) fn waves(
        &mut self,
        plans: &[FramePlan],
        scenes: &[&[Prepared]],
        field_offsets: &[u64],
    ) -> (Vec<wgpu::BindGroup>, Vec<Wave>) {
        let mut binds = Binds::default();
        let mut waves = Vec::new();
        let mut fields = field_offsets;
        for (plans, scenes) in plans.chunks(self.lanes).zip(scenes.chunks(self.lanes)) {
            let spans = self.wave_spans(plans);
            let contacts = scenes.iter().map(|c| c.len()).sum::<usize>();
            let (mine, rest) = fields.split_at(contacts.min(fields.len()));
            fields = rest;
            waves.push(self.wave(&mut binds, plans, scenes, mine, spans));
        }
        self.resources.write_uniforms(self.ctx, &binds.uniforms);
        let res = &self.resources;
        let groups = binds
            .groups
            .iter()
            .map(|&(first, wave, object)| {
                let binding = FrameBinding {
                    uniform: &res.frame_uniforms,
                    uniform_offset: first as u64 * UNIFORM_STRIDE,
                    wave,
                    grid: object.map_or(&res.empty_grid, |o| res.grid_of(o)),
                };
                res.bind_group(&self.ctx.device, binding)
            })
            .collect();
        (groups, waves)
    }

    /// The dispatches of a wave of frames (`plans`, of the contacts in `scenes`, whose
    /// fields go at `fields`), their uniforms added to `binds`.
    fn wave<'c>(
        &self,
        binds: &mut Binds<'c>,
        plans: &[FramePlan],
        scenes: &[&'c [Prepared]],
        fields: &[u64],
        spans: Vec<LaneSpan>,
    ) -> Wave {
        let res = &self.resources;
        let first_slot = plans.first().map_or(0, |p| p.slot);
        let image_offset = plans.first().map_or(0, |p| p.image_offset);
        let image_end = plans
            .last()
            .map_or(0, |p| p.image_offset + p.holding.map_or(0, held_bytes));
        let slots = WaveRange {
            first_slot,
            slots: plans.len() as u64,
            image_offset,
            image_bytes: image_end - image_offset,
        };
        let seen = plans.iter().filter(|p| p.pixels.is_some()).count() as u32;
        let fields_at = res.heightfield.fields_at();
        // Each frame's first pressing contact's field (its uniform's, as the frame's is).
        let mut at = fields;
        let first_fields: Vec<u64> = scenes
            .iter()
            .map(|contacts| {
                let (mine, rest) = at.split_at(contacts.len().min(at.len()));
                at = rest;
                let pressing = contacts
                    .iter()
                    .zip(mine)
                    .filter(|(c, _)| c.footprint.is_some());
                pressing.map(|(_, &o)| o).next().unwrap_or(0)
            })
            .collect();
        // Each frame's uniform, with where its data lies in the wave's bindings.
        let placed: Vec<FrameUniform> = plans
            .iter()
            .zip(&first_fields)
            .map(|(p, &field)| {
                let mut u = p.uniform;
                u.field_at = (fields_at + field / 4) as u32;
                let k = p.slot - first_slot;
                u.lane = self.lane_of(p.slot) as u32;
                u.image_at = ((p.image_offset - image_offset) / 4) as u32;
                // The wave's frames' counters side by side, then their lists: the counters
                // are read back in one copy.
                u.counters_at = (k * COUNTER_HEADER_BYTES / 4) as u32;
                let lists = plans.len() as u64 * COUNTER_HEADER_BYTES;
                u.list_at = ((lists + k * (res.counter_bytes - COUNTER_HEADER_BYTES)) / 4) as u32;
                u.listed_frames = seen;
                u
            })
            .collect();
        let copies = plans.len() == 1 || self.software();
        let start = match plans {
            _ if copies => {
                Start::Copies(plans.iter().map(|p| (p.image_offset, p.holding)).collect())
            }
            _ => {
                let held = plans.iter().filter_map(|p| p.holding);
                // At least a workgroup a frame: the first clears its counters.
                let g = |n| over_largest(held.clone(), 1, n);
                let added = binds.add(&placed, slots, None);
                Start::Pass(added.into_iter().map(|(k, n)| (k, g(n))).collect())
            }
        };
        let mut wave = Wave {
            first_slot,
            spans,
            start,
            ..Wave::default()
        };
        // Round k: each frame's k-th contact that presses the skin, its uniform its frame's
        // with its own object, rects and field.
        let mut rounds: Vec<Vec<(&'c Object, FrameUniform, Rect)>> = Vec::new();
        let mut at = fields;
        for ((plan, frame), contacts) in plans.iter().zip(&placed).zip(scenes) {
            let (mine, rest) = at.split_at(contacts.len().min(at.len()));
            at = rest;
            let pressing = contacts.iter().zip(mine);
            let pressing = pressing.filter_map(|(c, &o)| Some((c, c.footprint?, o)));
            for (k, (c, f, offset)) in pressing.enumerate() {
                // Its frame's places, so that a frame of one contact has one uniform.
                let mut u = c.uniform.holding(plan.holding);
                u.list_at = frame.list_at;
                u.listed_frames = frame.listed_frames;
                u.noise_seed = plan.uniform.noise_seed;
                u.lane = frame.lane;
                u.image_at = frame.image_at;
                u.counters_at = frame.counters_at;
                u.field_at = (fields_at + offset / 4) as u32;
                if rounds.len() <= k {
                    rounds.push(Vec::new());
                }
                rounds[k].push((&*c.press.object, u, f.pressed));
            }
        }
        wave.contacts = rounds
            .iter()
            .map(|round| contact_dispatches(binds, round, slots))
            .collect();
        // Each pressing frame's pieces, each with the frame's uniform holding it as the rect
        // its pass runs over.
        let pieces = |rects: fn(&FramePlan) -> &[Rect], set: fn(&mut FrameUniform, Rect)| {
            let pressed = plans.iter().zip(&placed);
            let pressed = pressed.filter(|(p, _)| p.texel_span().is_some());
            let all: Vec<(FrameUniform, Rect)> = pressed
                .flat_map(|(p, &u)| {
                    rects(p).iter().map(move |&r| {
                        let mut u = u;
                        set(&mut u, r);
                        (u, r)
                    })
                })
                .collect();
            all
        };
        let meridians = pieces(|p| &p.meridians, |u, r| u.meridian_rect = rect4(Some(r)));
        wave.meridians = binds.over_rects(&meridians, slots, None);
        let texels = pieces(|p| &p.texels, |u, r| u.texel_rect = rect4(Some(r)));
        wave.texels = binds.over_rects(&texels, slots, None);
        let listed: Vec<(FrameUniform, Rect)> = plans
            .iter()
            .zip(&placed)
            .filter_map(|(p, &u)| Some((u, p.pixels?)))
            .collect();
        if !listed.is_empty() {
            let items: Vec<(FrameUniform, u32)> = listed
                .iter()
                .map(|&(u, r)| {
                    let (columns, rows) = tiles_over(r);
                    let tiles = columns.len() as u32 * rows.len() as u32;
                    (u, groups(tiles, SELECT_TILES_WORKGROUP))
                })
                .collect();
            // Every listed frame is in one group: the passes over the lists find their frames
            // among its first listed_frames uniforms (at most the lanes, at most
            // FRAMES_BOUND).
            wave.listed = Some(binds.spread(&items, slots, None)[0]);
        }
        if self.sensor.config.render.noise.any() {
            let whole = super::resources::whole_image(&self.sensor);
            let all: Vec<(FrameUniform, Rect)> = placed.iter().map(|&u| (u, whole)).collect();
            wave.noise = binds.over(&all, slots);
        }
        wave
    }

    /// The lane (heightfield) of the frame in `slot`.
    pub(super) fn lane_of(&self, slot: u64) -> usize {
        slot as usize % self.lanes
    }

    /// Records the waves, a command buffer each, side by side on rayon's threads (what the
    /// CPU does for a frame, recording, is then shared by the cores), each wave's errors
    /// caught on its own thread; with the dispatches and copies recorded.
    fn record_frames(
        &self,
        waves: &[Wave],
        groups: &[wgpu::BindGroup],
    ) -> Result<(Vec<wgpu::CommandBuffer>, (u64, u64))> {
        let args = &self.resources.dispatch_args;
        let recorded: Vec<(wgpu::CommandBuffer, (u64, u64))> = waves
            .par_iter()
            .map(|wave| {
                let recorded = self.ctx.scoped("recording frames", || {
                    let mut rec = Recorder::new(self.ctx, args);
                    self.record_wave(&mut rec, wave, groups)?;
                    let commands = rec.commands();
                    Ok((rec.finish().finish(), commands))
                });
                recorded?
            })
            .collect::<Result<_>>()?;
        let commands = recorded
            .iter()
            .fold((0, 0), |(d, c), (_, (d1, c1))| (d + d1, c + c1));
        Ok((recorded.into_iter().map(|r| r.0).collect(), commands))
    }

    /// Records a wave of frames: each stage one dispatch over all of them (or a few, by
    /// kind of object or [`FRAMES_BOUND`] at a time), then the copies that stage's readers
    /// need, one for the wave; each stage's end marked for a profile.
    pub(super) fn record_wave<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        wave: &Wave,
        groups: &'a [wgpu::BindGroup],
    ) -> Result<()> {
        let (res, p) = (&self.resources, &self.pipelines);
        let hf = &res.heightfield;
        let batches = |d: &Dispatches| -> Vec<Batch<'a>> {
            d.iter()
                .map(|&(k, g)| Batch {
                    bind: &groups[k],
                    groups: g,
                })
                .collect()
        };
        for &span in &wave.spans {
            hf.clear(rec.copies(Map::ALL.len() as u64), span);
        }
        match &wave.start {
            Start::Copies(frames) => self.record_frame_starts(rec, wave.first_slot, frames),
            Start::Pass(start) => {
                for b in batches(start) {
                    p.start.dispatch(rec, b);
                }
            }
        }
        rec.stage_done(Stage::Start)?;
        let refresh = |rec: &mut Recorder<'a>, map: Map| {
            for &span in &wave.spans {
                hf.refresh(rec.copies(1), map, span);
            }
        };
        for round in &wave.contacts {
            for &(kind, k, g) in round {
                let b = Batch {
                    bind: &groups[k],
                    groups: g,
                };
                p.contact.dispatch(rec, kind, b)?;
            }
        }
        refresh(rec, Map::Penetration);
        rec.stage_done(Stage::Contact)?;
        p.elastomer
            .dispatch_meridians(rec, &batches(&wave.meridians));
        refresh(rec, Map::Elastomer);
        rec.stage_done(Stage::Meridians)?;
        let texels = batches(&wave.texels);
        p.elastomer.dispatch_parallels(rec, &texels);
        refresh(rec, Map::Height);
        rec.stage_done(Stage::Parallels)?;
        p.elastomer.record_normals(rec, &texels);
        rec.stage_done(Stage::SkinNormals)?;
        // The tile lists join the normals' pass (both read the height map alone); the
        // normals' maps are refreshed after it.
        let listed = wave.listed.map(|(k, g)| Batch {
            bind: &groups[k],
            groups: g,
        });
        if let Some(b) = listed {
            p.touched.record_tiles(rec, b);
        }
        refresh(rec, Map::Elastomer);
        if let Some(b) = listed {
            copy_dispatch_args(rec.copies(1), res, wave.first_slot, TILE_LIST_ARGS);
            p.touched.dispatch_listed(rec, wave.first_slot, b.bind);
            p.touched.record_touched_bases(rec, b.bind);
        }
        rec.stage_done(Stage::Select)?;
        if let Some(b) = listed {
            copy_dispatch_args(rec.copies(1), res, wave.first_slot, TOUCHED_LIST_ARGS);
            p.camera.dispatch_touched(rec, wave.first_slot, b.bind);
        }
        for b in batches(&wave.noise) {
            p.leds.record_noise(rec, b);
        }
        rec.stage_done(Stage::Touched)?;
        Ok(())
    }

    /// The starts of a wave's frames by copies (a frame alone, or a software device's
    /// wave): as the start pass, their image buffers hold their rects of the image, the
    /// reference's pixels there and zero indentation, and their counters are zero. The
    /// frames' rects lie packed in order, as do their counters, so each clear is one range.
    fn record_frame_starts(
        &self,
        rec: &mut Recorder,
        first_slot: u64,
        frames: &[(u64, Option<Rect>)],
    ) {
        let res = &self.resources;
        let held = frames.iter().filter_map(|&(at, r)| Some((at, r?)));
        for (offset, r) in held.clone() {
            res.copy_reference(rec.copies(1), offset, r);
        }
        let first = held.clone().next().map(|(at, _)| at);
        let end = held.map(|(at, r)| at + held_bytes(r)).next_back();
        if let (Some(first), Some(end)) = (first, end) {
            rec.copies(1)
                .clear_buffer(&res.indentation, first, Some(end - first));
        }
        let counters = first_slot * res.counter_bytes;
        let bytes = frames.len() as u64 * COUNTER_HEADER_BYTES;
        rec.copies(1)
            .clear_buffer(&res.counters, counters, Some(bytes));
    }
}

/// A round's contact dispatches: one for each kind of object (a pipeline each) and loaded
/// mesh (an SDF grid each), over their pressed rects side by side.
fn contact_dispatches<'c>(
    binds: &mut Binds<'c>,
    round: &[(&'c Object, FrameUniform, Rect)],
    slots: WaveRange,
) -> Vec<(u32, usize, Groups)> {
    let key = |(o, u, _): &(&Object, FrameUniform, Rect)| {
        let mesh = matches!(o, Object::Mesh { .. }).then_some(*o as *const Object as usize);
        (u.object_kind, mesh)
    };
    let mut out = Vec::new();
    let mut done = Vec::new();
    for item in round {
        let k = key(item);
        if done.contains(&k) {
            continue;
        }
        done.push(k);
        let alike: Vec<_> = round.iter().filter(|i| key(i) == k).collect();
        let items: Vec<(FrameUniform, Rect)> = alike.iter().map(|i| (i.1, i.2)).collect();
        for (group, g) in binds.over_rects(&items, slots, Some(item.0)) {
            out.push((k.0, group, g));
        }
    }
    out
}
