//! The detectors geltip runs itself: its own localisers, a program in another process that
//! reads frames on its stdin and answers on its stdout, and a predictions file written
//! beforehand.

use super::detections::{parse_line, Found};
use super::{Detector, Needs, Sample};
use crate::error::{GeltipError, Result};
use crate::localise::DetectorOptions;
use crate::localise::{Localiser, Method};
use crate::sensor::Sensor;
use rayon::prelude::*;
use serde_json::json;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// One of geltip's localisers, as a detector. The per-pixel table of the surface method is
/// built once per sensor.
pub struct MethodDetector {
    method: Method,
    /// The detectors' options, where not their defaults.
    options: DetectorOptions,
    localisers: Vec<Localiser>,
}

impl MethodDetector {
    pub fn new(method: Method) -> MethodDetector {
        MethodDetector {
            method,
            options: DetectorOptions::default(),
            localisers: Vec::new(),
        }
    }

    /// The method with `options` (the change method's decision threshold and the sensor's
    /// noise, the area limits on the finger); refused where the method does not take one, or
    /// unless the threshold and noise are finite and > 0.
    pub fn with_options(method: Method, options: DetectorOptions) -> Result<MethodDetector> {
        options.check(method)?;
        Ok(MethodDetector {
            options,
            ..MethodDetector::new(method)
        })
    }

    /// The frame's detections, with its sensor's localiser already made ([`Self::localiser`]).
    fn detect_with(&self, sample: &Sample) -> Result<Vec<Found>> {
        let sensor = &sample.sensor;
        let localiser = self
            .localisers
            .iter()
            .find(|l| l.sensor.config == sensor.config)
            .ok_or_else(|| GeltipError::input("evaluate", "no localiser for the frame's sensor"))?;
        let reference = sample.reference.rgb(sensor)?;
        let image = sample.image.rgb(sensor)?;
        let d = localiser.localise_with(reference, image, self.method, &self.options)?;
        Ok(Found::from_detection(&d))
    }

    /// The localiser of `sensor` (a suite's parts may differ in noise, not in geometry, but
    /// a localiser is kept per sensor all the same).
    fn localiser(&mut self, sensor: &Sensor) -> &Localiser {
        let k = match self
            .localisers
            .iter()
            .position(|l| l.sensor.config == sensor.config)
        {
            Some(k) => k,
            None => {
                self.localisers.push(Localiser::new(sensor));
                self.localisers.len() - 1
            }
        };
        &self.localisers[k]
    }
}

impl Detector for MethodDetector {
    fn name(&self) -> String {
        match self.options.any() {
            true => format!("{} ({})", self.method.name(), self.options.describe()),
            false => self.method.name().to_string(),
        }
    }

    fn detect(&mut self, sample: &Sample) -> Result<Vec<Found>> {
        self.localiser(&sample.sensor);
        self.detect_with(sample)
    }

    fn detect_all(&mut self, samples: &[Sample]) -> Vec<Result<Vec<Found>>> {
        // Every sensor's localiser made first; then the frames side by side.
        for sample in samples {
            self.localiser(&sample.sensor);
        }
        let me = &*self;
        samples.par_iter().map(|s| me.detect_with(s)).collect()
    }
}

/// How long a detector program may take over one frame, by default.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(60);

/// A detector program started once: one JSON line per frame on its stdin
/// (`{"sample", "image", "reference", "sensor"}`, paths), one line back on its stdout
/// (`{"detections": [...]}`); end of its stdin ends it. Its stderr is the caller's.
pub struct CommandDetector {
    command: String,
    child: Child,
    stdin: Option<ChildStdin>,
    lines: mpsc::Receiver<std::io::Result<String>>,
    timeout: Duration,
}

