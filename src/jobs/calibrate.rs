//! `geltip calibrate`: a sensor file fitted to a real sensor's frames ([`crate::calibrate`]),
//! judged by rendering it and comparing with the frames, and written with its report and
//! pictures to a directory.

use crate::calibrate::{self, quality, Calibration, Options};
use crate::error::{GeltipError, Result};
use crate::output;
use crate::render::gpu::Renderer;
use crate::sensor::{Sensor, SensorConfig};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How close a render of the empty finger is to the real empty frame, inside the circle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Likeness {
    pub psnr_db: f64,
    pub ssim: f64,
}

/// A calibration judged: the fitted sensor, its file's text, the renders of the start and
/// the calibrated sensor against the frame, and the report; nothing written yet.
#[derive(Debug)]
pub struct Judged {
    pub calibration: Calibration,
    /// The calibrated sensor, as `sensor.toml` loads.
    pub sensor: Sensor,
    pub sensor_toml: String,
    /// The start sensor's empty finger against the frame, and the calibrated one's.
    pub before: Likeness,
    pub after: Likeness,
    /// The calibrated sensor's empty finger.
    pub render: image::RgbImage,
    /// report.json's content.
    pub report: Value,
    pub seconds: f64,
}

/// What a run gives back: the judged calibration and the files written.
#[derive(Debug)]
pub struct Outcome {
    pub judged: Judged,
    pub files: Vec<PathBuf>,
}

/// Pixels compared: those at least this far (px) inside the image circle.
pub const MARGIN_PX: f64 = 2.0;

/// Calibrates, renders the start and the calibrated sensor, writes `out`'s files.
pub fn run(options: &Options, out: &Path, progress: &dyn Fn(&str)) -> Result<Outcome> {
    let judged = judge(options, progress)?;
    progress("writing");
    let files = write(&judged, out)?;
    Ok(Outcome { judged, files })
}

/// Calibrates and judges the result by rendering it; writes nothing.
pub fn judge(options: &Options, progress: &dyn Fn(&str)) -> Result<Judged> {
    let started = Instant::now();
    let calibration = calibrate::calibrate(options, progress)?;
    progress("rendering the calibrated sensor");
    let sensor_toml = sensor_toml(&calibration.config)?;
    // The file must load back as exactly what was fitted: every command reads it.
    let sensor = Sensor::from_toml("calibrated", &sensor_toml)?;
    if sensor.config != calibration.config {
        return Err(GeltipError::input(
            "sensor.toml",
            "the written file does not load back as the fitted sensor",
        ));
    }
    let real = &calibration.empty;
    let (w, h) = real.dimensions();
    let mut start = options.start.config.clone();
    start.image.width = w;
    start.image.height = h;
    let start = Sensor::from_config(options.start.name.clone(), start)?;
    let before_img = Renderer::new(&start)?.reference().to_rgb();
    let render = Renderer::new(&sensor)?.reference().to_rgb();
    let circle = calibration.circle;
    let mask = |x: u32, y: u32| circle.contains(x, y, MARGIN_PX);
    let likeness = |img: &image::RgbImage| Likeness {
        psnr_db: quality::psnr(img.as_raw(), real.as_raw(), w, mask),
        ssim: quality::ssim(img.as_raw(), real.as_raw(), w, h, mask),
    };
    let before = likeness(&before_img);
    let after = likeness(&render);
    let seconds = started.elapsed().as_secs_f64();
    let report = report_json(&calibration, options, before, after, seconds);
    Ok(Judged {
        calibration,
        sensor,
        sensor_toml,
        before,
        after,
        render,
        report,
        seconds,
    })
}

