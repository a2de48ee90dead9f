//! The `geltip` command line.

use anyhow::Result;
use clap::{Parser, Subcommand};
use geltip::sensor::{Sensor, PRESETS};
use glam::{DVec2, DVec3};
use serde_json::json;

#[derive(Parser)]
#[command(
    name = "geltip",
    version,
    about = "Simulator of the GelTip optical tactile sensor"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the sensor presets.
    Sensors,
    /// Map a pixel to the finger surface point it sees (the paper's map m).
    #[command(allow_negative_numbers = true)]
    Unproject {
        /// Preset name or path to a sensor TOML file.
        #[arg(long)]
        sensor: String,
        /// Pixel column (OpenCV convention: integer values at pixel centres).
        u: f64,
        /// Pixel row.
        v: f64,
    },
    /// Map a point on (or inside) the finger, in mm, to its pixel.
    #[command(allow_negative_numbers = true)]
    Project {
        #[arg(long)]
        sensor: String,
        x: f64,
        y: f64,
        z: f64,
    },
}

fn main() {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    if let Err(e) = run(Cli::parse()) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Sensors => {
            for (name, _) in PRESETS {
                let s = Sensor::preset(name)?;
                println!("{name:10} {}", s.config.description);
            }
        }
        Command::Unproject { sensor, u, v } => {
            let sensor = Sensor::load(&sensor)?;
            let out = match sensor.unproject(DVec2::new(u, v)) {
                Some(sp) => json!({
                    "point": sp.point.to_array(),
                    "normal": sp.normal.to_array(),
                    "region": sp.region.name(),
                }),
                None => json!({ "region": "none" }),
            };
            println!("{out}");
        }
        Command::Project { sensor, x, y, z } => {
            let sensor = Sensor::load(&sensor)?;
            let out = match sensor.project(DVec3::new(x, y, z)) {
                Ok(px) => json!({ "pixel": px.to_array() }),
                Err(why) => json!({ "pixel": null, "reason": why.to_string() }),
            };
            println!("{out}");
        }
    }
    Ok(())
}