impl CommandDetector {
    /// Starts `command` with the shell (`sh -c`).
    pub fn start(command: &str, timeout: Duration) -> Result<CommandDetector> {
        if command.trim().is_empty() {
            return Err(GeltipError::input("detector", "the command is empty"));
        }
        let mut child = Command::new("sh")
            .arg("-c")
            .arg(command)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(|e| GeltipError::input("detector", format!("cannot start sh -c: {e}")))?;
        let stdin = child.stdin.take();
        let stdout = child.stdout.take();
        let (tx, lines) = mpsc::channel();
        if let Some(out) = stdout {
            // Its answers are read on a thread of their own, so a silent detector times out.
            std::thread::spawn(move || {
                for line in BufReader::new(out).lines() {
                    if tx.send(line).is_err() {
                        return;
                    }
                }
            });
        }
        Ok(CommandDetector {
            command: command.to_string(),
            child,
            stdin,
            lines,
            timeout,
        })
    }

    /// What became of the program, for an error: its exit status, or that it still runs.
    fn status(&mut self) -> String {
        // A program that closed its output may take a moment to exit.
        let until = Instant::now() + Duration::from_millis(500);
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => return format!("it exited with {status}"),
                Ok(None) if Instant::now() < until => {
                    std::thread::sleep(Duration::from_millis(10));
                }
                Ok(None) => return "it is still running".into(),
                Err(e) => return format!("its status is unknown: {e}"),
            }
        }
    }

    fn fail(&mut self, k: u64, reason: impl std::fmt::Display) -> GeltipError {
        let status = self.status();
        GeltipError::input(
            format!("detector '{}', sample {k}", self.command),
            format!("{reason} ({status})"),
        )
    }
}

impl Detector for CommandDetector {
    fn name(&self) -> String {
        self.command.clone()
    }

    fn needs(&self) -> Needs {
        Needs::Files
    }

    fn detect(&mut self, sample: &Sample) -> Result<Vec<Found>> {
        let k = sample.truth.index;
        let path = |p: Option<&Path>| p.map(|p| p.display().to_string());
        let request = json!({
            "sample": k,
            "image": path(sample.image.path()),
            "reference": path(sample.reference.path()),
            "sensor": path(sample.sensor_file.as_deref().map(PathBuf::as_path)),
        });
        let sent = match self.stdin.as_mut() {
            Some(stdin) => writeln!(stdin, "{request}").and_then(|()| stdin.flush()),
            None => Err(std::io::Error::other("its stdin is closed")),
        };
        if let Err(e) = sent {
            return Err(self.fail(k, format!("cannot send the frame: {e}")));
        }
        let line = match self.lines.recv_timeout(self.timeout) {
            Ok(Ok(line)) => line,
            Ok(Err(e)) => return Err(self.fail(k, format!("cannot read its answer: {e}"))),
            Err(mpsc::RecvTimeoutError::Timeout) => {
                let _ = self.child.kill();
                return Err(self.fail(
                    k,
                    format!(
                        "no answer within {} s; stopped it",
                        self.timeout.as_secs_f64()
                    ),
                ));
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(self.fail(k, "it closed its output without answering"))
            }
        };
        let (named, found) = parse_line(&sample.sensor, &line, "its answer")
            .map_err(|e| self.fail(k, shorten(&e.to_string())))?;
        if let Some(other) = named.filter(|&n| n != k) {
            return Err(self.fail(k, format!("its answer names sample {other}")));
        }
        Ok(found)
    }

