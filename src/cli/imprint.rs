//! `geltip imprint`: fit the imprint's look to a real sensor's labelled contact frames and
//! write the sensor file with its report and picture.

use super::under_flags;
use anyhow::Result;
use clap::builder::PossibleValuesParser;
use clap::Args;
use geltip::calibrate::imprint::{ImprintOptions, Loss};
use geltip::evaluate::real::RealSet;
use geltip::jobs::imprint;
use geltip::sensor::Sensor;
use serde_json::json;
use std::path::PathBuf;

#[derive(Args)]
pub struct ImprintArgs {
    /// The sensor whose imprint is fitted (a preset or a TOML file, e.g. one `geltip
    /// calibrate` wrote): its light, lens and finger are held.
    #[arg(long)]
    sensor: String,
    /// The real contact frames: a real set (JSON lines, as `geltip evaluate --real` reads)
    /// or the AllSight set's labels.json.
    #[arg(long)]
    real: PathBuf,
    /// Contact frames the look is fitted to, spread over the set's groups.
    #[arg(long = "fit-frames", default_value_t = ImprintOptions::default().fit_frames)]
    fit_frames: usize,
    /// Other contact frames the fitted look is scored on.
    #[arg(long = "score-frames", default_value_t = ImprintOptions::default().score_frames)]
    score_frames: usize,
    /// Pixels within this distance of an imprint's middle are compared.
    #[arg(long, default_value_t = ImprintOptions::default().window_px)]
    window: f64,
    /// Levenberg-Marquardt steps of the fit.
    #[arg(long, default_value_t = ImprintOptions::default().iterations)]
    iterations: usize,
    /// The indenter's radius (mm) the fit starts from.
    #[arg(long, default_value_t = ImprintOptions::default().start_radius_mm)]
    radius: f64,
    /// How each pixel's residual counts: soft-l1 (large residuals about linearly) or squared
    /// (as the PSNR the look is scored by).
    #[arg(long, default_value = "soft-l1", value_parser = PossibleValuesParser::new(Loss::ALL.map(Loss::name)))]
    loss: String,
    /// Directory for sensor.toml, report.json, tables.md and imprints.png.
    #[arg(long)]
    out: PathBuf,
}

/// Fits, writes the directory and prints a summary line.
pub fn imprint(args: ImprintArgs) -> Result<()> {
    let sensor = Sensor::load(&args.sensor)?;
    let set = RealSet::read(&args.real)?;
    let options = ImprintOptions {
        fit_frames: args.fit_frames,
        score_frames: args.score_frames,
        window_px: args.window,
        iterations: args.iterations,
        place_iterations: ImprintOptions::default().place_iterations,
        start_radius_mm: args.radius,
        loss: args.loss.parse()?,
    };
    let (judged, _) = imprint::run(&sensor, &set, &args.real, &options, &args.out, &|stage| {
        eprintln!("{stage}...")
    })
    .map_err(under_flags(&[]))?;
    let all = judged.rows.last().expect("the all row");
    let db = |v: f64| (v * 100.0).round() / 100.0;
    println!(
        "{}",
        json!({
            "sensor": args.out.join("sensor.toml"),
            "indenter_radius_mm": db(judged.fit.radius_mm),
            "values": judged.fit.values.iter().map(|v| (v.name.clone(), db(v.value))).collect::<std::collections::BTreeMap<_, _>>(),
            "scored_frames": all.frames,
            "composite_psnr_db": {"start": db(all.before.composite.psnr_db()), "fitted": db(all.after.composite.psnr_db()), "no_imprint": db(all.unchanged.psnr_db())},
            "render_psnr_db": {"start": db(all.before.render.psnr_db()), "fitted": db(all.after.render.psnr_db())},
            "light_psnr_db": {"windows": db(all.after.light.psnr_db()), "whole_circle": db(all.after.light_circle.psnr_db())},
            "at_bounds": judged.fit.at_bounds.iter().map(|b| &b.name).collect::<Vec<_>>(),
            "seconds": db(judged.seconds),
        })
    );
    Ok(())
}
