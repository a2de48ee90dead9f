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

use crate::error::{GeltipError, Result};
use crate::finger::SurfaceCoord;
use crate::gpu::context::MAX_STREAMS;
use crate::object::{Object, Solid};
use crate::output::{self, LineLog, PngColor, PngRowCache};
use crate::render::gpu::{Renderer, MAX_BATCH};
use crate::render::{self, Contact, Frame, GroundTruth, Place};
use crate::sensor::Sensor;
use image::codecs::png::{CompressionType, FilterType};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Draws of a sample's contact before giving up on finding one the camera sees.
pub const MAX_ATTEMPTS: u64 = 1000;

/// The manifest of a set's options.
pub const MANIFEST: &str = "dataset.json";
/// The labels, one JSON line per sample.
pub const LABELS: &str = "labels.jsonl";

/// Which part of a set a run renders: shard `index` of `count`, a contiguous block of indices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub index: u64,
    pub count: u64,
}

impl Shard {
    /// The whole set.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Parses `i/n` (0 <= i < n).
    pub fn parse(text: &str) -> Result<Shard> {
        let bad = |reason: &str| GeltipError::input(format!("--shard {text}"), reason.to_string());
        let (i, n) = text
            .split_once('/')
            .ok_or_else(|| bad("expected <index>/<count>, e.g. 0/4"))?;
        let i: u64 = i
            .trim()
            .parse()
            .map_err(|_| bad("the index is not a whole number"))?;
        let n: u64 = n
            .trim()
            .parse()
            .map_err(|_| bad("the count is not a whole number"))?;
        if n == 0 {
            return Err(bad("the shard count must be at least 1"));
        }
        if i >= n {
            return Err(bad(&format!(
                "the shard index must be below the shard count: 0..{}",
                n - 1
            )));
        }
        Ok(Shard { index: i, count: n })
    }

    /// The sample indices of this shard of a set of `total`.
    pub fn range(self, total: u64) -> std::ops::Range<u64> {
        let at = |i: u64| ((i as u128 * total as u128) / self.count as u128) as u64;
        at(self.index)..at(self.index + 1)
    }
}

/// Parses `a..b` (mm): a press-depth range.
pub fn parse_depth_range(text: &str) -> Result<(f64, f64)> {
    let bad =
        |reason: &str| GeltipError::input(format!("--depth-range {text}"), reason.to_string());
    let (a, b) = text
        .split_once("..")
        .ok_or_else(|| bad("expected <min>..<max> in mm, e.g. 0.2..1.5"))?;
    let a: f64 = a
        .trim()
        .parse()
        .map_err(|_| bad("the minimum is not a number"))?;
    let b: f64 = b
        .trim()
        .parse()
        .map_err(|_| bad("the maximum is not a number"))?;
    Ok((a, b))
}

/// How hard PNG files are compressed (speed against size; see the README's measurements).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PngLevel {
    /// No compression: fastest to write, largest.
    None,
    /// zlib's fastest setting.
    Fast,
    /// zlib's default.
    Default,
    /// zlib's best.
    Best,
}

impl PngLevel {
    pub const ALL: [PngLevel; 4] = [
        PngLevel::None,
        PngLevel::Fast,
        PngLevel::Default,
        PngLevel::Best,
    ];

    pub fn name(self) -> &'static str {
        match self {
            PngLevel::None => "none",
            PngLevel::Fast => "fast",
            PngLevel::Default => "default",
            PngLevel::Best => "best",
        }
    }

    pub fn from_name(name: &str) -> Result<PngLevel> {
        PngLevel::ALL
            .into_iter()
            .find(|l| l.name() == name)
            .ok_or_else(|| {
                GeltipError::input(
                    format!("--png {name}"),
                    "expected none, fast, default or best",
                )
            })
    }

    /// The encoder settings.
    pub fn settings(self) -> (CompressionType, FilterType) {
        match self {
            PngLevel::None => (CompressionType::Uncompressed, FilterType::NoFilter),
            PngLevel::Fast => (CompressionType::Fast, FilterType::Adaptive),
            PngLevel::Default => (CompressionType::Default, FilterType::Adaptive),
            PngLevel::Best => (CompressionType::Best, FilterType::Adaptive),
        }
    }
}

