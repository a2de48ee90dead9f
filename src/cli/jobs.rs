//! `geltip experiment`, `preview`, `stability`, `tradeoff` and `objects`: the jobs that
//! write a directory of results and print their tables.

use super::{progress, under_flags};
use anyhow::Result;
use clap::Args;
use geltip::jobs::experiment::{self, Protocol};
use geltip::jobs::{preview, stability, tradeoff};
use geltip::localise::Method;
use geltip::object::Solid;
use geltip::sensor::Sensor;
use serde_json::json;
use std::path::PathBuf;

#[derive(Args)]
pub struct ExperimentArgs {
    /// Which experiment (only `paper` for now).
    #[arg(value_parser = ["paper"])]
    name: String,
    #[arg(long)]
    sensor: String,
    /// Directory for images, labels, taps.csv, tables.md and the chart.
    #[arg(long)]
    out: PathBuf,
    /// Press depth of every tap, mm.
    #[arg(long, default_value_t = 1.0)]
    depth: f64,
    /// Azimuth of the tapped side, degrees.
    #[arg(long, default_value_t = 0.0)]
    azimuth: f64,
}

/// Runs the paper's protocol and prints its tables.
pub fn experiment(args: ExperimentArgs) -> Result<()> {
    let sensor = Sensor::load(&args.sensor)?;
    let protocol = Protocol {
        depth_mm: args.depth,
        azimuth_deg: args.azimuth,
        ..Protocol::default()
    };
    let bar = progress::bar("taps", "{msg}")?;
    bar.set_length((Solid::ALL.len() * experiment::POSITIONS.len()) as u64);
    let report = experiment::run(&sensor, &protocol, Some(&args.out), |name| {
        bar.set_message(name.to_string());
        bar.inc(1);
    })?;
    bar.finish_and_clear();
    println!("{}", report.tables_markdown());
    println!(
        "Wrote {}: images/, labels/, taps.csv, tables.md, errors_per_position.svg",
        args.out.display()
    );
    Ok(())
}

#[derive(Args)]
pub struct PreviewArgs {
    /// Comma-separated presets or sensor TOML files.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "paper,webcam70,tube13,tube21"
    )]
    sensors: Vec<String>,
    /// Directory for the pictures, charts and table.
    #[arg(long)]
    out: PathBuf,
    /// Lens sweep of the first design: equidistant fisheye fields of view <from>:<to>:<step>
    /// in degrees ("none" to skip).
    #[arg(long, default_value = "120:200:10")]
    sweep_fov: String,
    /// Skip the rendered pictures (geometry only, no GPU).
    #[arg(long)]
    no_pictures: bool,
}

/// The preview's options whose flags have other names.
const PREVIEW_FLAGS: &[(&str, &str)] = &[("designs", "--sensors"), ("sweep_fovs", "--sweep-fov")];

/// Previews the designs and prints their table and the sweep's best lens.
pub fn preview(args: PreviewArgs) -> Result<()> {
    let designs = args
        .sensors
        .iter()
        .map(|s| Sensor::load(s.trim()))
        .collect::<geltip::Result<Vec<_>>>()?;
    let fovs = if args.sweep_fov == "none" {
        vec![]
    } else {
        preview::parse_range(&args.sweep_fov).map_err(under_flags(PREVIEW_FLAGS))?
    };
    let report = preview::run(
        &designs,
        &fovs,
        Some(&args.out),
        !args.no_pictures,
        |name| {
            eprintln!("previewed {name}");
        },
    )
    .map_err(under_flags(PREVIEW_FLAGS))?;
    println!("{}", preview::table_markdown(&report.designs));
    if let Some((_, best)) = report.best_sweep() {
        println!("Best lens of the sweep: {}", best.lens);
    }
    println!(
        "Wrote {}: preview.md, preview.csv, resolution.svg, lens_sweep.svg, <design>.png",
        args.out.display()
    );
    Ok(())
}

