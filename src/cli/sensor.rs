//! `geltip sensors`, `unproject` and `project`: the sensor presets and the projection map.

use anyhow::Result;
use clap::Args;
use geltip::sensor::{Sensor, PRESETS};
use glam::{DVec2, DVec3};
use serde_json::json;

#[derive(Args)]
pub struct UnprojectArgs {
    /// Preset name or path to a sensor TOML file.
    #[arg(long)]
    sensor: String,
    /// Pixel column (OpenCV convention: integer values at pixel centres).
    u: f64,
    /// Pixel row.
    v: f64,
}

#[derive(Args)]
pub struct ProjectArgs {
    #[arg(long)]
    sensor: String,
    x: f64,
    y: f64,
    z: f64,
}

/// Lists the presets with their descriptions.
pub fn sensors() -> Result<()> {
    for (name, _) in PRESETS {
        let s = Sensor::preset(name)?;
        println!("{name:10} {}", s.config.description);
    }
    Ok(())
}

/// Prints the surface point a pixel sees, as JSON.
pub fn unproject(args: UnprojectArgs) -> Result<()> {
    let sensor = Sensor::load(&args.sensor)?;
    let out = match sensor.unproject(DVec2::new(args.u, args.v)) {
        Some(sp) => json!({
            "point": sp.point.to_array(),
            "normal": sp.normal.to_array(),
            "region": sp.region.name(),
        }),
        None => json!({ "region": "none" }),
    };
    println!("{out}");
    Ok(())
}

/// Prints the pixel a point projects to (or why none), as JSON.
pub fn project(args: ProjectArgs) -> Result<()> {
    let sensor = Sensor::load(&args.sensor)?;
    let out = match sensor.project(DVec3::new(args.x, args.y, args.z)) {
        Ok(px) => json!({ "pixel": px.to_array() }),
        Err(why) => json!({ "pixel": null, "reason": why.to_string() }),
    };
    println!("{out}");
    Ok(())
}
