//! Rendering a run's samples: a thread draws and prepares the next batches' contacts (CPU
//! work) while the render streams ([`RenderPool`]) render batches on the GPU, and encoder
//! threads post-process, encode and write the frames.

use super::encode::{Job, SampleWriter};
use super::reference::write_references;
use super::sampling::{sample_contact, sample_contacts};
use super::spec::Spec;
use super::{Progress, Report, Split};
use crate::error::{GeltipError, Result};
use crate::object::Object;
use crate::render::background::Backgrounds;
use crate::render::gpu::{PreparedBatch, Renderer};
use crate::render::pool::RenderPool;
use crate::render::{Frame, GroundTruth};
use crate::sensor::{Noise, Sensor};
use rayon::prelude::*;
use std::path::Path;
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

/// A batch of samples rendered by one stream.
struct Rendered<'t> {
    indices: &'t [u64],
    frames: Vec<(Frame, Vec<GroundTruth>)>,
    /// Drawing and preparing the batch's contacts.
    prepare: Duration,
    render: Duration,
    readback: Duration,
}

/// Renders the samples `todo` of `spec` into `out` (or encodes and discards them), filling
/// `report`'s start-up, wall time, split, counts and bytes.
pub(super) fn render_samples(
    spec: &Spec,
    out: Option<&Path>,
    objects: &[Arc<Object>],
    backgrounds: Option<&Backgrounds>,
    todo: &[u64],
    report: &mut Report,
    progress: &mut impl FnMut(Progress),
) -> Result<()> {
    let start = Instant::now();
    // Noise is added per sample on the CPU; the renderers render without it. Every object's
    // contact pipeline is built now, at start-up, not in the first batch's frames.
    let mut config = spec.sensor.config.clone();
    config.render.noise = Noise::NONE;
    let render_sensor = Sensor::from_config(spec.sensor.name.clone(), config)?;
    let mut pool = RenderPool::start(&render_sensor, spec.streams, objects)?;
    report.startup = start.elapsed();
    let start = Instant::now();
    if let Some(dir) = out {
        write_references(spec, dir, pool.first().reference(), backgrounds)?;
    }
    let writer = SampleWriter::new(spec, out, pool.first().reference(), backgrounds)?;
    let total = todo.len() as u64;
    let mut split = Split::default();
    let (tx, rx) = mpsc::sync_channel::<Job>(2 * pool.batch_frames());
    let rx = Mutex::new(rx);
    let rendered = std::thread::scope(|scope| {
        for _ in 0..spec.workers.max(1) {
            scope.spawn(|| writer.serve(&rx));
        }
        // Returning drops the sender: the encoder threads stop once the channel is empty.
        render_batches(
            &mut pool, spec, objects, todo, &writer, tx, &mut split, progress,
        )
    });
    if let Some(e) = writer.take_error() {
        return Err(e);
    }
    rendered?;
    writer.add_times_to(&mut split);
    report.split = split;
    report.rendered = writer.done();
    report.bytes = writer.bytes();
    report.wall = start.elapsed();
    progress(Progress {
        done: report.rendered,
        total,
    });
    Ok(())
}

/// Draws, prepares and renders the samples `todo` in batches on the pool's streams, sending
/// each frame to the encoder threads through `tx`; adds the preparation and GPU times to
/// `split`, and reports progress after each batch.
// Eight arguments: the pipeline's parts, each used once here.
#[allow(clippy::too_many_arguments)]
fn render_batches<'t>(
    pool: &mut RenderPool,
    spec: &Spec,
    objects: &[Arc<Object>],
    todo: &'t [u64],
    writer: &SampleWriter<'_>,
    tx: mpsc::SyncSender<Job>,
    split: &mut Split,
    progress: &mut impl FnMut(Progress),
) -> Result<()> {
    let total = todo.len() as u64;
    let preparer = pool.first().preparer();
    // Drawn and prepared on the pool's producer thread, a batch ahead of each stream.
    let layout = (spec.empty_fraction, spec.contacts_per_sample);
    let batches = todo.chunks(pool.batch_frames()).map(move |indices| {
        let t = Instant::now();
        // Drawn side by side on rayon's threads; the first sample's error in order.
        let drawn: Vec<Result<Vec<_>>> = indices
            .par_iter()
            .map(|&k| {
                let (sensor, range, seed) = (&spec.sensor, spec.depth_range, spec.seed);
                if spec.scenes() {
                    sample_contacts(sensor, objects, range, layout, seed, k)
                } else {
                    sample_contact(sensor, objects, range, seed, k).map(|c| vec![c])
                }
            })
            .collect();
        let prepared = drawn
            .into_iter()
            .collect::<Result<Vec<_>>>()
            .and_then(|frames| preparer.prepare_frames(&frames));
        (indices, prepared, t.elapsed())
    });
    let render =
        |renderer: &mut Renderer,
         (indices, prepared, prepare): (&'t [u64], Result<PreparedBatch>, Duration)| {
            let frames = renderer.render_prepared_frames(prepared?)?;
            let t = renderer.timings();
            Ok(Rendered {
                indices,
                frames,
                prepare,
                render: t.render,
                readback: t.readback,
            })
        };
    // The encoders failed: stop rendering (their error is the run's).
    let stopped = || GeltipError::input("dataset", "the encoder threads stopped");
    pool.run(batches, render, |batch| {
        split.prepare += batch.prepare;
        split.render += batch.render;
        split.readback += batch.readback;
        for (&k, (frame, truths)) in batch.indices.iter().zip(batch.frames) {
            if writer.failed() {
                return Err(stopped());
            }
            tx.send(Job { k, frame, truths }).map_err(|_| stopped())?;
        }
        progress(Progress {
            done: writer.done(),
            total,
        });
        Ok(())
    })
}