/// Everything that defines a set (and how to produce it).
#[derive(Debug, Clone)]
pub struct Spec {
    /// The sensor as given (preset or file) and loaded.
    pub sensor_arg: String,
    pub sensor: Sensor,
    /// Built-in solid names or mesh paths.
    pub objects: Vec<String>,
    pub count: u64,
    pub seed: u64,
    /// Press depths (mm), drawn uniformly.
    pub depth_range: (f64, f64),
    pub shard: Shard,
    /// Write `depth/<k>.npy`, the indentation (mm) each pixel sees.
    pub depth_maps: bool,
    /// Write `masks/<k>.png`: 255 where the skin is pressed in more than
    /// [`render::MASK_THRESHOLD_MM`].
    pub masks: bool,
    /// Standard deviation of additive sensor noise, 8-bit grey levels.
    pub noise: f64,
    /// Per-sample gain of each colour channel drawn from `1 ± light_jitter` (the three LEDs).
    pub light_jitter: f64,
    /// Per-sample gain of the tactile change (frame minus the empty finger) drawn from
    /// `1 ± paint_jitter` (how strongly the paint shades a dent).
    pub paint_jitter: f64,
    /// A real sensor's empty frame: each image is this plus the rendered change.
    pub background: Option<PathBuf>,
    pub png: PngLevel,
    /// Encoder threads (does not change the files).
    pub workers: usize,
    /// Render streams, each a renderer on a device of its own (does not change the files):
    /// see [`default_streams`].
    pub streams: usize,
    /// The command line, recorded in `dataset.json` (not compared on resume).
    pub command: Vec<String>,
}

impl Spec {
    /// A set of `count` samples of the seven solids with the defaults.
    pub fn new(sensor_arg: &str, sensor: Sensor, count: u64, seed: u64) -> Spec {
        let max_depth = sensor.finger.shell_thickness;
        Spec {
            sensor_arg: sensor_arg.to_string(),
            sensor,
            objects: Solid::ALL.iter().map(|s| s.name().to_string()).collect(),
            count,
            seed,
            depth_range: default_depth_range(max_depth),
            shard: Shard::ALL,
            depth_maps: false,
            masks: false,
            noise: 0.0,
            light_jitter: 0.0,
            paint_jitter: 0.0,
            background: None,
            png: PngLevel::Fast,
            workers: default_workers(),
            streams: default_streams(),
            command: Vec::new(),
        }
    }

    fn check(&self) -> Result<()> {
        if self.count == 0 {
            return Err(GeltipError::input("--count", "must be at least 1, got 0"));
        }
        if !(1..=MAX_STREAMS).contains(&self.streams) {
            return Err(GeltipError::input(
                "--streams",
                format!("must lie in 1..={MAX_STREAMS}, got {}", self.streams),
            ));
        }
        if self.shard.count == 0 || self.shard.index >= self.shard.count {
            return Err(GeltipError::input(
                format!("--shard {}/{}", self.shard.index, self.shard.count),
                "the shard index must be below the shard count",
            ));
        }
        let (a, b) = self.depth_range;
        if !(a.is_finite() && b.is_finite()) || a < 0.0 || b < a {
            return Err(GeltipError::input(
                format!("--depth-range {a}..{b}"),
                "needs 0 <= min <= max, finite, in mm",
            ));
        }
        if self.objects.is_empty() {
            return Err(GeltipError::input("--objects", "the list is empty"));
        }
        for (what, v, max) in [
            ("--noise", self.noise, 255.0),
            ("--light-jitter", self.light_jitter, 1.0),
            ("--paint-jitter", self.paint_jitter, 1.0),
        ] {
            if !v.is_finite() || v < 0.0 || v >= max {
                return Err(GeltipError::input(
                    what,
                    format!("must be a number in [0, {max}), got {v}"),
                ));
            }
        }
        Ok(())
    }

    /// The options that define the set's samples, as `dataset.json` records and a resume
    /// compares them (everything but the shard, the workers and the command line).
    pub fn options_json(&self, background_hash: Option<u64>) -> Value {
        json!({
            "sensor": self.sensor_arg,
            "sensor_config": serde_json::to_value(&self.sensor.config).unwrap_or(Value::Null),
            "objects": self.objects,
            "count": self.count,
            "seed": self.seed,
            "depth_range_mm": [self.depth_range.0, self.depth_range.1],
            "depth_maps": self.depth_maps,
            "masks": self.masks,
            "noise": self.noise,
            "light_jitter": self.light_jitter,
            "paint_jitter": self.paint_jitter,
            "background": self.background.as_ref().map(|p| json!({
                "path": p.display().to_string(),
                "fnv1a64": format!("{:016x}", background_hash.unwrap_or(0)),
            })),
            "png": self.png.name(),
        })
    }
}

/// The default press depths for a finger whose gel is `shell_mm` thick: from a light touch
/// to the full thickness.
pub fn default_depth_range(shell_mm: f64) -> (f64, f64) {
    (0.2_f64.min(shell_mm), shell_mm)
}

/// Render streams by default: three. A software rasteriser leaves cores idle within and
/// between one stream's dispatches (and while it records, submits and reads back), which
/// other streams fill: on 2-core lavapipe 1, 2, 3 and 4 streams gave about 100, 115, 130
/// and 110 samples/s, at about 120 MB of memory a stream (the README's dataset section).
pub fn default_streams() -> usize {
    3
}

