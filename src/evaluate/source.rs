//! Where frames come from: a set written by `geltip dataset` (its images, labels and empty
//! frame), or a suite of contacts rendered on the fly, the rendering running on a thread of
//! its own while the detectors work on the frames before.

use super::truth::{SampleTruth, Target};
use super::{Needs, Picture, Sample};
use crate::error::{GeltipError, Result};
use crate::jobs::dataset::{self, LABELS, MANIFEST};
use crate::object::Object;
use crate::output;
use crate::render::gpu::Renderer;
use crate::render::pool::RenderPool;
use crate::render::{Frame, GroundTruth, Press};
use crate::sensor::Sensor;
use image::RgbImage;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Frames to score.
pub enum Source {
    Dataset(DatasetSource),
    Suite(Suite),
}

impl Source {
    /// Frames and their labels, delivered in order to `deliver`. With `Needs::Files` the
    /// images, references and sensor are files; rendered ones are written under `files`.
    pub(super) fn run(
        &self,
        needs: Needs,
        files: Option<&Path>,
        deliver: impl FnMut(Sample) -> Result<()>,
    ) -> Result<()> {
        let files = match (needs, files) {
            (Needs::Files, None) => {
                return Err(GeltipError::input(
                    "evaluate",
                    "a detector reads files but no directory was given for them",
                ))
            }
            (Needs::Files, Some(dir)) => Some(dir),
            _ => None,
        };
        match self {
            Source::Dataset(set) => set.run(needs, files, deliver),
            Source::Suite(suite) => suite.run(needs, files, deliver),
        }
    }

    /// How many frames it holds.
    pub fn len(&self) -> usize {
        match self {
            Source::Dataset(set) => set.entries.len(),
            Source::Suite(suite) => suite.len(),
        }
    }

    /// Whether it holds no frame.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The indices of its frames, in order.
    pub fn indices(&self) -> Vec<u64> {
        match self {
            Source::Dataset(set) => set.entries.iter().map(|(t, _)| t.index).collect(),
            Source::Suite(suite) => (0..suite.len() as u64).collect(),
        }
    }

    /// The sensor of its first frame.
    pub fn sensor(&self) -> &Sensor {
        match self {
            Source::Dataset(set) => &set.sensor,
            Source::Suite(suite) => &suite.parts[0].sensor,
        }
    }

    /// How reports name it.
    pub fn describe(&self) -> String {
        match self {
            Source::Dataset(set) => format!("dataset {}", set.dir.display()),
            Source::Suite(suite) => format!("suite {}", suite.name),
        }
    }
}

/// Writes `sensor` as a TOML file `name` in `dir`, for detectors in other processes.
pub(crate) fn write_sensor(dir: &Path, name: &str, sensor: &Sensor) -> Result<Arc<PathBuf>> {
    let text = toml::to_string(&sensor.config)
        .map_err(|e| GeltipError::input(format!("sensor '{}'", sensor.name), e.to_string()))?;
    let path = dir.join(name);
    output::write_atomic(&path, text.as_bytes())?;
    Ok(Arc::new(path))
}

/// A complete set from `geltip dataset`.
pub struct DatasetSource {
    pub dir: PathBuf,
    pub sensor: Arc<Sensor>,
    /// Each sample's labels and image file, by index.
    entries: Vec<(SampleTruth, PathBuf)>,
    /// The empty frame of each sample that names its own (a set on a folder of
    /// backgrounds), by index; the others take the set's.
    references: BTreeMap<u64, PathBuf>,
}

