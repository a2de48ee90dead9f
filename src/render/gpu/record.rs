//! Recording a submission: the stages' dispatches go into as few compute passes as the
//! copies between them allow, and profiling times the stages a frame marks.

use super::layout::{groups, GROUPS_ROW, WORKGROUP};
use crate::error::{GeltipError, Result};
use crate::gpu::readback::read_buffer;
use crate::gpu::GpuContext;
use crate::render::Rect;
use std::time::{Duration, Instant};

/// A compute dispatch's workgroups: a count, or the indirect arguments at a byte offset of
/// the dispatch buffer.
#[derive(Debug, Clone, Copy)]
pub(super) enum Groups {
    Direct(u32, u32, u32),
    Indirect(u64),
}

impl Groups {
    /// One invocation a texel or pixel of `r`, in [`WORKGROUP`]-square workgroups, of one
    /// frame.
    pub fn over(r: Rect) -> Groups {
        Groups::Direct(groups(r.w, WORKGROUP), groups(r.h, WORKGROUP), 1)
    }

    /// `n` workgroups in rows of [`GROUPS_ROW`] (a dispatch over frames side by side:
    /// `shaders/shared/common.wgsl` use_frame_of).
    pub fn spread(n: u32) -> Groups {
        Groups::Direct(n.min(GROUPS_ROW), n.div_ceil(GROUPS_ROW), 1)
    }

    /// Whether the dispatch runs any workgroup (an indirect one may still run none).
    fn works(self) -> bool {
        !matches!(self, Groups::Direct(x, y, z) if x == 0 || y == 0 || z == 0)
    }
}

/// The stages of a frame, as the renderer's profile names them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Stage {
    /// The frame's image buffers from the reference, its counters and heightfield cleared.
    Start,
    Contact,
    Meridians,
    Parallels,
    SkinNormals,
    /// The tile list and the touched list.
    Select,
    /// The camera's passes over the touched pixels, and the noise.
    Touched,
}

impl Stage {
    pub const ALL: [Stage; 7] = [
        Stage::Start,
        Stage::Contact,
        Stage::Meridians,
        Stage::Parallels,
        Stage::SkinNormals,
        Stage::Select,
        Stage::Touched,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Stage::Start => "copy reference + clear",
            Stage::Contact => "contact",
            Stage::Meridians => "elastomer: meridians",
            Stage::Parallels => "elastomer: parallels",
            Stage::SkinNormals => "elastomer: skin normals",
            Stage::Select => "touched: select",
            Stage::Touched => "camera + leds: touched pixels",
        }
    }
}

/// How a profile times the stages: timestamps between them in one submission, where the
/// device writes them between commands (lavapipe does), so that a stage's time is its own
/// work; else each stage submitted and waited for on its own, its wall time including both.
enum Clock {
    Timestamps(wgpu::QuerySet),
    Waits {
        since: Instant,
        times: Vec<(Stage, Duration)>,
    },
}

/// A command encoder whose dispatches wait in a pending compute pass until a copy, the end
/// of a stage being profiled, or the end of the recording closes it. Why: lavapipe charges
/// each pass of this renderer some 70 µs beyond its dispatches, and a dispatch within a
/// pass some 25 µs (`cargo bench --bench render` prints the device's overhead).
pub(super) struct Recorder<'a> {
    ctx: &'static GpuContext,
    encoder: wgpu::CommandEncoder,
    pass: Vec<(&'a wgpu::ComputePipeline, &'a wgpu::BindGroup, Groups)>,
    dispatch_args: &'a wgpu::Buffer,
    clock: Option<Clock>,
    /// Dispatches and copies (or clears) recorded.
    dispatches: u64,
    copies: u64,
}