/// Encoder threads by default: the cores this process may use.
pub fn default_workers() -> usize {
    std::thread::available_parallelism().map_or(2, |n| n.get())
}

// ---------------------------------------------------------------------------------------
// Counter-based randomness: every draw is a pure function of (seed, k, stream, attempt).

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// SplitMix64 started from a hash of `parts`.
#[derive(Debug, Clone)]
pub struct SampleRng(u64);

/// Streams of a sample's draws.
const STREAM_CONTACT: u64 = 1;
const STREAM_LOOK: u64 = 2;
const STREAM_NOISE: u64 = 3;

impl SampleRng {
    pub fn new(parts: &[u64]) -> SampleRng {
        let mut h = 0x6765_6c74_6970_u64; // "geltip"
        for &p in parts {
            h = mix(h.wrapping_add(GOLDEN) ^ p);
        }
        SampleRng(h)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN);
        mix(self.0)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// The contact of a sample: one place to build it (contact fields may grow).
pub fn make_contact(
    object: Arc<Object>,
    s_mm: f64,
    azimuth_deg: f64,
    spin_deg: f64,
    depth_mm: f64,
) -> Contact {
    Contact {
        object,
        place: Place::ArcLength(s_mm),
        azimuth_deg,
        spin_deg,
        depth_mm,
    }
}

/// Arc length (mm) from the tip of the farthest surface point the lens can see.
pub fn visible_arc_length(sensor: &Sensor) -> f64 {
    render::heightfield_extent(sensor) - render::margin_mm(sensor) - sensor.finger.shell_thickness
}

/// Sample `k`'s contact: drawn from `(seed, k)`, redrawn (attempt 1, 2, ...) until the
/// camera sees the contact point.
pub fn sample_contact(
    sensor: &Sensor,
    objects: &[Arc<Object>],
    depth_range: (f64, f64),
    seed: u64,
    k: u64,
) -> Result<Contact> {
    let s_max = visible_arc_length(sensor);
    for attempt in 0..MAX_ATTEMPTS {
        let mut rng = SampleRng::new(&[seed, k, STREAM_CONTACT, attempt]);
        let s = rng.uniform(0.0, s_max);
        let azimuth = rng.uniform(0.0, 360.0);
        let depth = rng.uniform(depth_range.0, depth_range.1);
        let spin = rng.uniform(0.0, 360.0);
        let object = &objects[(rng.next_u64() % objects.len() as u64) as usize];
        // The contact point is the surface point at (s, azimuth) whatever the object: no
        // first-touch search here (the renderer does it once, when it prepares the frame).
        let point = sensor.finger.point_at(SurfaceCoord {
            s,
            phi: azimuth.to_radians(),
        });
        if sensor.project(point.point).is_ok() {
            return Ok(make_contact(object.clone(), s, azimuth, spin, depth));
        }
    }
    Err(GeltipError::input(
        format!("sample {k}"),
        format!("no contact the camera sees in {MAX_ATTEMPTS} draws"),
    ))
}

/// 64-bit FNV-1a of `bytes` (identifies a background image in `dataset.json`).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The CPU post-process of a sample's image: the tactile change on a base image, light and
/// paint jitter, sensor noise. `None` when there is nothing to do.
struct Look {
    /// The empty finger as rendered (RGB).
    reference: Vec<u8>,
    /// What the change is added to: the background, or the reference.
    base: Vec<u8>,
    noise: f64,
    light_jitter: f64,
    paint_jitter: f64,
}

impl Look {
    fn apply(&self, seed: u64, k: u64, frame: &Frame) -> Vec<u8> {
        let mut rng = SampleRng::new(&[seed, k, STREAM_LOOK]);
        let gains: [f64; 3] =
            std::array::from_fn(|_| 1.0 + self.light_jitter * (2.0 * rng.unit() - 1.0));
        let contrast = 1.0 + self.paint_jitter * (2.0 * rng.unit() - 1.0);
        let mut noise = SampleRng::new(&[seed, k, STREAM_NOISE]);
        // Approximately Gaussian: the sum of four 16-bit uniforms, scaled to unit variance.
        let scale = self.noise * 3.0_f64.sqrt() / 65536.0;
        let mut out = Vec::with_capacity(self.base.len());
        for (i, px) in frame.rgba.chunks_exact(4).enumerate() {
            for c in 0..3 {
                let j = 3 * i + c;
                let change = px[c] as f64 - self.reference[j] as f64;
                let mut v = (self.base[j] as f64 + contrast * change) * gains[c];
                if self.noise > 0.0 {
                    let r = noise.next_u64();
                    let sum =
                        (r & 0xffff) + ((r >> 16) & 0xffff) + ((r >> 32) & 0xffff) + (r >> 48);
                    v += (sum as f64 - 2.0 * 65535.0) * scale;
                }
                out.push(v.round().clamp(0.0, 255.0) as u8);
            }
        }
        out
    }
}

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

/// One rendered sample on its way to a worker.
struct Job {
    k: u64,
    frame: Frame,
    truth: GroundTruth,
}

/// State the workers share.
struct Shared<'a> {
    spec: &'a Spec,
    out: Option<&'a Path>,
    look: Option<Look>,
    /// The empty finger's rows, filtered and compressed once (fast PNG without a look:
    /// a sample's image re-encodes only the rows its contact changed).
    png_rows: Option<PngRowCache>,
    digits: usize,
    labels: Option<Mutex<LineLog>>,
    done: AtomicU64,
    bytes: AtomicU64,
    nanos: [AtomicU64; 3],
    error: Mutex<Option<GeltipError>>,
}

