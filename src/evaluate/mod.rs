//! Scoring contact detectors, any detector, with one fixed protocol: frames with exact labels
//! go to the detector, its detections are matched one to one to the visible contacts
//! ([`matching`]), and the results are summed up ([`metrics`]) and written out ([`report`]).
//!
//! - Frames come from a [`Source`]: a set written by `geltip dataset`, or a [`Suite`]
//!   rendered on the fly while the detector runs (the paper's experiment, the stability
//!   sweep).
//! - A detector is anything that implements [`Detector`]: the built-in localisers
//!   ([`MethodDetector`]), a program reading frames on its stdin ([`CommandDetector`]), a
//!   predictions file written beforehand ([`Predictions`]), or a Python function.
//! - `geltip experiment` and `geltip stability` score their detectors through [`evaluate`]
//!   too: one scoring code for every table geltip prints.
//! - Frames from a real sensor, whose labels say only part of a contact's place (or that
//!   there is none), are scored by [`real`] with the metrics each kind of label allows.

pub mod charts;
pub mod detections;
pub mod detector;
pub mod matching;
pub mod metrics;
pub mod real;
pub mod report;
pub mod source;
pub mod truth;

pub use detections::{parse_line, Found, Given};
pub use detector::{CommandDetector, MethodDetector, Named, Predictions};
pub use matching::{score_sample, Match, SampleScore};
pub use metrics::{ErrorStats, Group, Scored, Summary};
pub use real::{evaluate_real, RealFrame, RealLabel, RealReport, RealSet};
pub use source::{DatasetSource, Source, Suite, SuiteJob, SuitePart};
pub use truth::{region_of, LabelledContact, SampleTruth, Target, REGIONS};

use crate::error::{GeltipError, Result};
use crate::localise::load_frame;
use crate::render::GroundTruth;
use crate::sensor::Sensor;
use image::RgbImage;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// The default matching gate: a detection farther than this (mm, on the finger) from every
/// contact is a false positive.
pub const DEFAULT_GATE_MM: f64 = 3.0;

/// An image a detector may read: a file, pixels in memory, or both (a file is decoded on
/// first use).
#[derive(Debug)]
pub struct Picture {
    path: Option<PathBuf>,
    rgb: OnceLock<RgbImage>,
}

impl Picture {
    /// An image file.
    pub fn file(path: impl Into<PathBuf>) -> Picture {
        Picture {
            path: Some(path.into()),
            rgb: OnceLock::new(),
        }
    }

    /// Pixels, with the file that holds them if one was written.
    pub fn pixels(rgb: RgbImage, path: Option<PathBuf>) -> Picture {
        Picture {
            path,
            rgb: OnceLock::from(rgb),
        }
    }

    /// The file holding the image, if any.
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// The pixels, decoded from the file on first use (the sensor's image size required).
    pub fn rgb(&self, sensor: &Sensor) -> Result<&RgbImage> {
        if let Some(rgb) = self.rgb.get() {
            return Ok(rgb);
        }
        let path = self
            .path
            .as_ref()
            .ok_or_else(|| GeltipError::input("evaluate", "a frame has neither pixels nor file"))?;
        let rgb = load_frame(sensor, path)?;
        Ok(self.rgb.get_or_init(|| rgb))
    }
}

/// One frame handed to the detectors.
#[derive(Debug)]
pub struct Sample {
    pub truth: SampleTruth,
    pub image: Picture,
    /// The same sensor's empty frame, as detectors subtract it.
    pub reference: Arc<Picture>,
    /// The sensor that made the frame (a suite's parts may differ in noise).
    pub sensor: Arc<Sensor>,
    /// Its sensor as a TOML file, when detectors read files.
    pub sensor_file: Option<Arc<PathBuf>>,
    /// The renderer's full labels, for frames rendered on the fly.
    pub rendered: Option<Vec<GroundTruth>>,
}

