//! The encoder threads' work: a rendered sample's post-process, its files (PNG image, NPY
//! depth map, PNG mask), written under temporary names and renamed, then its label line.

use super::look::Look;
use super::spec::{PngLevel, Spec};
use super::store::LABELS;
use super::Split;
use crate::error::{GeltipError, Result};
use crate::output::{self, LineLog, PngColor, PngRowCache};
use crate::render::background::{background_stem, Backgrounds};
use crate::render::{self, Frame, GroundTruth};
use serde_json::{json, Value};
use std::panic::AssertUnwindSafe;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Mutex};
use std::time::{Duration, Instant};

/// The backgrounds' RGB values (none without backgrounds).
pub(super) fn rgb_of(backgrounds: Option<&Backgrounds>) -> Vec<Vec<u8>> {
    backgrounds.map_or_else(Vec::new, |b| {
        b.images.iter().map(|i| i.as_raw().clone()).collect()
    })
}

/// The empty frame, in a set, of the samples put on the background `name`.
pub fn reference_file(name: &str) -> String {
    format!("references/{}.png", background_stem(name))
}

/// One rendered sample on its way to an encoder thread.
pub(super) struct Job {
    pub k: u64,
    pub frame: Frame,
    /// The labels of the frame's contacts (one, unless the set is of scenes).
    pub truths: Vec<GroundTruth>,
}

/// A sample's files: relative path and bytes.
type Files = Vec<(String, Vec<u8>)>;

/// What the encoder threads share: the options, the post-process, the cached empty rows,
/// the labels log, counters and the first error.
pub(super) struct SampleWriter<'a> {
    spec: &'a Spec,
    /// `None`: encode and discard (measurements).
    out: Option<&'a Path>,
    look: Option<Look>,
    /// The names of a folder's backgrounds, when each sample draws one: its label names
    /// it and its empty frame (`references/<stem>.png`).
    background_names: Option<Vec<String>>,
    /// The empty finger's rows, filtered and compressed once (fast PNG without a look:
    /// a sample's image re-encodes only the rows its contact changed).
    png_rows: Option<PngRowCache>,
    /// Digits of a sample's file name.
    digits: usize,
    labels: Option<Mutex<LineLog>>,
    done: AtomicU64,
    bytes: AtomicU64,
    /// Nanoseconds in post-process, encoding and writing, summed over the threads.
    nanos: [AtomicU64; 3],
    error: Mutex<Option<GeltipError>>,
}