impl Shared<'_> {
    fn add_time(&self, slot: usize, d: Duration) {
        self.nanos[slot].fetch_add(d.as_nanos() as u64, Ordering::Relaxed);
    }

    fn process(&self, job: Job) -> Result<()> {
        let spec = self.spec;
        let (w, h) = (job.frame.width, job.frame.height);
        let t0 = Instant::now();
        let look_rgb = self
            .look
            .as_ref()
            .map(|look| look.apply(spec.seed, job.k, &job.frame));
        let name = format!("{:0width$}", job.k, width = self.digits);
        let image = format!("images/{name}.png");
        let depth = spec.depth_maps.then(|| format!("depth/{name}.npy"));
        let mask = spec.masks.then(|| format!("masks/{name}.png"));
        let mut label = json!({
            "index": job.k,
            "image": image,
            "depth": depth,
            "mask": mask,
        });
        if let (Value::Object(l), Value::Object(t)) = (&mut label, job.truth.to_json()) {
            l.extend(t);
        }
        let line = serde_json::to_string(&label)
            .map_err(|e| GeltipError::input(format!("sample {}", job.k), e.to_string()))?;
        let t1 = Instant::now();
        let (compression, filter) = spec.png.settings();
        let png = match (&look_rgb, &self.png_rows) {
            (None, Some(rows)) => rows.encode(&job.frame.rgba)?,
            (Some(rgb), _) => output::png_bytes(w, h, rgb, PngColor::Rgb8, compression, filter)?,
            (None, None) => {
                let rgb = job.frame.to_rgb().into_raw();
                output::png_bytes(w, h, &rgb, PngColor::Rgb8, compression, filter)?
            }
        };
        let mut files = vec![(image, png)];
        if let Some(depth) = depth {
            files.push((depth, output::npy_f32_bytes(w, h, &job.frame.indentation)?));
        }
        if let Some(mask) = mask {
            let grey: Vec<u8> = job
                .frame
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
        let t2 = Instant::now();
        let bytes: usize = files.iter().map(|(_, b)| b.len()).sum();
        self.bytes.fetch_add(bytes as u64, Ordering::Relaxed);
        if let Some(out) = self.out {
            for (rel, bytes) in &files {
                output::write_atomic(out.join(rel), bytes)?;
            }
            if let Some(labels) = &self.labels {
                labels
                    .lock()
                    .map_err(|_| GeltipError::input(LABELS, "a writer thread failed"))?
                    .append(&line)?;
            }
        }
        let t3 = Instant::now();
        self.add_time(0, t1 - t0);
        self.add_time(1, t2 - t1);
        self.add_time(2, t3 - t2);
        self.done.fetch_add(1, Ordering::Relaxed);
        Ok(())
    }

    fn fail(&self, e: GeltipError) {
        if let Ok(mut slot) = self.error.lock() {
            slot.get_or_insert(e);
        }
    }

    fn failed(&self) -> bool {
        self.error.lock().map_or(true, |e| e.is_some())
    }
}

/// Loads the objects named in `spec`, once each.
pub fn load_objects(names: &[String]) -> Result<Vec<Arc<Object>>> {
    names
        .iter()
        .map(|n| Object::from_arg(n).map(Arc::new))
        .collect()
}