impl<'a> Recorder<'a> {
    /// A recorder whose indirect dispatches read `dispatch_args`.
    pub fn new(ctx: &'static GpuContext, dispatch_args: &'a wgpu::Buffer) -> Recorder<'a> {
        Recorder {
            ctx,
            encoder: ctx.device.create_command_encoder(&Default::default()),
            pass: Vec::new(),
            dispatch_args,
            clock: None,
            dispatches: 0,
            copies: 0,
        }
    }

    /// A recorder that times each [`Stage`] the recording marks ([`Self::stage_done`]).
    pub fn profiling(ctx: &'static GpuContext, dispatch_args: &'a wgpu::Buffer) -> Recorder<'a> {
        let mut rec = Recorder::new(ctx, dispatch_args);
        if ctx.has_timestamps() {
            let queries = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("geltip stage timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: Stage::ALL.len() as u32 + 1,
            });
            rec.encoder.write_timestamp(&queries, 0);
            rec.clock = Some(Clock::Timestamps(queries));
        } else {
            rec.clock = Some(Clock::Waits {
                since: Instant::now(),
                times: Vec::new(),
            });
        }
        rec
    }

    /// Adds a dispatch to the pending pass (none when it would run no workgroup).
    pub fn dispatch(
        &mut self,
        pipeline: &'a wgpu::ComputePipeline,
        bind: &'a wgpu::BindGroup,
        groups: Groups,
    ) {
        if groups.works() {
            self.dispatches += 1;
            self.pass.push((pipeline, bind, groups));
        }
    }

    /// The encoder, for `n` copies and clears (counted): the pending pass is recorded
    /// first.
    pub fn copies(&mut self, n: u64) -> &mut wgpu::CommandEncoder {
        self.copies += n;
        self.encoder()
    }

    /// Dispatches and copies recorded so far.
    pub fn commands(&self) -> (u64, u64) {
        (self.dispatches, self.copies)
    }

    /// The encoder, for copies and clears: the pending pass is recorded first.
    pub fn encoder(&mut self) -> &mut wgpu::CommandEncoder {
        self.close_pass();
        &mut self.encoder
    }

    fn close_pass(&mut self) {
        if self.pass.is_empty() {
            return;
        }
        let mut pass = self
            .encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: None,
                timestamp_writes: None,
            });
        for (pipeline, bind, groups) in self.pass.drain(..) {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, bind, &[]);
            match groups {
                Groups::Direct(x, y, z) => pass.dispatch_workgroups(x, y, z),
                Groups::Indirect(offset) => {
                    pass.dispatch_workgroups_indirect(self.dispatch_args, offset)
                }
            }
        }
    }

    /// Marks the end of `stage`: nothing unless profiling.
    pub fn stage_done(&mut self, stage: Stage) -> Result<()> {
        if self.clock.is_none() {
            return Ok(());
        }
        self.close_pass();
        match &mut self.clock {
            Some(Clock::Timestamps(queries)) => {
                self.encoder.write_timestamp(queries, stage as u32 + 1);
            }
            Some(Clock::Waits { since, times }) => {
                let fresh = self.ctx.device.create_command_encoder(&Default::default());
                let encoder = std::mem::replace(&mut self.encoder, fresh);
                self.ctx.submit_and_wait(stage.name(), encoder)?;
                times.push((stage, since.elapsed()));
                *since = Instant::now();
            }
            None => {}
        }
        Ok(())
    }

    /// The recording, to submit.
    pub fn finish(mut self) -> wgpu::CommandEncoder {
        self.close_pass();
        self.encoder
    }

    /// Submits a profiled recording, waits, and returns each marked stage's time.
    pub fn finish_profile(mut self) -> Result<Vec<(Stage, Duration)>> {
        self.close_pass();
        let ctx = self.ctx;
        match self.clock {
            Some(Clock::Timestamps(queries)) => {
                let marks = Stage::ALL.len() as u32 + 1;
                let resolved = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("geltip stage timestamps"),
                    size: marks as u64 * 8,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                self.encoder
                    .resolve_query_set(&queries, 0..marks, &resolved, 0);
                ctx.submit_and_wait("profiling a frame", self.encoder)?;
                let ticks: Vec<u64> = read_buffer(ctx, &resolved, 0, marks as usize)?;
                let ns = ctx.queue.get_timestamp_period() as f64;
                Ok(Stage::ALL
                    .iter()
                    .zip(ticks.windows(2))
                    .map(|(&stage, t)| {
                        let elapsed = t[1].saturating_sub(t[0]) as f64 * ns;
                        (stage, Duration::from_nanos(elapsed as u64))
                    })
                    .collect())
            }
            Some(Clock::Waits { times, .. }) => {
                ctx.submit_and_wait("profiling a frame", self.encoder)?;
                Ok(times)
            }
            None => Err(GeltipError::Gpu(
                "a recording that was not profiled has no stage times".into(),
            )),
        }
    }
}