impl DatasetSource {
    /// Reads the set in `dir`: its manifest, its sensor and every label line, checked.
    pub fn open(dir: &Path, target: Target) -> Result<DatasetSource> {
        let what = |file: &str| dir.join(file).display().to_string();
        if let Some(holder) = output::DirLock::holder(dir)? {
            return Err(GeltipError::input(
                dir.display().to_string(),
                format!("is being written by another run ({holder}); score it once that ends"),
            ));
        }
        let manifest: Value = read_json(&dir.join(MANIFEST))?;
        let options = &manifest["options"];
        let config = serde_json::from_value(options["sensor_config"].clone()).map_err(|e| {
            GeltipError::input(what(MANIFEST), format!("options.sensor_config: {e}"))
        })?;
        let name = options["sensor"].as_str().unwrap_or("dataset sensor");
        let sensor = Arc::new(Sensor::from_config(name, config)?);
        // The samples the set's labels are of: its shard's range, else its count.
        let range = &manifest["shard_range"];
        let samples = match (range[0].as_u64(), range[1].as_u64()) {
            (Some(a), Some(b)) if b >= a => Some(a..b),
            _ => options["count"].as_u64().map(|n| 0..n),
        };
        let mut entries = Vec::new();
        let mut references = BTreeMap::new();
        for line in dataset::read_labels(&dir.join(LABELS))? {
            let (index, v) = (line.index, &line.value);
            let at = format!("{}: line {}", what(LABELS), line.line);
            if let Some(r) = samples.as_ref().filter(|r| !r.contains(&index)) {
                return Err(GeltipError::input(
                    &at,
                    format!(
                        "index: sample {index} is not one of the set's samples {}..{}",
                        r.start, r.end
                    ),
                ));
            }
            let image = v["image"]
                .as_str()
                .ok_or_else(|| GeltipError::input(&at, "image: required, a file name"))?;
            let truth = SampleTruth::from_json(&sensor, index, v, target, &at)?;
            entries.push((truth, dir.join(image)));
            if let Some(r) = v.get("reference").filter(|r| !r.is_null()) {
                let r = r
                    .as_str()
                    .ok_or_else(|| GeltipError::input(&at, "reference: a file name"))?;
                references.insert(index, dir.join(r));
            }
        }
        let expected = samples.map_or(entries.len() as u64, |r| r.end - r.start);
        if entries.len() as u64 != expected {
            return Err(GeltipError::input(
                dir.display().to_string(),
                format!(
                    "holds {} of its {expected} samples: finish it first (rerun its dataset command)",
                    entries.len()
                ),
            ));
        }
        entries.sort_by_key(|(t, _)| t.index);
        Ok(DatasetSource {
            dir: dir.to_path_buf(),
            sensor,
            entries,
            references,
        })
    }

    fn run(
        &self,
        needs: Needs,
        files: Option<&Path>,
        mut deliver: impl FnMut(Sample) -> Result<()>,
    ) -> Result<()> {
        let reference = match needs {
            Needs::Index => Picture::pixels(RgbImage::new(1, 1), None),
            _ => self.reference(files)?,
        };
        let reference = Arc::new(reference);
        let sensor_file = files
            .map(|dir| write_sensor(dir, "sensor.toml", &self.sensor))
            .transpose()?;
        // Images are decoded a few frames ahead, on a thread of their own.
        let (tx, rx) = std::sync::mpsc::sync_channel::<Result<Sample>>(4);
        std::thread::scope(|scope| {
            // Moves the sender in: the reading thread's end closes the channel.
            scope.spawn(move || {
                let mut own: BTreeMap<&Path, Arc<Picture>> = BTreeMap::new();
                for (truth, path) in &self.entries {
                    let image = Picture::file(path);
                    let reference = match self.references.get(&truth.index) {
                        Some(r) => own
                            .entry(r.as_path())
                            .or_insert_with(|| Arc::new(Picture::file(r)))
                            .clone(),
                        None => reference.clone(),
                    };
                    let loaded = match needs {
                        Needs::Pixels => image.rgb(&self.sensor).map(|_| ()),
                        _ if !path.is_file() => Err(GeltipError::input(
                            path.display().to_string(),
                            "the set's image is missing",
                        )),
                        _ => Ok(()),
                    };
                    let sample = loaded.map(|()| Sample {
                        truth: truth.clone(),
                        image,
                        reference,
                        sensor: self.sensor.clone(),
                        sensor_file: sensor_file.clone(),
                        rendered: None,
                    });
                    if tx.send(sample).is_err() {
                        return;
                    }
                }
            });
            // Dropping the receiver on an error stops the reading thread.
            let rx = rx;
            for sample in rx.iter() {
                deliver(sample?)?;
            }
            Ok(())
        })
    }

    /// The set's empty frame: its `reference.png`, or rendered as the set's options say.
    fn reference(&self, files: Option<&Path>) -> Result<Picture> {
        let path = self.dir.join(dataset::REFERENCE);
        if path.is_file() {
            return Ok(Picture::file(path));
        }
        let rgb = dataset::reference_of_set(&self.dir)?;
        let written = match files {
            Some(dir) => {
                let path = dir.join(dataset::REFERENCE);
                output::write_png_rgb8(&path, rgb.width(), rgb.height(), rgb.as_raw())?;
                Some(path)
            }
            None => None,
        };
        Ok(Picture::pixels(rgb, written))
    }
}

fn read_json(path: &Path) -> Result<Value> {
    let text = std::fs::read_to_string(path).map_err(|e| GeltipError::io(path, e))?;
    serde_json::from_str(&text)
        .map_err(|e| GeltipError::input(path.display().to_string(), format!("not valid JSON: {e}")))
}

/// What a suite renders, in order, on one renderer.
#[derive(Debug, Clone)]
pub enum SuiteJob {
    /// Presses rendered a frame each, in one submission.
    Batch(Vec<Press>),
    /// Presses rendered together in one frame.
    Scene(Vec<Press>),
    /// A frame with nothing pressed (fresh noise where the sensor has noise).
    Empty,
}

