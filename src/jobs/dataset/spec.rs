//! What defines a set: the options, their validation and defaults, shards and PNG levels.

use crate::error::{GeltipError, Result};
use crate::gpu::context::MAX_STREAMS;
use crate::object::Solid;
use crate::sensor::{Noise, Sensor};
use image::codecs::png::{CompressionType, FilterType};
use serde_json::{json, Value};
use std::path::PathBuf;

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
        let bad = |reason: &str| GeltipError::option_value("shard", text, reason);
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
    let bad = |reason: &str| GeltipError::option_value("depth_range", text, reason);
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
                GeltipError::option_value("png", name, "expected none, fast, default or best")
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
    /// [`crate::render::MASK_THRESHOLD_MM`].
    pub masks: bool,
    /// Standard deviation of additive sensor noise, 8-bit levels (one, or one per channel).
    pub noise: Noise,
    /// Per-sample gain of each colour channel drawn from `1 ± light_jitter` (the three LEDs).
    pub light_jitter: f64,
    /// Per-sample gain of the tactile change (frame minus the empty finger) drawn from
    /// `1 ± paint_jitter` (how strongly the paint shades a dent).
    pub paint_jitter: f64,
    /// A real sensor's empty frame: each image is this plus the rendered change.
    pub background: Option<PathBuf>,
    /// How far each image's light drifts from its empty frame's, as a real sensor's LEDs do
    /// between two moments (0: none; 1: a sector's channel up to 40% brighter or darker,
    /// each channel's gain 1 ± 12%, an offset up to ± 5 levels).
    pub drift: f64,
    /// Share of samples that are empty frames (labelled, no contact: what false positives
    /// are counted on).
    pub empty_fraction: f64,
    /// Contacts in each non-empty sample, drawn uniformly from this range (inclusive).
    pub contacts_per_sample: (u32, u32),
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
            noise: Noise::NONE,
            light_jitter: 0.0,
            drift: 0.0,
            paint_jitter: 0.0,
            background: None,
            empty_fraction: 0.0,
            contacts_per_sample: (1, 1),
            png: PngLevel::Fast,
            workers: default_workers(),
            streams: default_streams(),
            command: Vec::new(),
        }
    }

    /// Refuses options no set can be made with, naming the option (its field here).
    pub(super) fn check(&self) -> Result<()> {
        if self.count == 0 {
            return Err(GeltipError::option("count", "must be at least 1, got 0"));
        }
        if !(1..=MAX_STREAMS).contains(&self.streams) {
            return Err(GeltipError::option(
                "streams",
                format!("must lie in 1..={MAX_STREAMS}, got {}", self.streams),
            ));
        }
        if self.shard.count == 0 || self.shard.index >= self.shard.count {
            return Err(GeltipError::option_value(
                "shard",
                format!("{}/{}", self.shard.index, self.shard.count),
                "the shard index must be below the shard count",
            ));
        }
        let (a, b) = self.depth_range;
        if !(a.is_finite() && b.is_finite()) || a < 0.0 || b < a {
            return Err(GeltipError::option_value(
                "depth_range",
                format!("{a}..{b}"),
                "needs 0 <= min <= max, finite, in mm",
            ));
        }
        if self.objects.is_empty() {
            return Err(GeltipError::option("objects", "the list is empty"));
        }
        let e = self.empty_fraction;
        if !(0.0..1.0).contains(&e) {
            return Err(GeltipError::option(
                "empty_fraction",
                format!("must be a number in [0, 1), got {e}"),
            ));
        }
        let (a, b) = self.contacts_per_sample;
        if a < 1 || b < a || b > MAX_CONTACTS_PER_SAMPLE {
            return Err(GeltipError::option_value(
                "contacts_per_sample",
                format!("{a}..{b}"),
                format!("needs 1 <= min <= max <= {MAX_CONTACTS_PER_SAMPLE}"),
            ));
        }
        let noise = self.noise.rgb();
        for (what, v, max) in [
            ("noise", noise[0], 255.0),
            ("noise", noise[1], 255.0),
            ("noise", noise[2], 255.0),
            ("light_jitter", self.light_jitter, 1.0),
            ("paint_jitter", self.paint_jitter, 1.0),
            ("drift", self.drift, 1.0 + 1e-9),
        ] {
            if !v.is_finite() || v < 0.0 || v >= max {
                return Err(GeltipError::option(
                    what,
                    format!("must be a number in [0, {max}), got {v}"),
                ));
            }
        }
        Ok(())
    }

    /// Whether samples are labelled as scenes (`{"contacts": [...]}`): when some are empty
    /// or hold several contacts. Otherwise each line is one contact's labels.
    pub fn scenes(&self) -> bool {
        self.empty_fraction > 0.0 || self.contacts_per_sample != (1, 1)
    }

    /// The options that define the set's samples, as `dataset.json` records and a resume
    /// compares them (everything but the shard, the workers and the command line). Options
    /// left at their defaults that older sets do not record are left out.
    pub fn options_json(&self, background_hash: Option<u64>) -> Value {
        let mut options = self.base_options_json(background_hash);
        if let Value::Object(o) = &mut options {
            if self.empty_fraction > 0.0 {
                o.insert("empty_fraction".into(), json!(self.empty_fraction));
            }
            if self.drift > 0.0 {
                o.insert("drift".into(), json!(self.drift));
            }
            if self.contacts_per_sample != (1, 1) {
                let (a, b) = self.contacts_per_sample;
                o.insert("contacts_per_sample".into(), json!([a, b]));
            }
        }
        options
    }

    fn base_options_json(&self, background_hash: Option<u64>) -> Value {
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

/// Most contacts one sample may hold.
pub const MAX_CONTACTS_PER_SAMPLE: u32 = 8;

/// Parses a count of contacts per sample: `n` or `min..max`.
pub fn parse_contacts_range(text: &str) -> Result<(u32, u32)> {
    let bad = || {
        GeltipError::option_value(
            "contacts_per_sample",
            text,
            "expected a count n or a range min..max, e.g. 1..3",
        )
    };
    let (a, b) = match text.split_once("..") {
        Some((a, b)) => (a, b),
        None => (text, text),
    };
    let a: u32 = a.trim().parse().map_err(|_| bad())?;
    let b: u32 = b.trim().parse().map_err(|_| bad())?;
    Ok((a, b))
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
            assert!(
                e.starts_with(&format!("shard {bad}: ")) && !e.contains('\n'),
                "{e}"
            );
        }
        assert_eq!(parse_depth_range("0.5..1.5").unwrap(), (0.5, 1.5));
        assert_eq!(parse_contacts_range("1..3").unwrap(), (1, 3));
        assert_eq!(parse_contacts_range("2").unwrap(), (2, 2));
        for bad in ["x", "1..", "-1..2", "1.5..2"] {
            let e = parse_contacts_range(bad).unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("contacts_per_sample {bad}: ")) && !e.contains('\n'),
                "{e}"
            );
        }
        assert!(parse_depth_range("0.5-1").is_err());
    }
}
