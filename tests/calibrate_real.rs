//! Calibration on real sensors' frames, from `../shared/real` (see its README for where each
//! frame comes from; the frames are not part of the repository): the AllSight's two
//! sessions' first frames and the GelTip's empty frame, each fitted with the geometry its
//! sensor file states held. Skipped, with a message, where the folder is absent.

mod common;

use anyhow::Result;
use common::real;
use geltip::calibrate::{self, quality, FitSet, Options};
use geltip::jobs::calibrate::MARGIN_PX;
use geltip::render::gpu::Renderer;
use geltip::sensor::Sensor;
use std::path::PathBuf;

/// Fewer samples than the command's default: the test runs in the dev profile.
fn quick(start: Sensor, empty: PathBuf) -> Options {
    let mut o = Options::new(start, vec![empty]);
    o.samples = 6000;
    o
}

/// PSNR inside the circle between `config`'s empty finger and the frame calibration read.
fn psnr(c: &calibrate::Calibration, config: geltip::sensor::SensorConfig) -> f64 {
    let frame = &c.empty;
    let mut config = config;
    config.image.width = frame.width();
    config.image.height = frame.height();
    let sensor = Sensor::from_config("compared", config).unwrap();
    let render = Renderer::new(&sensor).unwrap().reference().to_rgb();
    quality::psnr(render.as_raw(), frame.as_raw(), frame.width(), |x, y| {
        c.circle.contains(x, y, MARGIN_PX)
    })
}

/// Both AllSight sessions' first frames: at least 28 dB inside the image circle from the
/// `allsight` preset with its geometry held, and the finger exactly the preset's. The same
/// frames under the light model geltip had before (point LEDs, no camera response, no clear
/// shell end) stay under 28 dB, so the target is the new terms' doing.
#[test]
fn allsight_first_frames_reach_28_db_with_the_geometry_held() -> Result<()> {
    let Some(dir) = real("allsight") else {
        return Ok(());
    };
    let start = Sensor::preset("allsight")?;
    for session in ["s1", "s2"] {
        let frame = dir.join(format!("{session}_ref_frame.jpg"));
        let c = calibrate::calibrate(&quick(start.clone(), frame.clone()), &|_| {})?;
        assert_eq!(
            c.config.finger, start.config.finger,
            "{session}: geometry moved"
        );
        let after = psnr(&c, c.config.clone());
        eprintln!(
            "{session}: {after:.2} dB, {} LEDs, at bounds {:?}",
            c.leds, c.at_bounds
        );
        assert!(after >= 28.0, "{session}: {after:.2} dB");
        assert_eq!(c.leds, 9);
        // The shell's open end is what lights the tip: the preset as shipped, with and
        // without its [shell_end], against the frame.
        let with = psnr(&c, start.config.clone());
        let mut plain = start.config.clone();
        plain.shell_end = None;
        if let geltip::sensor::Leds::List(list) = &mut plain.leds {
            list.iter_mut().for_each(|l| l.end_glow = [0.0; 3]);
        }
        let without = psnr(&c, plain.clone());
        eprintln!("{session}: the preset {with:.2} dB, without its shell end {without:.2} dB");
        assert!(
            with >= without + 1.0,
            "{session}: the shell end buys {:.2} dB",
            with - without
        );
        if session == "s1" {
            // Neither the shell's end nor its glow: point LEDs would light the rim through it.
            let mut old = quick(Sensor::from_config("plain", plain)?, frame);
            old.fit = FitSet::parse("lens,light")?;
            old.led_kind = Some(geltip::sensor::LedKindName::Point);
            old.starts = 2;
            let before = calibrate::calibrate(&old, &|_| {})?;
            let point = psnr(&before, before.config.clone());
            eprintln!("{session}: point LEDs without the camera: {point:.2} dB");
            assert!(point < 28.0, "point LEDs alone reach {point:.2} dB");
        }
    }
    Ok(())
}

/// The GelTip's empty frame from the `paper` preset: the image circle within 2 px of the
/// authors' mask (radius 240 at (320, 240)), the finger held, and 33 dB inside the circle
/// (within the quicker sample's spread) with the lens's principal point and focal length
/// fitted to the light.
#[test]
fn geltip_empty_frame_with_the_geometry_held() -> Result<()> {
    let Some(dir) = real("geltip") else {
        return Ok(());
    };
    let start = Sensor::preset("paper")?;
    // The authors' circle is a mask: the lens's principal point and focal length are fitted
    // to the light, the finger held.
    let mut options = quick(start.clone(), dir.join("empty.png"));
    options.fit = FitSet::parse("lens,principal,focal,light")?;
    let c = calibrate::calibrate(&options, &|_| {})?;
    let centre = &c.circle.centre;
    assert!(
        (centre.x - 320.0).hypot(centre.y - 240.0) < 2.0 && (c.circle.radius - 240.0).abs() < 2.0,
        "circle {:?} r {}",
        c.circle.centre,
        c.circle.radius
    );
    assert_eq!(c.config.finger, start.config.finger, "geometry moved");
    let after = psnr(&c, c.config.clone());
    let before = psnr(&c, start.config.clone());
    eprintln!(
        "GelTip: {before:.2} -> {after:.2} dB, at bounds {:?}",
        c.at_bounds
    );
    // The command's full sample reaches 33.0 dB (README); this quicker sample 32.98.
    assert!(
        after >= 32.8 && before < 15.0,
        "{before:.2} -> {after:.2} dB"
    );
    // The mask stays where the frame cuts its picture; the lens moved inside it.
    assert_eq!(
        c.config.image.circle,
        Some([c.circle.centre.x, c.circle.centre.y, c.circle.radius])
    );
    Ok(())
}
