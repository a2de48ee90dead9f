//! `geltip dataset`: labelled synthetic tactile images, many at a time.
//!
//! Sample `k` of a set is drawn from `(seed, k)` alone by a counter-based hash (SplitMix64),
//! so it is the same whether rendered alone, in a batch, in any shard, or after a resume.
//! Each sample is a contact anywhere the lens can see (object, arc length from the tip,
//! azimuth, depth, spin), rendered on the GPU in batches; PNG encoding and writing run on
//! worker threads while the next batch renders.
//!
//! On disk (`<out>/`): `dataset.json` (written first: the sensor config, geltip version,
//! seed, count, options, shard and command line), `images/000123.png`, optionally
//! `depth/000123.npy` and `masks/000123.png`, and `labels.jsonl`, one JSON line per sample,
//! appended only once the sample's files are complete (every file is written to a temporary
//! name and renamed). A rerun resumes: it keeps the samples whose line and files exist and
//! renders the rest; when the shard is complete, `labels.jsonl` is rewritten sorted by index,
//! so a set's files never depend on how it was produced. Shards (`i/n`: a contiguous block of
//! indices) go to separate directories joined by [`merge`].
//!
//! Sensor noise, light and paint jitter are applied on the CPU per sample from a hash of
//! `(seed, k)`: the renderer draws its own noise from a counter that depends on the batch,
//! and a per-sample sensor would need a new renderer (1-2 s) per sample.
//!
//! One run writes a directory at a time: a run (or merge) locks it, and a second one fails
//! at once naming the first.
//!
//! The parts: [`spec`] (the options), [`sampling`] (a sample's contact from `(seed, k)`),
//! [`look`] (the per-sample post-process), `pipeline` (preparing, render streams, encoder
//! threads), `encode` (a sample's files and label line) and [`store`] (the directory:
//! manifest, labels, resume, lock, merge).

mod encode;
pub mod labels;
pub mod look;
mod pipeline;
mod reference;
pub mod sampling;
pub mod spec;
pub mod store;

pub use crate::render::background::fnv1a64;
pub use labels::{read_labels, LabelLine};
pub use reference::{reference_of_set, REFERENCE};
pub use sampling::{
    load_objects, make_contact, sample_contact, sample_contacts, visible_arc_length, SampleRng,
    MAX_ATTEMPTS,
};
pub use spec::{
    default_depth_range, default_streams, default_workers, parse_contacts_range, parse_depth_range,
    PngLevel, Shard, Spec, MAX_CONTACTS_PER_SAMPLE,
};
pub use store::{merge, LABELS, MANIFEST};

use crate::error::{GeltipError, Result};
use crate::render::background::load_backgrounds;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Duration;

/// Seconds spent in each part of a run (rendering summed over the streams, encoding and
/// writing over the workers).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Split {
    /// Drawing contacts and the renderer's CPU preparation.
    pub prepare: Duration,
    /// GPU render: recording, submitting and waiting until the frames are mapped (summed
    /// over the render streams, which run at once: it can exceed the wall time).
    pub render: Duration,
    /// Unpacking the frames on the CPU (summed over the render streams).
    pub readback: Duration,
    /// Post-process (background, jitter, noise), labels.
    pub post: Duration,
    /// PNG and NPY encoding.
    pub encode: Duration,
    /// Writing files (temporary name, sync, rename) and label lines.
    pub write: Duration,
}

/// What a run did.
#[derive(Debug, Clone, Default)]
pub struct Report {
    /// Samples of the shard.
    pub shard_samples: u64,
    /// Samples found complete and kept.
    pub kept: u64,
    /// Samples rendered now.
    pub rendered: u64,
    /// Renderer start-up (pipelines, empty finger).
    pub startup: Duration,
    /// Wall time of rendering and writing the samples (after start-up).
    pub wall: Duration,
    pub split: Split,
    /// Bytes of files encoded.
    pub bytes: u64,
}

/// Progress of a run: samples done of the samples to do.
#[derive(Debug, Clone, Copy)]
pub struct Progress {
    pub done: u64,
    pub total: u64,
}

/// Renders the samples of `spec`'s shard into `out` (resuming what is there), or, with
/// `out = None`, renders and encodes them and discards the files (for measurements).
/// `progress` is called after each batch.
pub fn run(spec: &Spec, out: Option<&Path>, mut progress: impl FnMut(Progress)) -> Result<Report> {
    spec.check()?;
    let objects = load_objects(&spec.objects)?;
    // Refuse an object that cannot be pressed as deep as asked before any work: the depth
    // is the range's, so the error names the range.
    for o in &objects {
        let c = make_contact(o.clone(), 0.0, 0.0, 0.0, spec.depth_range.1);
        c.pose(&spec.sensor).map_err(|e| match e {
            GeltipError::InvalidContact { field, reason } if field == "depth" => {
                let (a, b) = spec.depth_range;
                GeltipError::option_value("depth_range", format!("{a}..{b}"), reason)
            }
            other => other,
        })?;
    }
    let backgrounds = spec
        .background
        .as_ref()
        .map(|p| load_backgrounds(p, &spec.sensor))
        .transpose()?;
    let options = spec.options_json(backgrounds.as_ref().map(|b| b.fnv1a64));

    let range = spec.shard.range(spec.count);
    let mut report = Report {
        shard_samples: range.end - range.start,
        ..Report::default()
    };
    let (set, done) = match out {
        Some(dir) => {
            let (set, done) = store::SetDir::open(dir, spec, &options)?;
            (Some(set), done)
        }
        None => (None, BTreeMap::new()),
    };
    report.kept = done.len() as u64;
    let todo: Vec<u64> = range.clone().filter(|k| !done.contains_key(k)).collect();
    let total = todo.len() as u64;
    progress(Progress { done: 0, total });
    if !todo.is_empty() {
        pipeline::render_samples(
            spec,
            out,
            &objects,
            backgrounds.as_ref(),
            &todo,
            &mut report,
            &mut progress,
        )?;
    }
    if let Some(set) = set {
        set.finish(range)?;
    }
    Ok(report)
}