impl<'a> SampleWriter<'a> {
    /// A writer into `out` for frames rendered against the empty finger `reference`, with
    /// the loaded `backgrounds` if any.
    pub(super) fn new(
        spec: &'a Spec,
        out: Option<&'a Path>,
        reference: &Frame,
        backgrounds: Option<&Backgrounds>,
    ) -> Result<SampleWriter<'a>> {
        let look = Look::new(spec, reference, rgb_of(backgrounds));
        let background_names = backgrounds.filter(|b| b.many()).map(|b| b.names.clone());
        let png_rows = match (spec.png, &look) {
            (PngLevel::Fast, None) => Some(PngRowCache::new(
                reference.width,
                reference.height,
                &reference.rgba,
            )?),
            _ => None,
        };
        let labels = out
            .map(|dir| LineLog::open(dir.join(LABELS)).map(Mutex::new))
            .transpose()?;
        Ok(SampleWriter {
            spec,
            out,
            look,
            background_names,
            png_rows,
            digits: (spec.count - 1).to_string().len().max(6),
            labels,
            done: AtomicU64::new(0),
            bytes: AtomicU64::new(0),
            nanos: Default::default(),
            error: Mutex::new(None),
        })
    }

    /// An encoder thread: takes jobs until the channel closes. After a failure (its own or
    /// another thread's) it drains the channel without writing, so the renderers never
    /// block on a full channel.
    pub(super) fn serve(&self, jobs: &Mutex<mpsc::Receiver<Job>>) {
        loop {
            let job = match jobs.lock() {
                Ok(rx) => rx.recv(),
                Err(_) => return,
            };
            let Ok(job) = job else { return };
            if self.failed() {
                continue;
            }
            let k = job.k;
            // A panic is this sample's error: a thread that died would leave the renderers
            // blocked on a full channel once every encoder had.
            let done = std::panic::catch_unwind(AssertUnwindSafe(|| self.process(job)));
            match done {
                Ok(Ok(())) => {}
                Ok(Err(e)) => self.fail(e),
                Err(payload) => {
                    let message = payload
                        .downcast_ref::<&str>()
                        .map(|s| s.to_string())
                        .or_else(|| payload.downcast_ref::<String>().cloned())
                        .unwrap_or_default();
                    self.fail(GeltipError::input(
                        format!("sample {k}"),
                        format!("encoding panicked: {message}"),
                    ));
                }
            }
        }
    }

    fn process(&self, job: Job) -> Result<()> {
        let t0 = Instant::now();
        let seed = self.spec.seed;
        let (look_rgb, base) = match &self.look {
            Some(look) => {
                let base = look.base_of(seed, job.k);
                (Some(look.apply(seed, job.k, base, &job.frame)), base)
            }
            None => (None, 0),
        };
        let name = format!("{:0width$}", job.k, width = self.digits);
        let image = format!("images/{name}.png");
        let depth = self.spec.depth_maps.then(|| format!("depth/{name}.npy"));
        let mask = self.spec.masks.then(|| format!("masks/{name}.png"));
        let mut label = json!({
            "index": job.k,
            "image": image,
            "depth": depth,
            "mask": mask,
        });
        let truth = if self.spec.scenes() {
            render::scene_labels(&job.frame, &job.truths)
        } else {
            job.truths
                .first()
                .map(GroundTruth::to_json)
                .unwrap_or_default()
        };
        if let (Value::Object(l), Value::Object(t)) = (&mut label, truth) {
            l.extend(t);
            if let Some(names) = &self.background_names {
                l.insert("background".into(), json!(names[base]));
                l.insert("reference".into(), json!(reference_file(&names[base])));
            }
        }
        let line = serde_json::to_string(&label)
            .map_err(|e| GeltipError::input(format!("sample {}", job.k), e.to_string()))?;
        let t1 = Instant::now();
        let files = self.encode(&job.frame, look_rgb, image, depth, mask)?;
        let t2 = Instant::now();
        let bytes: usize = files.iter().map(|(_, b)| b.len()).sum();
        self.bytes.fetch_add(bytes as u64, Ordering::Relaxed);
        self.write(&files, &line)?;
        let t3 = Instant::now();
        self.add_time(0, t1 - t0);
        self.add_time(1, t2 - t1);
        self.add_time(2, t3 - t2);
        self.done.fetch_add(1, Ordering::Relaxed);
        Ok(())
    }

    /// The bytes of a sample's files under their relative paths: the image (the post-
    /// processed `look_rgb` if any), and the depth map and mask where named.
    fn encode(
        &self,
        frame: &Frame,
        look_rgb: Option<Vec<u8>>,
        image: String,
        depth: Option<String>,
        mask: Option<String>,
    ) -> Result<Files> {
        let (w, h) = (frame.width, frame.height);
        let (compression, filter) = self.spec.png.settings();
        let png = match (&look_rgb, &self.png_rows) {
            (None, Some(rows)) => rows.encode(&frame.rgba)?,
            (Some(rgb), _) => output::png_bytes(w, h, rgb, PngColor::Rgb8, compression, filter)?,
            (None, None) => {
                let rgb = frame.to_rgb().into_raw();
                output::png_bytes(w, h, &rgb, PngColor::Rgb8, compression, filter)?
            }
        };
        let mut files = vec![(image, png)];
        if let Some(depth) = depth {
            files.push((depth, output::npy_f32_bytes(w, h, &frame.indentation)?));
        }
        if let Some(mask) = mask {
            let grey: Vec<u8> = frame
                .indentation
                .iter()
                .map(|&d| {
                    if d as f64 > render::MASK_THRESHOLD_MM {
                        255
                    } else {
                        0
                    }
                })
                .collect();
            files.push((
                mask,
                output::png_bytes(w, h, &grey, PngColor::Gray8, compression, filter)?,
            ));
        }
        Ok(files)
    }

    /// Writes a sample's files, then appends its label line: a line names only files that
    /// are complete.
    fn write(&self, files: &Files, line: &str) -> Result<()> {
        let Some(out) = self.out else {
            return Ok(());
        };
        for (rel, bytes) in files {
            output::write_atomic(out.join(rel), bytes)?;
        }
        if let Some(labels) = &self.labels {
            labels
                .lock()
                .map_err(|_| GeltipError::input(LABELS, "a writer thread failed"))?
                .append(line)?;
        }
        Ok(())
    }

    fn add_time(&self, slot: usize, d: Duration) {
        self.nanos[slot].fetch_add(d.as_nanos() as u64, Ordering::Relaxed);
    }

    /// Records `e` unless an error is recorded already: the first error is the run's.
    pub(super) fn fail(&self, e: GeltipError) {
        if let Ok(mut slot) = self.error.lock() {
            slot.get_or_insert(e);
        }
    }

    pub(super) fn failed(&self) -> bool {
        self.error.lock().map_or(true, |e| e.is_some())
    }

    /// The first error, if any.
    pub(super) fn take_error(&self) -> Option<GeltipError> {
        self.error.lock().ok().and_then(|mut e| e.take())
    }

    /// Samples written so far.
    pub(super) fn done(&self) -> u64 {
        self.done.load(Ordering::Relaxed)
    }

    /// Bytes of files encoded so far.
    pub(super) fn bytes(&self) -> u64 {
        self.bytes.load(Ordering::Relaxed)
    }

    /// Adds the post-process, encoding and writing times to `split`.
    pub(super) fn add_times_to(&self, split: &mut Split) {
        let nanos = |i: usize| Duration::from_nanos(self.nanos[i].load(Ordering::Relaxed));
        split.post += nanos(0);
        split.encode += nanos(1);
        split.write += nanos(2);
    }
}
