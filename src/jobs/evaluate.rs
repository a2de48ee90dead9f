//! `geltip evaluate`: a detector scored on a set from `geltip dataset` or on a suite rendered
//! on the fly (the paper's experiment, the stability sweep), with one protocol
//! ([`crate::evaluate`]), or on a real sensor's labelled frames ([`run_real`]); the report
//! goes to a directory.

use crate::error::{GeltipError, Result};
use crate::evaluate::{
    self, report, DatasetSource, Detector, Evaluation, Options, Source, Suite, Target,
};
use crate::jobs::{experiment, stability};
use crate::sensor::Sensor;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The suites `--suite` names.
pub const SUITES: [&str; 2] = ["paper", "stability"];

/// The suite called `name`, for `sensor`: the paper's 7 x 8 taps, or the stability sweep.
pub fn suite(name: &str, sensor: &Sensor) -> Result<Suite> {
    match name {
        "paper" => experiment::suite(sensor, &experiment::Protocol::default()),
        "stability" => stability::suite(sensor, &stability::Sweep::default_for(sensor)),
        _ => Err(GeltipError::input(
            "suite",
            format!("unknown '{name}', expected one of {}", SUITES.join(", ")),
        )),
    }
}

/// What to score on: a set's directory, or a suite's name with the sensor to render it for.
/// A set holds its own sensor: a sensor given with one is refused, not ignored.
pub fn source(
    dataset: Option<&Path>,
    suite_name: Option<&str>,
    sensor: Option<&Sensor>,
) -> Result<Source> {
    match (dataset, suite_name) {
        (Some(_), None) if sensor.is_some() => Err(GeltipError::input(
            "sensor",
            "a dataset holds its own sensor; name a sensor only with a suite",
        )),
        (Some(dir), None) => Ok(Source::Dataset(DatasetSource::open(
            dir,
            Target::ContactCentre,
        )?)),
        (None, Some(name)) => {
            let sensor = sensor.ok_or_else(|| {
                GeltipError::input(
                    "suite",
                    format!("'{name}' renders its frames: name a sensor"),
                )
            })?;
            Ok(Source::Suite(suite(name, sensor)?))
        }
        _ => Err(GeltipError::input(
            "evaluate",
            "score on either a dataset or a suite (one of them)",
        )),
    }
}

/// What a run gives back.
#[derive(Debug)]
pub struct Outcome {
    pub evaluation: Evaluation,
    /// `summary.json`'s object.
    pub summary: Value,
    /// `tables.md`.
    pub tables: String,
    /// The files written in the output directory.
    pub files: Vec<&'static str>,
}

/// A temporary directory for frames handed to other processes, removed when dropped.
struct WorkDir(PathBuf);

impl WorkDir {
    fn new() -> Result<WorkDir> {
        use std::sync::atomic::{AtomicU64, Ordering};
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let dir = std::env::temp_dir().join(format!(
            "geltip-evaluate-{}-{}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&dir).map_err(|e| GeltipError::io(&dir, e))?;
        Ok(WorkDir(dir))
    }
}

impl Drop for WorkDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Scores `detector` on `source` with matching gate `gate_mm` (`None`: any distance) and,
/// with `out`, writes the report there (beside `compare`'s, another run's output
/// directory). `progress(done, total)` follows the frames. Nothing is written unless every
/// frame scored.
pub fn run(
    source: &Source,
    detector: &mut dyn Detector,
    gate_mm: Option<f64>,
    out: Option<&Path>,
    compare: Option<&Path>,
    mut progress: impl FnMut(usize, usize),
) -> Result<Outcome> {
    let start = Instant::now();
    let compare = compare.map(report::read_summary).transpose()?;
    let work = match detector.needs() {
        evaluate::Needs::Files => Some(WorkDir::new()?),
        _ => None,
    };
    let options = Options {
        gate_mm,
        work_dir: work.as_ref().map(|w| w.0.clone()),
    };
    let total = source.len();
    let mut done = 0;
    let mut evaluations = evaluate::evaluate(source, &mut [detector], &options, |_, _| {
        done += 1;
        progress(done, total);
        Ok(())
    })?;
    let evaluation = evaluations.remove(0);
    let run = report::RunInfo {
        source: source.describe(),
        sensor: source.sensor().name.clone(),
        gate_mm,
        seconds: start.elapsed().as_secs_f64(),
    };
    let summary = report::summary_json(&evaluation.summary(), &run);
    let mut summaries = vec![summary.clone()];
    summaries.extend(compare.clone());
    let tables = report::tables_markdown(&summaries);
    let files = match out {
        Some(dir) => report::write(dir, &evaluation, &run, source.sensor(), compare.as_ref())?,
        None => Vec::new(),
    };
    Ok(Outcome {
        evaluation,
        summary,
        tables,
        files,
    })
}

/// What [`run_real`] gives back: the report and the files written.
#[derive(Debug)]
pub struct RealOutcome {
    pub report: evaluate::RealReport,
    pub files: Vec<String>,
}

/// Scores `detector` on the real labelled frames of `set` (a set file, or the AllSight
/// set's `labels.json`) taken with `sensor`, and with `out` writes the report there.
/// `progress(done, total)` follows the frames. Nothing is written unless every frame scored.
pub fn run_real(
    set: &Path,
    sensor: &Sensor,
    detector: &mut dyn Detector,
    out: Option<&Path>,
    progress: impl FnMut(usize, usize),
) -> Result<RealOutcome> {
    let frames = evaluate::RealSet::read(set)?;
    let work = match detector.needs() {
        evaluate::Needs::Files => Some(WorkDir::new()?),
        _ => None,
    };
    let sensor_file = work
        .as_ref()
        .map(|w| evaluate::source::write_sensor(&w.0, "sensor.toml", sensor))
        .transpose()?;
    let sensor = std::sync::Arc::new(sensor.clone());
    let report = evaluate::evaluate_real(&frames, &sensor, sensor_file, detector, progress)?;
    let files = match out {
        Some(dir) => report.write(&frames, dir)?,
        None => Vec::new(),
    };
    Ok(RealOutcome { report, files })
}