#[derive(Args)]
pub struct StabilityArgs {
    #[arg(long)]
    sensor: String,
    #[arg(long)]
    out: PathBuf,
    /// Detectors to test (comma separated): paper, surface.
    #[arg(long, value_delimiter = ',', default_value = "paper,surface")]
    method: Vec<String>,
    /// Arc-length positions per azimuth, tip to lens edge (plus both sides of the junction).
    #[arg(long, default_value_t = 3)]
    positions: usize,
    /// Azimuths round the finger.
    #[arg(long, default_value_t = 2)]
    azimuths: usize,
    /// Press depths (mm, comma separated); default 0.01 .. the shell thickness.
    #[arg(long, value_delimiter = ',')]
    depths: Option<Vec<f64>>,
    /// Sensor noise of the noisy pass (8-bit grey levels); 0 skips it. Default 2, or 0 for a
    /// sensor whose camera blurs (camera.blur_px), which would blur the noise.
    #[arg(long)]
    noise: Option<f64>,
}

/// Runs the sweep and prints its table.
pub fn stability(args: StabilityArgs) -> Result<()> {
    let sensor = Sensor::load(&args.sensor)?;
    let mut sweep = stability::Sweep::default_for(&sensor);
    sweep.methods = args
        .method
        .iter()
        .map(|m| Method::from_name(m.trim()))
        .collect::<geltip::Result<_>>()?;
    sweep.positions = args.positions;
    sweep.azimuths = args.azimuths;
    if let Some(d) = args.depths {
        sweep.depths = d;
    }
    if let Some(noise) = args.noise {
        geltip::checks::non_negative(noise)
            .map_err(|reason| anyhow::anyhow!("--noise: {reason}"))?;
        sweep.noise = noise;
    }
    let bar = progress::bar_or_lines("contacts")?;
    let report = stability::run(&sensor, &sweep, Some(&args.out), |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })
    .map_err(under_flags(&[("methods", "--method")]))?;
    bar.finish_and_clear();
    println!("{}", report.markdown());
    println!(
        "Wrote {}: stability.md, stability.csv, detection_rate.svg, error_map.svg",
        args.out.display()
    );
    Ok(())
}

#[derive(Args)]
pub struct TradeoffArgs {
    #[arg(long)]
    sensor: String,
    #[arg(long)]
    out: PathBuf,
    /// Also every texels x steps pair (128..512 x 4..32), image scale 0.75, voxel 0.125 mm,
    /// and all eight contacts instead of four.
    #[arg(long)]
    full: bool,
    /// Speed rounds per configuration (the median is kept).
    #[arg(long, default_value_t = 3)]
    rounds: usize,
}

/// Measures the knobs and prints the table.
pub fn tradeoff(args: TradeoffArgs) -> Result<()> {
    let sensor = Sensor::load(&args.sensor)?;
    let configs = tradeoff::configurations(&sensor, args.full);
    let bar = progress::bar_or_lines("configurations")?;
    bar.set_length((configs.len() + args.rounds) as u64);
    let contacts = tradeoff::contacts(args.full);
    let report = tradeoff::run(
        &sensor,
        &configs,
        &contacts,
        args.rounds,
        Some(&args.out),
        |label| {
            bar.set_message(label.to_string());
            bar.inc(1);
        },
    )?;
    bar.finish_and_clear();
    println!("{}", report.markdown());
    println!(
        "Wrote {}: tradeoff.md, tradeoff.csv, tradeoff.svg",
        args.out.display()
    );
    Ok(())
}

#[derive(Args)]
pub struct ObjectsArgs {
    /// Directory to write into.
    #[arg(long, default_value = "assets/objects")]
    out: PathBuf,
}

/// Writes the built-in solids as OBJ files.
pub fn objects(args: ObjectsArgs) -> Result<()> {
    geltip::object::write_builtin_objects(&args.out)?;
    println!("{}", json!({ "written": args.out }));
    Ok(())
}
