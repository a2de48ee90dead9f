//! Calibration speed and quality: `cargo bench --bench calibrate [-- --frame PNG ...]
//! [--leds N] [--starts N]`. Prints a table: for each empty frame, the LEDs fitted, the
//! seconds `geltip calibrate` takes (fit, renders of the start and the calibrated sensor,
//! files), the image circle, and PSNR and SSIM inside the circle before and after (target:
//! one empty frame in <= 60 s on the 2-core machine).
//!
//! Without `--frame`, a synthetic frame: the paper sensor with its lens moved and refocused,
//! other LEDs (colours, places, intensities) and noise of 2 levels, the values hidden from
//! the fit. With `--frame`, real frames, e.g. the GelTip empty frame of
//! github.com/danfergo/geltip-simulation (experimental_setup/geltip/sim_assets/bkg.png).

use geltip::calibrate::Options;
use geltip::host_speed::HostSpeed;
use geltip::jobs::calibrate;
use geltip::render::gpu::Renderer;
use geltip::sensor::{LedConfig, Leds, Noise, Sensor};
use std::path::PathBuf;

fn main() -> anyhow::Result<()> {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| args.windows(2).find(|w| w[0] == flag).map(|w| w[1].clone());
    let leds: usize = value("--leds").map(|v| v.parse()).transpose()?.unwrap_or(0);
    let starts: usize = value("--starts")
        .map(|v| v.parse())
        .transpose()?
        .unwrap_or(8);
    let dir = std::env::temp_dir().join(format!("geltip-bench-calibrate-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir)?;
    let mut frames: Vec<PathBuf> = args
        .windows(2)
        .filter(|w| w[0] == "--frame")
        .map(|w| PathBuf::from(&w[1]))
        .collect();
    if frames.is_empty() {
        let path = dir.join("synthetic.png");
        Renderer::new(&hidden_sensor()?)?
            .render_empty()?
            .to_rgb()
            .save(&path)?;
        frames.push(path);
    }
    let host = HostSpeed::measure();
    println!(
        "geltip calibrate; host loop {:.2} ms on one core, {:.2} ms on all",
        host.one_core_ms, host.all_cores_ms
    );
    println!("| frame | LEDs | seconds | circle (cx, cy, r) | PSNR dB before -> after | SSIM before -> after |");
    println!("|---|---|---|---|---|---|");
    for frame in &frames {
        let mut options = Options::new(Sensor::preset("paper")?, vec![frame.clone()]);
        options.leds = leds;
        options.starts = starts;
        let out = calibrate::judge(&options, &|_| {})?;
        let c = &out.calibration.circle;
        println!(
            "| {} | {} | {:.1} | {:.2}, {:.2}, {:.2} | {:.2} -> {:.2} | {:.3} -> {:.3} |",
            frame.display(),
            out.calibration.leds,
            out.seconds,
            c.centre.x,
            c.centre.y,
            c.radius,
            out.before.psnr_db,
            out.after.psnr_db,
            out.before.ssim,
            out.after.ssim
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// The sensor whose empty frame the synthetic row calibrates to.
fn hidden_sensor() -> anyhow::Result<Sensor> {
    let mut c = Sensor::preset("paper")?.config;
    c.lens.focal_px *= 0.93;
    c.lens.cx -= 8.0;
    c.lens.cy += 5.0;
    let led = |colour: [f64; 3], azimuth_deg: f64, z_mm: f64, intensity: f64| LedConfig {
        z_mm,
        intensity,
        ..LedConfig::new(colour, azimuth_deg)
    };
    c.leds = Leds::List(vec![
        led([1.0, 0.3, 0.5], 60.0, -2.5, 2.6),
        led([0.3, 1.0, 0.3], 170.0, -1.0, 1.7),
        led([0.4, 0.5, 1.0], 300.0, -3.5, 2.2),
    ]);
    c.render.noise = Noise::Grey(2.0);
    Ok(Sensor::from_config("hidden", c)?)
}
