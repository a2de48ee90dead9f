//! `geltip dataset`: a labelled synthetic dataset, or shards merged into one.

use super::{progress, under_flags};
use anyhow::{Context, Result};
use clap::Args;
use geltip::jobs::dataset;
use geltip::sensor::{Noise, Sensor};
use serde_json::json;
use std::path::PathBuf;

#[derive(Args)]
pub struct DatasetArgs {
    /// Preset name or path to a sensor TOML file.
    #[arg(long, required_unless_present = "merge")]
    sensor: Option<String>,
    /// Samples in the whole set (all shards).
    #[arg(long, required_unless_present = "merge")]
    count: Option<u64>,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Directory of the set (or of this shard).
    #[arg(long, required_unless_present = "merge", conflicts_with = "merge")]
    out: Option<PathBuf>,
    /// Comma-separated built-in solids, sized primitives (box:x=10,y=6,z=4 keeps its
    /// commas) and/or mesh files (default: the seven solids).
    #[arg(long)]
    objects: Vec<String>,
    /// Press depths, mm, as min..max (default: 0.2 to the gel's thickness).
    #[arg(long = "depth-range")]
    depth_range: Option<String>,
    /// Render shard i of n (a contiguous block of indices) into --out.
    #[arg(long)]
    shard: Option<String>,
    /// Also write depth/<k>.npy: the indentation (mm) each pixel sees.
    #[arg(long = "depth-maps")]
    depth_maps: bool,
    /// Also write masks/<k>.png: 255 where the skin is pressed in.
    #[arg(long)]
    masks: bool,
    /// Sensor noise, std in 8-bit grey levels (default: the sensor's).
    #[arg(long)]
    noise: Option<f64>,
    /// Per-sample gain of each colour channel drawn from 1 ± this.
    #[arg(long = "light-jitter", default_value_t = 0.0)]
    light_jitter: f64,
    /// Per-sample gain of the tactile change drawn from 1 ± this.
    #[arg(long = "paint-jitter", default_value_t = 0.0)]
    paint_jitter: f64,
    /// How far each image's light drifts from its empty frame's, as a real sensor's LEDs
    /// do (0 to 1; 1: a sector's channel up to 40% brighter or darker, each channel's gain
    /// 1 ± 12%, offsets up to ± 5 levels): for detectors that must not call drift a contact.
    #[arg(long, default_value_t = 0.0)]
    drift: f64,
    /// A real sensor's empty frame (same size): images are it plus the rendered change. A
    /// folder of them (PNG, JPEG): each sample is put on one, drawn from the seed and its
    /// index; its label names it and its empty frame (references/<name>.png).
    #[arg(long)]
    background: Option<PathBuf>,
    /// Share of samples that are empty frames, labelled with no contact (for counting a
    /// detector's false positives). Labels then take the scene form {"contacts": [...]}.
    #[arg(long = "empty-fraction", default_value_t = 0.0)]
    empty_fraction: f64,
    /// Contacts per (non-empty) sample: n or min..max, drawn uniformly. Above one, labels
    /// take the scene form {"contacts": [...]}, as render --scene writes them.
    #[arg(long = "contacts-per-sample")]
    contacts_per_sample: Option<String>,
    /// PNG compression: none, fast, default, best.
    #[arg(long, default_value = "fast")]
    png: String,
    /// Encoder threads (default: the cores available).
    #[arg(long)]
    jobs: Option<usize>,
    /// Render streams, each a renderer on a device of its own (default 3; 1..=4).
    #[arg(long)]
    streams: Option<usize>,
    /// Join shard directories into OUT: --merge OUT SHARD_DIR...
    #[arg(long, num_args = 2.., value_name = "DIR")]
    merge: Vec<PathBuf>,
}

/// Renders the set (or merges shards) and prints a summary as JSON.
pub fn dataset(args: DatasetArgs) -> Result<()> {
    let command: Vec<String> = std::env::args().collect();
    if let Some((out, shards)) = args.merge.split_first() {
        let n = dataset::merge(out, shards, &command)
            .map_err(under_flags(&[("out", "--merge"), ("shards", "--merge")]))?;
        println!("{}", json!({ "merged": out, "samples": n }));
        return Ok(());
    }
    let out = args.out.clone().context("--out is required")?;
    let mut spec = args.spec()?;
    spec.command = command;
    let report = dataset::run(&spec, Some(&out), progress::reporter("samples")?)
        .map_err(under_flags(&[]))?;
    println!(
        "{}",
        json!({
            "out": out,
            "samples": report.shard_samples,
            "kept": report.kept,
            "rendered": report.rendered,
            "samples_per_s": report.rendered as f64 / report.wall.as_secs_f64().max(1e-9),
        })
    );
    Ok(())
}

impl DatasetArgs {
    /// The set the flags describe; an error about one of the set's options names its flag.
    fn spec(self) -> Result<dataset::Spec> {
        let flag = under_flags(&[]);
        let (sensor_arg, count) = (
            self.sensor.context("--sensor is required")?,
            self.count.context("--count is required")?,
        );
        let sensor = Sensor::load(&sensor_arg)?;
        let mut spec = dataset::Spec::new(&sensor_arg, sensor, count, self.seed);
        if !self.objects.is_empty() {
            spec.objects = self
                .objects
                .iter()
                .flat_map(|list| geltip::object::primitive::split_objects(list))
                .collect();
        }
        if let Some(r) = self.depth_range {
            spec.depth_range = dataset::parse_depth_range(&r).map_err(&flag)?;
        }
        if let Some(s) = self.shard {
            spec.shard = dataset::Shard::parse(&s).map_err(&flag)?;
        }
        spec.depth_maps = self.depth_maps;
        spec.masks = self.masks;
        spec.noise = self
            .noise
            .map_or(spec.sensor.config.render.noise, Noise::from);
        spec.light_jitter = self.light_jitter;
        spec.paint_jitter = self.paint_jitter;
        spec.drift = self.drift;
        spec.background = self.background;
        spec.empty_fraction = self.empty_fraction;
        if let Some(c) = self.contacts_per_sample {
            spec.contacts_per_sample = dataset::parse_contacts_range(&c).map_err(&flag)?;
        }
        spec.png = dataset::PngLevel::from_name(&self.png).map_err(&flag)?;
        spec.workers = self.jobs.unwrap_or(spec.workers);
        spec.streams = self.streams.unwrap_or(spec.streams);
        Ok(spec)
    }
}