/// Writes `out`/sensor.toml, report.json and the pictures (real, calibrated, residual and
/// the three side by side), each file whole or not at all.
pub fn write(judged: &Judged, out: &Path) -> Result<Vec<PathBuf>> {
    let real = &judged.calibration.empty;
    let mut files = Vec::new();
    let path = out.join("sensor.toml");
    output::write_atomic(&path, judged.sensor_toml.as_bytes())?;
    files.push(path);
    let residual = residual_image(&judged.render, real);
    let side = side_by_side(&[real, &judged.render, &residual]);
    for (name, img) in [
        ("real.png", real),
        ("calibrated.png", &judged.render),
        ("residual.png", &residual),
        ("comparison.png", &side),
    ] {
        let path = out.join(name);
        output::write_png_rgb8(&path, img.width(), img.height(), img.as_raw())?;
        files.push(path);
    }
    let path = out.join("report.json");
    output::write_json(&path, &judged.report)?;
    files.push(path);
    Ok(files)
}

/// The configuration as a sensor file, with a header saying what made it.
pub fn sensor_toml(config: &SensorConfig) -> Result<String> {
    let body = toml::to_string_pretty(config)
        .map_err(|e| GeltipError::input("sensor.toml", e.to_string()))?;
    Ok(format!(
        "# Written by geltip calibrate {}: a complete sensor file; every command takes it.\n{body}",
        env!("CARGO_PKG_VERSION")
    ))
}

/// The calibrated render less the real frame, at twice the difference about mid grey:
/// grey where they agree, brighter where the render is brighter.
fn residual_image(render: &image::RgbImage, real: &image::RgbImage) -> image::RgbImage {
    let raw = residual_values(render.as_raw(), real.as_raw());
    image::RgbImage::from_raw(render.width(), render.height(), raw).expect("same size")
}

/// `render` less `real`, value by value, at twice the difference about mid grey.
pub(crate) fn residual_values(render: &[u8], real: &[u8]) -> Vec<u8> {
    render
        .iter()
        .zip(real)
        .map(|(&a, &b)| {
            (128.0 + 2.0 * (a as f64 - b as f64))
                .round()
                .clamp(0.0, 255.0) as u8
        })
        .collect()
}

/// Images of one size set left to right.
fn side_by_side(images: &[&image::RgbImage]) -> image::RgbImage {
    let (w, h) = images[0].dimensions();
    let mut out = image::RgbImage::new(w * images.len() as u32, h);
    for (k, img) in images.iter().enumerate() {
        for (x, y, p) in img.enumerate_pixels() {
            out.put_pixel(x + k as u32 * w, y, *p);
        }
    }
    out
}

fn report_json(
    c: &Calibration,
    options: &Options,
    before: Likeness,
    after: Likeness,
    seconds: f64,
) -> Value {
    let finite = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
    json!({
        "start_sensor": options.start.name,
        "empty_frames": options.empty,
        "frames_averaged": c.frames,
        "contacts": options.contacts,
        "leds": c.leds,
        "image_circle": {
            "centre": [c.circle.centre.x, c.circle.centre.y],
            "radius": c.circle.radius,
            "edge_points": c.circle.points,
            "edge_rms_px": c.circle.rms_px,
        },
        "inside_circle": {
            "margin_px": MARGIN_PX,
            "psnr_db": {"before": finite(before.psnr_db), "after": finite(after.psnr_db)},
            "ssim": {"before": finite(before.ssim), "after": finite(after.ssim)},
        },
        "values": c.values.iter().map(|v| json!({
            "name": v.name,
            "value": v.value,
            "std_error": finite(v.std_error),
        })).collect::<Vec<_>>(),
        "unconstrained": c.unconstrained,
        "fitted": c.fit.names(),
        "at_bounds": c.at_bounds.iter().map(|b| json!({
            "name": b.name,
            "value": b.value,
            "bound": b.side,
        })).collect::<Vec<_>>(),
        "fit": {
            "robust_cost": c.fit_cost,
            "iterations": c.fit_iterations,
            "starts": c.starts.iter().map(|s| json!({"leds": s.leds, "rotation_deg": s.rotation_deg, "coarse_cost": s.cost})).collect::<Vec<_>>(),
        },
        "imprint": c.contacts.as_ref().map(|f| json!({
            "frames": f.frames,
            "change_rms_before": f.rms_before,
            "change_rms_after": f.rms_after,
            "renders": f.renders,
        })),
        "seconds": seconds,
    })
}