    fn finish(&mut self) -> Result<()> {
        // End of its stdin ends it; one that does not end in time is stopped.
        self.stdin = None;
        let until = Instant::now() + Duration::from_secs(5);
        while Instant::now() < until {
            if let Ok(Some(_)) = self.child.try_wait() {
                return Ok(());
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
        Ok(())
    }
}

impl Drop for CommandDetector {
    fn drop(&mut self) {
        self.stdin = None;
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
        }
        let _ = self.child.wait();
    }
}

/// At most 300 characters of a message (a garbage answer can be a megabyte long).
fn shorten(text: &str) -> String {
    match text.char_indices().nth(300) {
        Some((i, _)) => format!("{}...", &text[..i]),
        None => text.to_string(),
    }
}

/// A predictions file: JSON lines `{"sample": k, "detections": [...]}`, one per frame,
/// checked whole when read.
pub struct Predictions {
    path: PathBuf,
    /// Each sample's detections and the line that gave them.
    by_sample: BTreeMap<u64, (usize, Vec<Found>)>,
}

impl Predictions {
    /// Reads and checks `path` against `sensor`'s images.
    pub fn read(path: &Path, sensor: &Sensor) -> Result<Predictions> {
        let text = std::fs::read_to_string(path).map_err(|e| GeltipError::io(path, e))?;
        let mut by_sample = BTreeMap::new();
        for (n, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let what = format!("{}: line {}", path.display(), n + 1);
            let (sample, found) = parse_line(sensor, line, &what)?;
            let k = sample.ok_or_else(|| {
                GeltipError::input(&what, "sample: required (the sample's index in the set)")
            })?;
            if let Some((first, _)) = by_sample.insert(k, (n + 1, found)) {
                return Err(GeltipError::input(
                    &what,
                    format!("sample {k} again (first on line {first})"),
                ));
            }
        }
        Ok(Predictions {
            path: path.to_path_buf(),
            by_sample,
        })
    }

    /// The detections it gives frame `k` (none when it names no such frame).
    pub fn detections_of(&self, k: u64) -> Vec<Found> {
        self.by_sample
            .get(&k)
            .map(|(_, found)| found.clone())
            .unwrap_or_default()
    }

    /// How many frames it gives detections for.
    pub fn len(&self) -> usize {
        self.by_sample.len()
    }

    /// Whether it holds no line.
    pub fn is_empty(&self) -> bool {
        self.by_sample.is_empty()
    }
}

impl Detector for Predictions {
    fn name(&self) -> String {
        self.path.display().to_string()
    }

    fn needs(&self) -> Needs {
        Needs::Index
    }

    fn start(&mut self, indices: &[u64]) -> Result<()> {
        let set: std::collections::BTreeSet<u64> = indices.iter().copied().collect();
        if let Some((k, (line, _))) = self.by_sample.iter().find(|(k, _)| !set.contains(k)) {
            return Err(GeltipError::input(
                format!("{}: line {line}", self.path.display()),
                format!("sample {k} is not in the set ({} samples)", set.len()),
            ));
        }
        match indices.iter().find(|k| !self.by_sample.contains_key(k)) {
            Some(k) => Err(GeltipError::input(
                self.path.display().to_string(),
                format!(
                    "no line for sample {k} ({} of {} samples have none); a frame with nothing found is {{\"sample\": {k}, \"detections\": []}}",
                    indices.iter().filter(|k| !self.by_sample.contains_key(k)).count(),
                    indices.len()
                ),
            )),
            None => Ok(()),
        }
    }

    fn detect(&mut self, sample: &Sample) -> Result<Vec<Found>> {
        let k = sample.truth.index;
        self.by_sample
            .get(&k)
            .map(|(_, found)| found.clone())
            .ok_or_else(|| {
                GeltipError::input(
                    self.path.display().to_string(),
                    format!("no line for sample {k}"),
                )
            })
    }
}

/// A detector under a name of the caller's choosing (reports and comparisons show it).
pub struct Named<'a> {
    inner: Box<dyn Detector + 'a>,
    name: Option<String>,
}

impl<'a> Named<'a> {
    /// `inner`, called `name` when given.
    pub fn new(inner: Box<dyn Detector + 'a>, name: Option<String>) -> Named<'a> {
        Named { inner, name }
    }
}

impl Detector for Named<'_> {
    fn name(&self) -> String {
        self.name.clone().unwrap_or_else(|| self.inner.name())
    }

    fn needs(&self) -> Needs {
        self.inner.needs()
    }

    fn detect(&mut self, sample: &Sample) -> Result<Vec<Found>> {
        self.inner.detect(sample)
    }

    fn detect_all(&mut self, samples: &[Sample]) -> Vec<Result<Vec<Found>>> {
        self.inner.detect_all(samples)
    }

    fn start(&mut self, indices: &[u64]) -> Result<()> {
        self.inner.start(indices)
    }

    fn finish(&mut self) -> Result<()> {
        self.inner.finish()
    }
}