/// What a detector reads of a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Needs {
    /// Only the sample's index (a predictions file).
    Index,
    /// The pixels.
    Pixels,
    /// Image, reference and sensor as files (another process).
    Files,
}

/// A contact detector: finds the contacts in a frame. `Send`: a run may be handed to
/// another thread (Python releases the GIL while one runs).
pub trait Detector: Send {
    /// The name reports give it.
    fn name(&self) -> String;

    /// What it reads of a frame.
    fn needs(&self) -> Needs {
        Needs::Pixels
    }

    /// Called before the first frame with the indices of every frame to come: a detector
    /// that names frames itself (a predictions file) checks it names these and no others.
    fn start(&mut self, indices: &[u64]) -> Result<()> {
        let _ = indices;
        Ok(())
    }

    /// The frame's detections.
    fn detect(&mut self, sample: &Sample) -> Result<Vec<Found>>;

    /// The detections of several frames, in order, each frame's own result: one frame
    /// after another unless a detector can do better (the built-in localisers run side by
    /// side on rayon's threads).
    fn detect_all(&mut self, samples: &[Sample]) -> Vec<Result<Vec<Found>>> {
        samples.iter().map(|s| self.detect(s)).collect()
    }

    /// Called once every frame has been scored.
    fn finish(&mut self) -> Result<()> {
        Ok(())
    }
}

/// How detections are matched, and where frames go for detectors that read files.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Farthest a detection may be from its contact (mm, on the finger); `None`: any.
    pub gate_mm: Option<f64>,
    /// Where rendered frames, references and sensor files are written for detectors in
    /// other processes.
    pub work_dir: Option<PathBuf>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            gate_mm: Some(DEFAULT_GATE_MM),
            work_dir: None,
        }
    }
}

impl Options {
    /// Refuses a gate no match could pass.
    pub fn check(&self) -> Result<()> {
        match self.gate_mm {
            Some(g) if !(g.is_finite() && g > 0.0) => Err(GeltipError::input(
                "gate_mm",
                format!("must be a positive number of mm, got {g}"),
            )),
            _ => Ok(()),
        }
    }
}

/// One detector's scored frames.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    pub detector: String,
    pub frames: Vec<Scored>,
}

impl Evaluation {
    /// The summary of every frame.
    pub fn summary(&self) -> Summary {
        Summary::of(&self.detector, &self.frames)
    }
}

/// Runs every detector on every frame of `source` and scores it. `each` sees every frame
/// with each detector's detections, in order (after scoring), e.g. to save images or show
/// progress; an error from it stops the run.
pub fn evaluate(
    source: &Source,
    detectors: &mut [&mut dyn Detector],
    options: &Options,
    mut each: impl FnMut(&Sample, &[Scored]) -> Result<()>,
) -> Result<Vec<Evaluation>> {
    options.check()?;
    if detectors.is_empty() {
        return Err(GeltipError::input("evaluate", "no detector to score"));
    }
    let needs = detectors
        .iter()
        .map(|d| d.needs())
        .max()
        .unwrap_or(Needs::Index);
    let mut out: Vec<Evaluation> = detectors
        .iter()
        .map(|d| Evaluation {
            detector: d.name(),
            frames: Vec::new(),
        })
        .collect();
    let indices = source.indices();
    for d in detectors.iter_mut() {
        d.start(&indices)?;
    }
    source.run(needs, options.work_dir.as_deref(), |sample| {
        let mut scored = Vec::with_capacity(detectors.len());
        for d in detectors.iter_mut() {
            let found = d.detect(&sample)?;
            let score = score_sample(&sample.truth, &found, options.gate_mm);
            scored.push(Scored {
                truth: sample.truth.clone(),
                found,
                score,
            });
        }
        each(&sample, &scored)?;
        for (e, s) in out.iter_mut().zip(scored) {
            e.frames.push(s);
        }
        Ok(())
    })?;
    for d in detectors.iter_mut() {
        d.finish()?;
    }
    Ok(out)
}
