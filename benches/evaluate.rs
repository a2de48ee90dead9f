//! Evaluation speed: `cargo bench --bench evaluate [-- --frames N]`. Prints a table:
//! - scoring alone (parse a predictions line, match, summarise), in predictions/s (target
//!   >= 50 000);
//! - a predictions file on a rendered set, end to end (read, check, score, report);
//! - geltip's own cost per frame with a detector program (`--detector`): the run's wall
//!   time less the same program's time over the same requests without geltip (target
//!   <= 2 ms a frame);
//! - a suite rendered while a slow program detects: the wall time against rendering alone
//!   and detecting alone (rendering overlaps the detector when the wall time is near the
//!   larger of the two, not their sum).

use geltip::evaluate::{
    self, parse_line, score_sample, CommandDetector, DatasetSource, Detector, LabelledContact,
    Options, Predictions, SampleTruth, Scored, Source, Summary, Target,
};
use geltip::host_speed::HostSpeed;
use geltip::jobs::{dataset, evaluate as job};
use geltip::sensor::Sensor;
use glam::{DVec2, DVec3};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn main() -> anyhow::Result<()> {
    geltip::memory::keep_freed_memory();
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    let args: Vec<String> = std::env::args().collect();
    let frames: u64 = args
        .windows(2)
        .find(|w| w[0] == "--frames")
        .map(|w| w[1].parse())
        .transpose()?
        .unwrap_or(512);
    let host = HostSpeed::measure();
    println!(
        "geltip evaluate speed; host loop {:.2} ms on one core, {:.2} ms on all",
        host.one_core_ms, host.all_cores_ms
    );
    println!("| what | frames | rate | per frame | target |");
    println!("|---|---|---|---|---|");
    scoring_alone()?;
    let dir = std::env::temp_dir().join(format!("geltip-bench-evaluate-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let set = make_set(&dir, frames)?;
    predictions_file(&dir, &set)?;
    detector_program(&dir, &set)?;
    overlap()?;
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// Parsing, matching and summing up predictions of frames of one to three contacts.
fn scoring_alone() -> anyhow::Result<()> {
    let sensor = Sensor::preset("paper")?;
    let n = 200_000usize;
    let mut lines = Vec::with_capacity(n / 2);
    let mut truths = Vec::with_capacity(n / 2);
    let mut predictions = 0;
    for k in 0..n / 2 {
        let contacts: Vec<LabelledContact> = (0..1 + k % 3)
            .map(|j| LabelledContact {
                target: DVec3::new(7.5, 0.0, 10.0 + j as f64 * 4.0),
                pixel: Some(DVec2::new(400.0, 240.0 + j as f64)),
                visible: true,
                object: "sphere".into(),
                depth_mm: 1.0,
                s_mm: 15.0,
                azimuth_deg: 0.0,
                region: "side",
            })
            .collect();
        let detections: Vec<String> = (0..1 + (k + 1) % 3)
            .map(|j| {
                format!(
                    r#"{{"point": [7.5, 0.1, {}], "confidence": 0.{j}5}}"#,
                    10.2 + j as f64 * 4.0
                )
            })
            .collect();
        predictions += detections.len();
        lines.push(format!(
            r#"{{"sample": {k}, "detections": [{}]}}"#,
            detections.join(", ")
        ));
        truths.push(SampleTruth {
            index: k as u64,
            contacts,
        });
    }
    let start = Instant::now();
    let mut frames = Vec::with_capacity(lines.len());
    for (line, truth) in lines.iter().zip(truths) {
        let (_, found) = parse_line(&sensor, line, "line")?;
        let score = score_sample(&truth, &found, Some(3.0));
        frames.push(Scored {
            truth,
            found,
            score,
        });
    }
    let summary = Summary::of("bench", &frames);
    let t = start.elapsed().as_secs_f64();
    std::hint::black_box(summary);
    let rate = predictions as f64 / t;
    println!(
        "| scoring alone: parse, match, summarise | {} | {:.0} predictions/s | {:.1} µs | >= 50 000 predictions/s: {} |",
        frames.len(),
        rate,
        1e6 * t / frames.len() as f64,
        if rate >= 50_000.0 { "met" } else { "NOT met" }
    );
    Ok(())
}

/// A set of `frames` samples (a tenth empty, one to two contacts).
fn make_set(dir: &Path, frames: u64) -> anyhow::Result<PathBuf> {
    let set = dir.join("set");
    let mut spec = dataset::Spec::new("paper", Sensor::preset("paper")?, frames, 1);
    spec.empty_fraction = 0.1;
    spec.contacts_per_sample = (1, 2);
    dataset::run(&spec, Some(&set), |_| {})?;
    Ok(set)
}

/// The labels' contact centres as a predictions file (the oracle).
fn oracle_file(dir: &Path, set: &Path) -> anyhow::Result<(PathBuf, usize)> {
    let mut text = String::new();
    let mut count = 0;
    for line in std::fs::read_to_string(set.join(dataset::LABELS))?.lines() {
        let v: serde_json::Value = serde_json::from_str(line)?;
        let found: Vec<serde_json::Value> = v["contacts"]
            .as_array()
            .into_iter()
            .flatten()
            .filter(|c| !c["contact_centre"].is_null())
            .map(|c| serde_json::json!({"point": c["contact_centre"], "confidence": 0.9}))
            .collect();
        count += found.len();
        text.push_str(&serde_json::json!({"sample": v["index"], "detections": found}).to_string());
        text.push('\n');
    }
    let path = dir.join("oracle.jsonl");
    std::fs::write(&path, text)?;
    Ok((path, count))
}

fn predictions_file(dir: &Path, set: &Path) -> anyhow::Result<()> {
    let (file, count) = oracle_file(dir, set)?;
    let source = Source::Dataset(DatasetSource::open(set, Target::ContactCentre)?);
    let start = Instant::now();
    let mut detector = Predictions::read(&file, source.sensor())?;
    let out = job::run(
        &source,
        &mut detector,
        Some(3.0),
        Some(&dir.join("report")),
        None,
        |_, _| {},
    )?;
    let t = start.elapsed().as_secs_f64();
    let n = out.evaluation.frames.len();
    println!(
        "| predictions file on a set: read, check, score, write the report | {n} | {:.0} predictions/s | {:.2} ms | – |",
        count as f64 / t,
        1e3 * t / n as f64
    );
    Ok(())
}

/// The shell loop that answers every request with no detections.
const ECHO: &str = r#"while IFS= read -r request; do echo '{"detections": []}'; done"#;

/// geltip's cost per frame with a program: the run's time less the program's own.
fn detector_program(dir: &Path, set: &Path) -> anyhow::Result<()> {
    let source = Source::Dataset(DatasetSource::open(set, Target::ContactCentre)?);
    let n = source.len();
    let mut best = f64::INFINITY;
    let mut alone = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        let mut detector = CommandDetector::start(ECHO, Duration::from_secs(10))?;
        job::run(&source, &mut detector, Some(3.0), None, None, |_, _| {})?;
        best = best.min(start.elapsed().as_secs_f64());
        alone = alone.min(program_alone(dir, set, n)?);
    }
    // The run's time per frame bounds geltip's own cost from above (it includes the
    // program's); the difference estimates it.
    let (per_frame, own) = (best / n as f64, (best - alone).max(0.0) / n as f64);
    println!(
        "| --detector on a set: run {best:.3} s, the program alone {alone:.3} s | {n} | {:.0} frames/s | {:.3} ms (geltip's own about {:.3} ms) | <= 2 ms: {} |",
        n as f64 / best,
        1e3 * per_frame,
        1e3 * own,
        if per_frame <= 2e-3 { "met" } else { "NOT met" }
    );
    Ok(())
}

/// The echo program over `n` requests like geltip's, fed from a file, in seconds.
fn program_alone(dir: &Path, set: &Path, n: usize) -> anyhow::Result<f64> {
    let requests = dir.join("requests.jsonl");
    let mut text = String::new();
    for k in 0..n {
        let line = serde_json::json!({
            "sample": k,
            "image": set.join(format!("images/{k:06}.png")),
            "reference": set.join("reference.png"),
            "sensor": dir.join("sensor.toml"),
        });
        text.push_str(&line.to_string());
        text.push('\n');
    }
    std::fs::write(&requests, text)?;
    let start = Instant::now();
    let status = Command::new("sh")
        .arg("-c")
        .arg(ECHO)
        .stdin(std::fs::File::open(&requests)?)
        .stdout(Stdio::null())
        .status()?;
    anyhow::ensure!(status.success(), "the echo program failed");
    Ok(start.elapsed().as_secs_f64())
}

/// A detector that takes `ms` per frame, in this process (no pipe), for the overlap row.
struct Slow(Duration);

impl Detector for Slow {
    fn name(&self) -> String {
        "slow".into()
    }

    fn detect(&mut self, _: &evaluate::Sample) -> geltip::Result<Vec<evaluate::Found>> {
        std::thread::sleep(self.0);
        Ok(Vec::new())
    }
}

/// The paper suite rendered while a detector taking a fixed time per frame runs: the time
/// from the first frame to the last (the renderer's start-up before it is not overlapped).
fn overlap() -> anyhow::Result<()> {
    let sensor = Sensor::preset("paper")?;
    let source = Source::Suite(job::suite("paper", &sensor)?);
    let n = source.len();
    let options = Options {
        gate_mm: Some(3.0),
        work_dir: None,
    };
    let time = |d: Duration| -> anyhow::Result<f64> {
        let mut first = None;
        evaluate::evaluate(&source, &mut [&mut Slow(d)], &options, |_, _| {
            first.get_or_insert_with(Instant::now);
            Ok(())
        })?;
        Ok(first.map_or(0.0, |t| t.elapsed().as_secs_f64()))
    };
    let render = time(Duration::ZERO)?;
    let per_frame = Duration::from_secs_f64(render / (n - 1) as f64);
    let detect = per_frame.as_secs_f64() * (n - 1) as f64;
    let both = time(per_frame)?;
    println!(
        "| suite paper, first frame to last: rendering alone {render:.2} s, a detector alone {detect:.2} s, both {both:.2} s | {n} | {:.0} frames/s | {:.2} ms | overlapped: both near max({render:.2}, {detect:.2}), not the sum {:.2} |",
        (n - 1) as f64 / both,
        1e3 * both / (n - 1) as f64,
        render + detect
    );
    Ok(())
}
