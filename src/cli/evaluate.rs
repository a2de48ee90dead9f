//! `geltip evaluate`: score a detector (a predictions file, a program, or a built-in
//! localiser) on a dataset or a suite, and write the report.

use super::{progress, under_flags};
use anyhow::{bail, Result};
use clap::{ArgGroup, Args};
use geltip::evaluate::{CommandDetector, Detector, MethodDetector, Named, Predictions};
use geltip::jobs::evaluate::{self, SUITES};
use geltip::localise::{AreaWindow, DetectorOptions, Method};
use geltip::sensor::Sensor;
use std::path::PathBuf;
use std::time::Duration;

#[derive(Args)]
#[command(group(ArgGroup::new("frames").required(true).args(["dataset", "suite", "real"])))]
#[command(group(ArgGroup::new("detector_kind").required(true).args(["predictions", "detector", "method"])))]
pub struct EvaluateArgs {
    /// A set written by `geltip dataset` (its sensor, labels and images).
    #[arg(long)]
    dataset: Option<PathBuf>,
    /// A suite rendered on the fly: `paper` (the paper's 7 solids x 8 taps) or `stability`
    /// (the stability sweep, with noise, hidden contacts, empty frames and pairs).
    #[arg(long, value_parser = SUITES, requires = "sensor")]
    suite: Option<String>,
    /// A real sensor's labelled frames: a set file (JSON lines: image, reference, contact and
    /// any of pixel, azimuth_deg + centre, point_mm, region, group) or the AllSight set's
    /// labels.json, scored with the metrics each label allows.
    #[arg(long, requires = "sensor")]
    real: Option<PathBuf>,
    /// The sensor a suite is rendered for, or that took the real frames: a preset or a TOML
    /// file.
    #[arg(long, conflicts_with = "dataset")]
    sensor: Option<String>,
    /// Detections written beforehand: JSON lines {"sample": k, "detections": [{"pixel":
    /// [u, v] | "point": [x, y, z], "confidence": c}, ...]}, one per frame.
    #[arg(long)]
    predictions: Option<PathBuf>,
    /// A detector program (run with sh -c): reads one JSON line per frame on stdin
    /// ({"sample", "image", "reference", "sensor"}: paths), answers one line
    /// {"detections": [...]} on stdout.
    #[arg(long)]
    detector: Option<String>,
    /// A built-in localiser: surface, paper or change.
    #[arg(long)]
    method: Option<String>,
    /// The change method's decision threshold, in noise spreads (default 20): lower finds
    /// fainter contacts and calls more drift a contact.
    #[arg(long, requires = "method")]
    threshold: Option<f64>,
    /// The change method's noise floor: the sensor's noise in 8-bit levels (default 1); each
    /// pair's own estimate is used where larger.
    #[arg(long, requires = "method")]
    noise: Option<f64>,
    /// The change and paper methods: the contact region's area on the finger, MIN,MAX in
    /// mm^2 (MAX may be inf; from the sensor model, so the same on any sensor's pixels).
    /// Defaults: change, at least 0.15 mm^2; paper, the paper's 0.012%..0.04% of the picture.
    #[arg(long = "area-mm2", value_name = "MIN,MAX", requires = "method")]
    area_mm2: Option<String>,
    /// Directory for summary.json, per_sample.jsonl, tables.md and the charts.
    #[arg(long)]
    out: PathBuf,
    /// A detection matches a contact no farther than this on the finger, mm.
    #[arg(long, default_value_t = geltip::evaluate::DEFAULT_GATE_MM)]
    gate_mm: f64,
    /// Seconds the detector program may take over one frame.
    #[arg(long, default_value_t = 60.0)]
    timeout_s: f64,
    /// Another run's output directory, to set the two detectors side by side.
    #[arg(long, conflicts_with = "real")]
    compare: Option<PathBuf>,
    /// What the report calls the detector (default: the file, the command or the method).
    #[arg(long)]
    name: Option<String>,
}

/// Scores the detector, writes the report and prints its tables.
pub fn evaluate(args: EvaluateArgs) -> Result<()> {
    if !(args.timeout_s.is_finite() && args.timeout_s > 0.0) {
        bail!(
            "--timeout-s: must be a positive number of seconds, got {}",
            args.timeout_s
        );
    }
    let sensor = args.sensor.as_deref().map(Sensor::load).transpose()?;
    if let (Some(set), Some(sensor)) = (&args.real, &sensor) {
        return real(&args, set, sensor);
    }
    let source = evaluate::source(
        args.dataset.as_deref(),
        args.suite.as_deref(),
        sensor.as_ref(),
    )?;
    let mut detector = Named::new(detector(&args, source.sensor())?, args.name.clone());
    let bar = progress::bar_or_lines("frames")?;
    let outcome = evaluate::run(
        &source,
        &mut detector,
        Some(args.gate_mm),
        Some(&args.out),
        args.compare.as_deref(),
        |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    )?;
    bar.finish_and_clear();
    println!("{}", outcome.tables);
    println!("Wrote {}: {}", args.out.display(), outcome.files.join(", "));
    Ok(())
}

/// The detector the arguments name, for frames of `sensor`.
fn detector(args: &EvaluateArgs, sensor: &Sensor) -> Result<Box<dyn Detector>> {
    Ok(match (&args.predictions, &args.detector, &args.method) {
        (Some(path), _, _) => Box::new(Predictions::read(path, sensor)?),
        (_, Some(command), _) => Box::new(CommandDetector::start(
            command,
            Duration::from_secs_f64(args.timeout_s),
        )?),
        (_, _, Some(method)) => Box::new(
            MethodDetector::with_options(
                Method::from_name(method).map_err(|e| anyhow::anyhow!("--{e}"))?,
                DetectorOptions {
                    threshold: args.threshold,
                    noise: args.noise,
                    area_mm2: args
                        .area_mm2
                        .as_deref()
                        .map(AreaWindow::parse)
                        .transpose()
                        .map_err(under_flags(&[]))?,
                },
            )
            .map_err(under_flags(&[]))?,
        ),
        _ => bail!("name a detector: --predictions, --detector or --method"),
    })
}

/// `--real`: the detector scored on a real sensor's labelled frames.
fn real(args: &EvaluateArgs, set: &std::path::Path, sensor: &Sensor) -> Result<()> {
    let mut detector = Named::new(detector(args, sensor)?, args.name.clone());
    let bar = progress::bar_or_lines("frames")?;
    let outcome = evaluate::run_real(
        set,
        sensor,
        &mut detector,
        Some(&args.out),
        |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    )?;
    bar.finish_and_clear();
    println!("{}", outcome.report.tables());
    println!("Wrote {}: {}", args.out.display(), outcome.files.join(", "));
    Ok(())
}
