//! `geltip calibrate`: fit a sensor file to a real sensor's frames and write it with its
//! report and pictures.

use super::under_flags;
use anyhow::Result;
use clap::Args;
use geltip::calibrate::{FitSet, Options};
use geltip::jobs::calibrate;
use geltip::sensor::{LedKindName, Sensor};
use serde_json::json;
use std::path::PathBuf;

#[derive(Args)]
pub struct CalibrateArgs {
    /// The sensor to start from (a preset or a TOML file): its finger, lens model and field
    /// of view, and every value the frames do not fit.
    #[arg(long, default_value = "paper")]
    sensor: String,
    /// A frame of the empty finger (PNG or JPEG); repeat for several frames of the same camera (their
    /// spread gives the noise).
    #[arg(long, required = true)]
    empty: Vec<PathBuf>,
    /// Frames with known contacts: JSON lines {"image": path, "object", "at", "depth", ...}
    /// or {"image", "object", "pose"}, paths relative to the file. Fits the imprint's
    /// elastomer values.
    #[arg(long)]
    contacts: Option<PathBuf>,
    /// How many LEDs to fit; 0 takes the start sensor's listed LEDs ([[leds]]), or for a
    /// ring tries 3 to 6 and keeps the fewest that explain the frame about as well as more
    /// would.
    #[arg(long, default_value_t = 0)]
    leds: usize,
    /// Which kind of LED to fit: point (straight light) or gel (carried up the gel from the
    /// base); by default the start sensor's listed LEDs' kind, point for a ring.
    #[arg(long = "led-kind", value_parser = ["point", "gel"])]
    led_kind: Option<String>,
    /// What to fit, comma-separated, of lens (from the image circle, kept as the mask),
    /// principal and focal (the lens's principal point and focal length fitted to the light,
    /// where the circle is a mask), light, camera (colour matrix and gamma), geometry (the
    /// finger's length), imprint (from --contacts) and glow (the LEDs' glow at a clear
    /// shell's end alone, over the start's light; its [shell_end] sets led_glow_deg); the
    /// rest is held at the start sensor's values.
    #[arg(long, default_value = "lens,light,imprint")]
    fit: String,
    /// Starting rotations of the LEDs tried (more find a better fit more often, and take
    /// longer).
    #[arg(long, default_value_t = geltip::calibrate::DEFAULT_STARTS)]
    starts: usize,
    /// Directory for sensor.toml, report.json and the pictures (real, calibrated, residual,
    /// comparison).
    #[arg(long)]
    out: PathBuf,
}

/// Calibrates, writes the directory and prints a summary line.
pub fn calibrate(args: CalibrateArgs) -> Result<()> {
    let start = Sensor::load(&args.sensor)?;
    let mut options = Options::new(start, args.empty);
    options.contacts = args.contacts;
    options.leds = args.leds;
    options.starts = args.starts;
    options.fit = FitSet::parse(&args.fit).map_err(under_flags(&[("fit", "--fit")]))?;
    options.led_kind = args
        .led_kind
        .as_deref()
        .map(LedKindName::from_name)
        .transpose()
        .map_err(under_flags(&[("led_kind", "--led-kind")]))?;
    let outcome = calibrate::run(&options, &args.out, &|stage| eprintln!("{stage}..."))
        .map_err(under_flags(&[]))?;
    let judged = &outcome.judged;
    let c = &judged.calibration;
    println!(
        "{}",
        json!({
            "sensor": args.out.join("sensor.toml"),
            "leds": c.leds,
            "image_circle": {
                "centre": [round(c.circle.centre.x), round(c.circle.centre.y)],
                "radius": round(c.circle.radius),
            },
            "psnr_db": {"before": round(judged.before.psnr_db), "after": round(judged.after.psnr_db)},
            "ssim": {"before": round(judged.before.ssim), "after": round(judged.after.ssim)},
            "at_bounds": c.at_bounds.iter().map(|b| &b.name).collect::<Vec<_>>(),
            "seconds": round(judged.seconds),
        })
    );
    Ok(())
}

fn round(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}
