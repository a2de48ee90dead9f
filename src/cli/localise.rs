//! `geltip localise`: the contact in a tactile image, on the finger.

use super::under_flags;
use anyhow::Result;
use clap::Args;
use geltip::localise::{load_frame, AreaWindow, DetectorOptions, Localiser, Method};
use geltip::sensor::Sensor;
use std::path::PathBuf;

#[derive(Args)]
pub struct LocaliseArgs {
    #[arg(long)]
    sensor: String,
    /// The no-contact image of the same sensor (PNG or JPEG).
    #[arg(long)]
    reference: PathBuf,
    /// change (the default, for real and rendered frames alike: absorbs the LEDs' drift,
    /// sub-pixel shifts and clipped channels, says "no contact" when nothing stands out, and
    /// places the contact on the finger's surface), surface (noise-relative threshold,
    /// averaging on the finger's surface: rendered frames) or paper (the paper's detector).
    #[arg(long, default_value = "change")]
    method: String,
    /// The change method's decision threshold: how many noise spreads the strongest change
    /// must stand out to be a contact (default 20; lower finds fainter contacts and calls
    /// more drift a contact).
    #[arg(long)]
    threshold: Option<f64>,
    /// The change method: the sensor's noise, standard deviation in 8-bit levels (default
    /// 1); the pair's own estimate is used where larger. Raise it for a noisier camera than
    /// the pair shows.
    #[arg(long)]
    noise: Option<f64>,
    /// The change and paper methods: the contact region's area on the finger, MIN,MAX in
    /// mm^2 (MAX may be inf; from the sensor model, so the same on any sensor's pixels).
    /// Defaults: change, at least 0.15 mm^2; paper, the paper's 0.012%..0.04% of the picture.
    #[arg(long = "area-mm2", value_name = "MIN,MAX")]
    area_mm2: Option<String>,
    /// The image with the contact (PNG or JPEG).
    image: PathBuf,
}

/// Prints the detection, as JSON.
pub fn localise(args: LocaliseArgs) -> Result<()> {
    let sensor = Sensor::load(&args.sensor)?;
    let method = Method::from_name(&args.method)?;
    let reference = load_frame(&sensor, &args.reference)?;
    let frame = load_frame(&sensor, &args.image)?;
    let detection = Localiser::new(&sensor)
        .localise_with(
            &reference,
            &frame,
            method,
            &DetectorOptions {
                threshold: args.threshold,
                noise: args.noise,
                area_mm2: args
                    .area_mm2
                    .as_deref()
                    .map(AreaWindow::parse)
                    .transpose()?,
            },
        )
        .map_err(under_flags(&[]))?;
    println!("{}", detection.to_json());
    Ok(())
}