/// Frames of one sensor, rendered in order by one renderer after its empty frame (the
/// reference detectors get): the order fixes each frame's noise.
#[derive(Debug, Clone)]
pub struct SuitePart {
    pub sensor: Sensor,
    /// The point each contact is scored against.
    pub target: Target,
    pub jobs: Vec<SuiteJob>,
}

impl SuitePart {
    fn frames(&self) -> usize {
        self.jobs
            .iter()
            .map(|j| match j {
                SuiteJob::Batch(p) => p.len(),
                SuiteJob::Scene(_) | SuiteJob::Empty => 1,
            })
            .sum()
    }

    fn objects(&self) -> Vec<Arc<Object>> {
        let mut objects: Vec<Arc<Object>> = Vec::new();
        for job in &self.jobs {
            if let SuiteJob::Batch(p) | SuiteJob::Scene(p) = job {
                for press in p {
                    if !objects.iter().any(|o| Arc::ptr_eq(o, &press.object)) {
                        objects.push(press.object.clone());
                    }
                }
            }
        }
        objects
    }
}

/// Contacts rendered on the fly: the frames are numbered from 0 across the parts.
#[derive(Debug, Clone)]
pub struct Suite {
    pub name: String,
    pub parts: Vec<SuitePart>,
}

impl Suite {
    /// Frames in the suite.
    pub fn len(&self) -> usize {
        self.parts.iter().map(SuitePart::frames).sum()
    }

    /// Whether the suite holds no frame.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn run(
        &self,
        needs: Needs,
        files: Option<&Path>,
        mut deliver: impl FnMut(Sample) -> Result<()>,
    ) -> Result<()> {
        if self.parts.is_empty() {
            return Err(GeltipError::input(
                format!("suite {}", self.name),
                "has no parts",
            ));
        }
        let mut index = 0u64;
        for (p, part) in self.parts.iter().enumerate() {
            let sensor = Arc::new(part.sensor.clone());
            let sensor_file = files
                .map(|dir| write_sensor(dir, &format!("sensor-{p}.toml"), &sensor))
                .transpose()?;
            let mut pool = RenderPool::start(&part.sensor, 1, &part.objects())?;
            // The reference is the part's first frame, as a camera's first empty frame.
            let reference = pool.streams_mut()[0].render_empty()?.to_rgb();
            let reference_file = files.map(|d| d.join(format!("reference-{p}.png")));
            let reference = Arc::new(picture(reference, reference_file)?);
            // Each job with the index of its first frame, for the files' names.
            let mut jobs = Vec::with_capacity(part.jobs.len());
            let mut next = index;
            for job in &part.jobs {
                jobs.push((next, job));
                next += match job {
                    SuiteJob::Batch(p) => p.len() as u64,
                    _ => 1,
                };
            }
            let render = |renderer: &mut Renderer, (k, job): (u64, &SuiteJob)| {
                let mut out = Vec::new();
                for (i, (frame, truths)) in render_job(renderer, job)?.into_iter().enumerate() {
                    let file = match (needs, files) {
                        (Needs::Files, Some(d)) => {
                            Some(d.join(format!("frame-{:06}.png", k + i as u64)))
                        }
                        _ => None,
                    };
                    out.push((picture(frame.to_rgb(), file)?, truths));
                }
                Ok(out)
            };
            pool.run(jobs, render, |frames: Vec<(Picture, Vec<GroundTruth>)>| {
                for (image, truths) in frames {
                    let truth = SampleTruth::from_truths(&sensor, index, &truths, part.target);
                    index += 1;
                    deliver(Sample {
                        truth,
                        image,
                        reference: reference.clone(),
                        sensor: sensor.clone(),
                        sensor_file: sensor_file.clone(),
                        rendered: Some(truths),
                    })?;
                }
                Ok(())
            })?;
        }
        Ok(())
    }
}

/// Renders one job: its frames and labels.
fn render_job(renderer: &mut Renderer, job: &SuiteJob) -> Result<Vec<(Frame, Vec<GroundTruth>)>> {
    Ok(match job {
        SuiteJob::Batch(presses) => renderer
            .render_batch(presses)?
            .into_iter()
            .map(|(f, t)| (f, vec![t]))
            .collect(),
        SuiteJob::Scene(presses) => vec![renderer.render_scene(presses)?],
        SuiteJob::Empty => vec![(renderer.render_empty()?, Vec::new())],
    })
}

/// Pixels, written to `path` when given.
fn picture(rgb: RgbImage, path: Option<PathBuf>) -> Result<Picture> {
    if let Some(p) = &path {
        output::write_png_rgb8(p, rgb.width(), rgb.height(), rgb.as_raw())?;
    }
    Ok(Picture::pixels(rgb, path))
}