/// Loads a background image: an RGB frame of the sensor's size.
fn load_background(path: &Path, sensor: &Sensor) -> Result<(Vec<u8>, u64)> {
    let bytes = fs::read(path).map_err(|e| GeltipError::io(path, e))?;
    let img = image::load_from_memory(&bytes).map_err(|e| GeltipError::InvalidImage {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    if (img.width(), img.height()) != (sensor.width, sensor.height) {
        return Err(GeltipError::InvalidImage {
            path: path.to_path_buf(),
            reason: format!(
                "is {}x{}, the sensor's images are {}x{}",
                img.width(),
                img.height(),
                sensor.width,
                sensor.height
            ),
        });
    }
    Ok((img.to_rgb8().into_raw(), fnv1a64(&bytes)))
}

/// A set directory's manifest as JSON.
fn read_manifest(dir: &Path) -> Result<Option<Value>> {
    let path = dir.join(MANIFEST);
    match fs::read_to_string(&path) {
        Ok(text) => serde_json::from_str(&text).map(Some).map_err(|e| {
            GeltipError::input(path.display().to_string(), format!("not valid JSON: {e}"))
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(GeltipError::io(path, e)),
    }
}

/// The keys whose values differ between two JSON objects.
fn differing_keys(a: &Value, b: &Value) -> Vec<String> {
    let empty = serde_json::Map::new();
    let (a, b) = (
        a.as_object().unwrap_or(&empty),
        b.as_object().unwrap_or(&empty),
    );
    let mut keys: Vec<String> = a
        .keys()
        .chain(b.keys())
        .filter(|k| a.get(*k) != b.get(*k))
        .cloned()
        .collect();
    keys.sort();
    keys.dedup();
    keys
}

/// Removes temporary files a killed run left (`.<name>.<pid>.<n>.tmp`) in a set directory.
fn remove_temp_files(dir: &Path) {
    for sub in ["", "images", "depth", "masks"] {
        let Ok(entries) = fs::read_dir(dir.join(sub)) else {
            continue;
        };
        for entry in entries.flatten() {
            let name = entry.file_name();
            let name = name.to_string_lossy();
            if name.starts_with('.') && name.ends_with(".tmp") {
                let _ = fs::remove_file(entry.path());
            }
        }
    }
}

/// The complete samples listed in a set directory's `labels.jsonl`: the parsed lines (by
/// index) whose files exist. Torn or unreadable lines are dropped.
fn complete_samples(dir: &Path) -> Result<BTreeMap<u64, String>> {
    let path = dir.join(LABELS);
    let text = match fs::read(&path) {
        Ok(bytes) => String::from_utf8_lossy(&bytes).into_owned(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(BTreeMap::new()),
        Err(e) => return Err(GeltipError::io(path, e)),
    };
    let mut done = BTreeMap::new();
    for line in text.lines() {
        let Ok(v) = serde_json::from_str::<Value>(line) else {
            continue;
        };
        let Some(k) = v.get("index").and_then(Value::as_u64) else {
            continue;
        };
        let files_exist = ["image", "depth", "mask"]
            .iter()
            .all(|key| match v.get(*key) {
                Some(Value::String(rel)) => dir.join(rel).is_file(),
                _ => *key != "image",
            });
        if files_exist {
            done.entry(k).or_insert_with(|| line.to_string());
        }
    }
    Ok(done)
}

/// Writes `labels.jsonl` holding `lines` (sorted by index), atomically.
fn write_labels(dir: &Path, lines: &BTreeMap<u64, String>) -> Result<()> {
    let mut text = String::new();
    for line in lines.values() {
        text.push_str(line);
        text.push('\n');
    }
    output::write_atomic(dir.join(LABELS), text.as_bytes())
}

/// The manifest of a run.
fn manifest(spec: &Spec, options: &Value) -> Value {
    json!({
        "geltip_version": env!("CARGO_PKG_VERSION"),
        "options": options,
        "shard": [spec.shard.index, spec.shard.count],
        "shard_range": [spec.shard.range(spec.count).start, spec.shard.range(spec.count).end],
        "command": spec.command,
    })
}

/// Renders the samples of `spec`'s shard into `out` (resuming what is there), or, with
/// `out = None`, renders and encodes them and discards the files (for measurements).
/// `progress` is called after each batch.
pub fn run(spec: &Spec, out: Option<&Path>, mut progress: impl FnMut(Progress)) -> Result<Report> {
    spec.check()?;
    let objects = load_objects(&spec.objects)?;
    // Refuse an object that cannot be pressed as deep as asked before any work.
    for o in &objects {
        let c = make_contact(o.clone(), 0.0, 0.0, 0.0, spec.depth_range.1);
        c.pose(&spec.sensor)?;
    }
    let background = spec
        .background
        .as_ref()
        .map(|p| load_background(p, &spec.sensor))
        .transpose()?;
    let options = spec.options_json(background.as_ref().map(|b| b.1));

    let range = spec.shard.range(spec.count);
    let mut report = Report {
        shard_samples: range.end - range.start,
        ..Report::default()
    };
    let mut done = BTreeMap::new();
    if let Some(dir) = out {
        fs::create_dir_all(dir).map_err(|e| GeltipError::io(dir, e))?;
        let wanted = manifest(spec, &options);
        match read_manifest(dir)? {
            Some(old) => {
                let mut diff = differing_keys(&old["options"], &options);
                if old["shard"] != wanted["shard"] {
                    diff.push("shard".into());
                }
                if !diff.is_empty() {
                    return Err(GeltipError::input(
                        format!("--out {}", dir.display()),
                        format!(
                            "holds a set made with different options ({}); use another directory",
                            diff.join(", ")
                        ),
                    ));
                }
            }
            None => output::write_json(dir.join(MANIFEST), &wanted)?,
        }
        remove_temp_files(dir);
        done = complete_samples(dir)?;
        done.retain(|k, _| range.contains(k));
        // Drop torn and dangling lines before appending.
        write_labels(dir, &done)?;
        report.kept = done.len() as u64;
    }
    let todo: Vec<u64> = range.clone().filter(|k| !done.contains_key(k)).collect();
    let total = todo.len() as u64;
    progress(Progress { done: 0, total });
    if !todo.is_empty() {
        render_samples(
            spec,
            out,
            &objects,
            background.map(|b| b.0),
            &todo,
            &mut report,
            &mut progress,
        )?;
    }
    if let Some(dir) = out {
        let mut complete = complete_samples(dir)?;
        complete.retain(|k, _| range.contains(k));
        if complete.len() as u64 != report.shard_samples {
            return Err(GeltipError::input(
                format!("--out {}", dir.display()),
                format!(
                    "{} of {} samples complete after the run",
                    complete.len(),
                    report.shard_samples
                ),
            ));
        }
        write_labels(dir, &complete)?;
    }
    Ok(report)
}

fn render_samples(
    spec: &Spec,
    out: Option<&Path>,
    objects: &[Arc<Object>],
    background: Option<Vec<u8>>,
    todo: &[u64],
    report: &mut Report,
    progress: &mut impl FnMut(Progress),
) -> Result<()> {
    let start = Instant::now();
    // Noise is added per sample on the CPU; the renderer renders without it.
    let mut config = spec.sensor.config.clone();
    config.render.noise = 0.0;
    let render_sensor = Sensor::from_config(spec.sensor.name.clone(), config)?;
    // Every object's contact pipeline is built now, at start-up, not in the first batch's
    // frames.
    let mut renderers = Renderer::on_streams(&render_sensor, spec.streams, objects)?;
    report.startup = start.elapsed();
    let renderer = &renderers[0];
    let start = Instant::now();
    let needs_look = background.is_some()
        || spec.noise > 0.0
        || spec.light_jitter > 0.0
        || spec.paint_jitter > 0.0;
    let look = needs_look.then(|| {
        let reference = renderer.reference().to_rgb().into_raw();
        Look {
            base: background.unwrap_or_else(|| reference.clone()),
            reference,
            noise: spec.noise,
            light_jitter: spec.light_jitter,
            paint_jitter: spec.paint_jitter,
        }
    });
    let png_rows = match (spec.png, &look) {
        (PngLevel::Fast, None) => {
            let reference = renderer.reference();
            Some(PngRowCache::new(
                reference.width,
                reference.height,
                &reference.rgba,
            )?)
        }
        _ => None,
    };
    let labels = match out {
        Some(dir) => Some(Mutex::new(LineLog::open(dir.join(LABELS))?)),
        None => None,
    };
    let shared = Shared {
        spec,
        out,
        look,
        png_rows,
        digits: (spec.count - 1).to_string().len().max(6),
        labels,
        done: AtomicU64::new(0),
        bytes: AtomicU64::new(0),
        nanos: Default::default(),
        error: Mutex::new(None),
    };
    let total = todo.len() as u64;
    let workers = spec.workers.max(1);
    let (tx, rx) = mpsc::sync_channel::<Job>(2 * MAX_BATCH);
    let rx = Mutex::new(rx);
    let mut split = Split::default();
    // The next batches' contacts are drawn and prepared (poses, footprints: CPU work) on
    // their own thread while the GPU renders; each render stream takes the next batch. The
    // last stream to stop closes the channel, so the preparing thread stops too.
    let preparer = renderer.preparer();
    let (prepared_tx, prepared_rx) = mpsc::sync_channel(renderers.len());
    let prepared_rx = Mutex::new(Some(prepared_rx));
    let live = AtomicU64::new(renderers.len() as u64);
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| loop {
                let job = match rx.lock() {
                    Ok(rx) => rx.recv(),
                    Err(_) => return,
                };
                let Ok(job) = job else { return };
                if shared.failed() {
                    continue;
                }
                if let Err(e) = shared.process(job) {
                    shared.fail(e);
                }
            });
        }
        scope.spawn(move || {
            for chunk in todo.chunks(MAX_BATCH) {
                let t = Instant::now();
                let batch = chunk
                    .iter()
                    .map(|&k| sample_contact(&spec.sensor, objects, spec.depth_range, spec.seed, k))
                    .collect::<Result<Vec<_>>>()
                    .and_then(|contacts| preparer.prepare(&contacts));
                let failed = batch.is_err();
                // A closed channel: the renderers stopped.
                if prepared_tx
                    .send(batch.map(|b| (chunk, b, t.elapsed())))
                    .is_err()
                    || failed
                {
                    return;
                }
            }
        });
        // Whichever way a stream ends (a panic included), it counts itself out; the last
        // one closes the channel, so the preparing thread cannot block on a full channel.
        struct Leaving<'a, T> {
            live: &'a AtomicU64,
            prepared_rx: &'a Mutex<Option<T>>,
        }
        impl<T> Drop for Leaving<'_, T> {
            fn drop(&mut self) {
                if self.live.fetch_sub(1, Ordering::Relaxed) == 1 {
                    if let Ok(mut rx) = self.prepared_rx.lock() {
                        rx.take();
                    }
                }
            }
        }
        let stream = |renderer: &mut Renderer,
                      tx: mpsc::SyncSender<Job>,
                      progress: &mut dyn FnMut(Progress)| {
            let _leaving = Leaving {
                live: &live,
                prepared_rx: &prepared_rx,
            };
            let mut split = Split::default();
            let result = (|| -> Result<()> {
                loop {
                    let next = match prepared_rx.lock() {
                        Ok(rx) => rx.as_ref().map(|rx| rx.recv()),
                        Err(_) => None,
                    };
                    let Some(Ok(prepared)) = next else {
                        return Ok(());
                    };
                    let (chunk, batch, prepare) = prepared?;
                    split.prepare += prepare;
                    let frames = renderer.render_prepared(batch)?;
                    let t = renderer.timings();
                    split.render += t.render;
                    split.readback += t.readback;
                    for (&k, (frame, truth)) in chunk.iter().zip(frames) {
                        if tx.send(Job { k, frame, truth }).is_err() || shared.failed() {
                            return Ok(());
                        }
                    }
                    progress(Progress {
                        done: shared.done.load(Ordering::Relaxed),
                        total,
                    });
                }
            })();
            if let Err(e) = result {
                shared.fail(e);
            }
            split
        };
        let (first, others) = renderers.split_first_mut().expect("one renderer at least");
        let others: Vec<_> = others
            .iter_mut()
            .map(|renderer| {
                let tx = tx.clone();
                scope.spawn(move || stream(renderer, tx, &mut |_| {}))
            })
            .collect();
        // The first stream on this thread: it alone reports progress.
        let mut splits = vec![stream(first, tx, progress)];
        for other in others {
            match other.join() {
                Ok(split) => splits.push(split),
                Err(_) => shared.fail(GeltipError::Gpu("a render stream panicked".into())),
            }
        }
        for s in splits {
            split.prepare += s.prepare;
            split.render += s.render;
            split.readback += s.readback;
        }
    });
    if let Some(e) = shared.error.lock().ok().and_then(|mut e| e.take()) {
        return Err(e);
    }
    let nanos = |i: usize| Duration::from_nanos(shared.nanos[i].load(Ordering::Relaxed));
    split.post = nanos(0);
    split.encode = nanos(1);
    split.write = nanos(2);
    report.split = split;
    report.rendered = shared.done.load(Ordering::Relaxed);
    report.bytes = shared.bytes.load(Ordering::Relaxed);
    report.wall = start.elapsed();
    progress(Progress {
        done: report.rendered,
        total,
    });
    Ok(())
}

/// Joins the shard directories of one set into `out`: checks that they hold the shards
/// 0..n of the same options, each complete, links (or copies) their files into `out` and
/// writes one `dataset.json` and one `labels.jsonl` sorted by index, as an unsharded run
/// would. Returns the number of samples.
pub fn merge(out: &Path, shards: &[PathBuf], command: &[String]) -> Result<u64> {
    if shards.is_empty() {
        return Err(GeltipError::input(
            "--merge",
            "name the shard directories to join",
        ));
    }
    let mut options: Option<Value> = None;
    let mut seen: BTreeMap<u64, &Path> = BTreeMap::new();
    let mut n_shards = None;
    let mut lines = BTreeMap::new();
    let mut version = Value::Null;
    for dir in shards {
        let what = || format!("shard {}", dir.display());
        let m = read_manifest(dir)?
            .ok_or_else(|| GeltipError::input(what(), format!("has no {MANIFEST}")))?;
        let opts = m["options"].clone();
        match &options {
            None => options = Some(opts.clone()),
            Some(o) if *o != opts => {
                return Err(GeltipError::input(
                    what(),
                    format!(
                        "was made with different options than {} ({})",
                        shards[0].display(),
                        differing_keys(o, &opts).join(", ")
                    ),
                ))
            }
            Some(_) => {}
        }
        version = m["geltip_version"].clone();
        let (Some(i), Some(n)) = (m["shard"][0].as_u64(), m["shard"][1].as_u64()) else {
            return Err(GeltipError::input(
                what(),
                format!("{MANIFEST} has no shard i/n"),
            ));
        };
        if *n_shards.get_or_insert(n) != n {
            return Err(GeltipError::input(
                what(),
                format!(
                    "is shard {i}/{n}, the others are of {}",
                    n_shards.unwrap_or(n)
                ),
            ));
        }
        if let Some(other) = seen.insert(i, dir) {
            return Err(GeltipError::input(
                what(),
                format!("is shard {i}/{n}, as is {}", other.display()),
            ));
        }
        let count = opts["count"].as_u64().unwrap_or(0);
        let range = Shard { index: i, count: n }.range(count);
        let mut done = complete_samples(dir)?;
        done.retain(|k, _| range.contains(k));
        if done.len() as u64 != range.end - range.start {
            return Err(GeltipError::input(
                what(),
                format!(
                    "is incomplete: {} of {} samples (rerun its command to finish it)",
                    done.len(),
                    range.end - range.start
                ),
            ));
        }
        for (k, line) in done {
            lines.insert(k, (dir.clone(), line));
        }
    }
    let n = n_shards.unwrap_or(1);
    if seen.len() as u64 != n {
        let missing: Vec<String> = (0..n)
            .filter(|i| !seen.contains_key(i))
            .map(|i| format!("{i}/{n}"))
            .collect();
        return Err(GeltipError::input(
            "--merge",
            format!("missing shards {}", missing.join(", ")),
        ));
    }
    let options = options.unwrap_or(Value::Null);
    let count = options["count"].as_u64().unwrap_or(0);
    let wanted = json!({
        "geltip_version": version,
        "options": options,
        "shard": [0, 1],
        "shard_range": [0, count],
        "command": command,
    });
    fs::create_dir_all(out).map_err(|e| GeltipError::io(out, e))?;
    if let Some(old) = read_manifest(out)? {
        if old["options"] != wanted["options"] || old["shard"] != wanted["shard"] {
            return Err(GeltipError::input(
                format!("--merge {}", out.display()),
                "already holds a different set; use another directory",
            ));
        }
    } else {
        output::write_json(out.join(MANIFEST), &wanted)?;
    }
    let mut merged = BTreeMap::new();
    for (k, (dir, line)) in lines {
        let v: Value = serde_json::from_str(&line).unwrap_or(Value::Null);
        for key in ["image", "depth", "mask"] {
            if let Some(rel) = v[key].as_str() {
                let dst = out.join(rel);
                if dir.as_path() != out {
                    output::link_or_copy_atomic(dir.join(rel), &dst)?;
                }
            }
        }
        merged.insert(k, line);
    }
    write_labels(out, &merged)?;
    Ok(merged.len() as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_indices() {
        for total in [1u64, 7, 10, 1000] {
            for n in 1..=5u64 {
                let mut all = Vec::new();
                for i in 0..n {
                    all.extend(Shard { index: i, count: n }.range(total));
                }
                assert_eq!(all, (0..total).collect::<Vec<_>>());
            }
        }
    }

    #[test]
    fn shard_and_range_parsing() {
        assert_eq!(Shard::parse("1/3").unwrap(), Shard { index: 1, count: 3 });
        for bad in ["3/3", "1/0", "x/2", "1", "-1/2"] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.contains("--shard") && !e.contains('\n'), "{e}");
        }
        assert_eq!(parse_depth_range("0.5..1.5").unwrap(), (0.5, 1.5));
        assert!(parse_depth_range("0.5-1").is_err());
    }

    #[test]
    fn draws_depend_on_seed_and_index_only() {
        let a: Vec<u64> = (0..4)
            .map(|_| SampleRng::new(&[1, 2, 3]).next_u64())
            .collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        assert_ne!(
            SampleRng::new(&[1, 2, 3]).next_u64(),
            SampleRng::new(&[1, 3, 3]).next_u64()
        );
        assert_ne!(
            SampleRng::new(&[2, 2, 3]).next_u64(),
            SampleRng::new(&[1, 2, 3]).next_u64()
        );
        let mut r = SampleRng::new(&[9]);
        let mean = (0..10_000).map(|_| r.unit()).sum::<f64>() / 10_000.0;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
    }

    #[test]
    fn sampled_contacts_are_visible_and_in_range() {
        let sensor = Sensor::preset("paper").unwrap();
        let objects = load_objects(&["sphere".into(), "cone".into()]).unwrap();
        for k in 0..200 {
            let c = sample_contact(&sensor, &objects, (0.3, 1.2), 5, k).unwrap();
            let again = sample_contact(&sensor, &objects, (0.3, 1.2), 5, k).unwrap();
            assert_eq!(c.place, again.place);
            assert!((0.3..=1.2).contains(&c.depth_mm));
            assert!((0.0..360.0).contains(&c.azimuth_deg));
            let pose = c.pose(&sensor).unwrap();
            assert!(sensor.project(pose.point).is_ok());
        }
    }
}
