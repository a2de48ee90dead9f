//! `geltip calibrate` on frames rendered from sensors whose values the test hides: the lens
//! and the light come back within the issue's tolerances, a saturated channel and seams do
//! not throw the fit off, known contacts give back the imprint's values, and bad frames are
//! refused on one line. Each check is also shown failing for the start sensor, so that a
//! fit that did nothing could not pass it.

use anyhow::Result;
use geltip::calibrate::{self, quality, Options};
use geltip::render::gpu::Renderer;
use geltip::sensor::{LedConfig, Leds, Noise, Sensor};
use std::path::{Path, PathBuf};

/// The paper sensor with its lens moved and refocused and other LEDs: colours, places and
/// intensities changed.
fn hidden_sensor() -> Sensor {
    let mut c = Sensor::preset("paper").unwrap().config;
    c.lens.focal_px *= 1.08;
    c.lens.cx += 7.0;
    c.lens.cy -= 6.0;
    let led = |colour: [f64; 3], azimuth_deg: f64, z_mm: f64, intensity: f64| LedConfig {
        z_mm,
        intensity,
        ..LedConfig::new(colour, azimuth_deg)
    };
    c.leds = Leds::List(vec![
        led([1.0, 0.35, 0.6], 105.0, -1.5, 1.8),
        led([0.25, 1.0, 0.4], 230.0, -2.5, 2.4),
        led([0.5, 0.45, 1.0], 340.0, -3.0, 2.1),
    ]);
    c.light.ambient = Some([0.05, 0.04, 0.08]);
    Sensor::from_config("hidden", c).unwrap()
}

/// Writes `n` empty frames of `sensor` (each with fresh noise when it has noise) into `dir`.
fn empty_frames(sensor: &Sensor, n: usize, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut renderer = Renderer::new(sensor)?;
    (0..n)
        .map(|k| {
            let path = dir.join(format!("empty{k}.png"));
            renderer.render_empty()?.to_rgb().save(&path)?;
            Ok(path)
        })
        .collect()
}

/// Fewer samples and starts than the command's defaults: the test runs in the dev profile.
fn quick(start: Sensor, empty: Vec<PathBuf>) -> Options {
    let mut o = Options::new(start, empty);
    o.samples = 6000;
    o.starts = 4;
    o
}

/// PSNR inside the circle (2 px in) between `sensor`'s empty finger and `frame`.
fn psnr_against(
    sensor: &Sensor,
    frame: &image::RgbImage,
    circle: &calibrate::circle::ImageCircle,
) -> f64 {
    let mut c = sensor.config.clone();
    c.image.width = frame.width();
    c.image.height = frame.height();
    let s = Sensor::from_config("compared", c).unwrap();
    let render = Renderer::new(&s).unwrap().reference().to_rgb();
    quality::psnr(render.as_raw(), frame.as_raw(), frame.width(), |x, y| {
        circle.contains(x, y, 2.0)
    })
}

fn value(c: &calibrate::Calibration, name: &str) -> f64 {
    c.values
        .iter()
        .find(|v| v.name == name)
        .unwrap_or_else(|| panic!("no value {name}"))
        .value
}

#[test]
fn a_hidden_lens_and_light_come_back() -> Result<()> {
    let dir = tempdir("hidden")?;
    let mut hidden = hidden_sensor().config;
    hidden.render.noise = Noise::Rgb([2.0, 1.5, 2.5]);
    hidden.render.noise_seed = 3;
    let hidden = Sensor::from_config("hidden", hidden)?;
    let frames = empty_frames(&hidden, 3, &dir)?;
    let start = Sensor::preset("paper")?;
    let c = calibrate::calibrate(&quick(start.clone(), frames), &|_| {})?;
    // Tried with 3 to 6, the fit keeps the hidden sensor's 3 LEDs.
    assert_eq!(c.leds, 3);
    // The finger the sensor file states is held unless the geometry is asked for.
    assert_eq!(c.config.finger, start.config.finger);

    let truth = &hidden.config.lens;
    let focal = value(&c, "lens.focal_px");
    let centre = (value(&c, "lens.cx") - truth.cx).hypot(value(&c, "lens.cy") - truth.cy);
    assert!(
        (focal / truth.focal_px - 1.0).abs() < 0.01,
        "focal {focal} vs {}",
        truth.focal_px
    );
    assert!(centre < 1.0, "centre {centre} px off");
    // The start sensor fails the same checks: 8% off in focal length, 9 px in centre.
    let s = &start.config.lens;
    assert!((s.focal_px / truth.focal_px - 1.0).abs() > 0.01);
    assert!((s.cx - truth.cx).hypot(s.cy - truth.cy) > 1.0);

    let fitted = Sensor::from_config("fitted", c.config.clone())?;
    let after = psnr_against(&fitted, &c.empty, &c.circle);
    let before = psnr_against(&start, &c.empty, &c.circle);
    eprintln!(
        "focal {focal:.2} (truth {:.2}), centre {centre:.3} px off, PSNR {before:.2} -> {after:.2} dB, noise {:?}",
        truth.focal_px,
        c.config.render.noise.rgb()
    );
    assert!(after >= 35.0, "re-rendered PSNR {after:.2} dB");
    assert!(
        before < 35.0,
        "the start sensor already scores {before:.2} dB"
    );

    // Three frames give the noise, channel by channel.
    let noise = c.config.render.noise.rgb();
    for (got, want) in noise.iter().zip([2.0, 1.5, 2.5]) {
        assert!((got - want).abs() < 0.25, "noise {noise:?}");
    }
    Ok(())
}

/// Several empty frames of a soft camera (`[camera] blur_px`): the noise they show is
/// reported, not written into the sensor file (the renderer would blur it; a blurred sensor
/// with noise is refused), and the file loads. The same frames from a sharp start write it.
#[test]
fn a_soft_cameras_noise_is_reported_not_written() -> Result<()> {
    let dir = tempdir("soft-noise")?;
    let mut noisy = Sensor::preset("paper")?.config;
    noisy.render.noise = Noise::Rgb([2.0, 1.5, 2.5]);
    let frames = empty_frames(&Sensor::from_config("noisy", noisy)?, 2, &dir)?;
    let mut soft = Sensor::preset("paper")?.config;
    soft.camera.blur_px = 1.0;
    let mut o = quick(Sensor::from_config("soft", soft)?, frames.clone());
    o.fit = calibrate::FitSet::parse("lens")?;
    let c = calibrate::calibrate(&o, &|_| {})?;
    assert_eq!(c.config.render.noise.rgb(), [0.0; 3]);
    assert!(value(&c, "render.noise[2]") > 1.0);
    let note = c
        .unconstrained
        .iter()
        .find(|n| n.starts_with("render.noise"))
        .expect("a note on the noise");
    assert!(note.contains("blur_px") && !note.contains('\n'), "{note}");
    Sensor::from_config("written", c.config)?;
    o.start = Sensor::preset("paper")?;
    let sharp = calibrate::calibrate(&o, &|_| {})?;
    assert!(sharp.config.render.noise.rgb()[2] > 1.0);
    Ok(())
}

/// A camera whose software cuts the picture to a circle of its own: the lens's principal
/// point 6 px right of and 5 px above the mask's centre and its focal length 7% shorter
/// than the field of view the mask implies. `--fit lens,principal,focal,light` finds both;
/// the plain lens fit, which takes the circle for the lens's edge, is off by both.
#[test]
fn a_lens_behind_a_mask_comes_back() -> Result<()> {
    let dir = tempdir("masked")?;
    let plain = hidden_sensor().config;
    let mut c = plain.clone();
    c.image.circle = Some([320.0, 240.0, 236.0]);
    c.lens.cx = 326.0;
    c.lens.cy = 235.0;
    c.lens.fov_deg = 200.0;
    let start = Sensor::preset("paper")?;
    // The focal length that puts the start's field of view on the mask, less 7%.
    let implied = 236.0 / (start.lens.max_rho() / start.lens.focal_px);
    c.lens.focal_px = 0.93 * implied;
    let hidden = Sensor::from_config("masked", c)?;
    let frames = empty_frames(&hidden, 1, &dir)?;
    let mut options = quick(start.clone(), frames);
    options.fit = calibrate::FitSet::parse("lens,principal,focal,light")?;
    let c = calibrate::calibrate(&options, &|_| {})?;
    let lens = &c.config.lens;
    let truth = &hidden.config.lens;
    let centre = (lens.cx - truth.cx).hypot(lens.cy - truth.cy);
    let focal = lens.focal_px / truth.focal_px - 1.0;
    let fitted = Sensor::from_config("fitted", c.config.clone())?;
    let after = psnr_against(&fitted, &c.empty, &c.circle);
    eprintln!(
        "principal ({:.2}, {:.2}) (truth ({}, {})), focal {:.2} (truth {:.2}), mask {:?}, {after:.2} dB",
        lens.cx, lens.cy, truth.cx, truth.cy, lens.focal_px, truth.focal_px, c.config.image.circle
    );
    assert!(centre < 1.0, "principal point {centre:.2} px off");
    assert!(focal.abs() < 0.01, "focal length {:.2}% off", 100.0 * focal);
    assert!(after >= 35.0, "re-rendered PSNR {after:.2} dB");
    let mask = c.config.image.circle.expect("the circle held as the mask");
    assert!((mask[0] - 320.0).hypot(mask[1] - 240.0) < 1.0 && (mask[2] - 236.0).abs() < 1.0);
    // What the plain lens fit assumes is off by both: the mask's centre and the focal
    // length its edge implies.
    assert!((320.0 - truth.cx).hypot(240.0 - truth.cy) > 1.0);
    assert!((implied / truth.focal_px - 1.0).abs() > 0.01);
    Ok(())
}

/// `c` with none of its listed LEDs glowing at a shell's end.
fn without_end_glow(c: &mut geltip::sensor::SensorConfig) {
    if let Leds::List(list) = &mut c.leds {
        list.iter_mut().for_each(|l| l.end_glow = [0.0; 3]);
    }
}

fn tempdir(name: &str) -> Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("geltip-calibrate-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}

/// Darkens seam lines and specks into a frame, as a real elastomer's mould leaves them.
fn add_seams_and_specks(frame: &mut image::RgbImage) {
    let (w, h) = frame.dimensions();
    let (cx, cy) = (w as f64 / 2.0, h as f64 / 2.0);
    for angle in [20.0f64, 140.0, 260.0] {
        let (s, c) = angle.to_radians().sin_cos();
        for t in 0..400 {
            for across in [-1.0, 0.0, 1.0] {
                let x = cx + t as f64 * c - across * s;
                let y = cy + t as f64 * s + across * c;
                if x >= 0.0 && y >= 0.0 && (x as u32) < w && (y as u32) < h {
                    let p = frame.get_pixel_mut(x as u32, y as u32);
                    p.0 = p.0.map(|v| (v as f64 * 0.6) as u8);
                }
            }
        }
    }
    for k in 0..40u32 {
        let (x, y) = ((k * 97 + 31) % w, (k * 53 + 17) % h);
        let bright = k % 2 == 0;
        for dy in 0..3 {
            for dx in 0..3 {
                if x + dx < w && y + dy < h {
                    let p = frame.get_pixel_mut(x + dx, y + dy);
                    p.0 = if bright { [255; 3] } else { p.0.map(|v| v / 4) };
                }
            }
        }
    }
}

#[test]
fn a_saturated_channel_seams_and_specks_do_not_throw_the_fit() -> Result<()> {
    let dir = tempdir("seams")?;
    let mut c = hidden_sensor().config;
    // A blue LED bright enough to clip blue over most of the disc, as on the real GelTip.
    if let Leds::List(list) = &mut c.leds {
        list[2].intensity = 9.0;
    }
    let hidden = Sensor::from_config("bright-blue", c)?;
    let clean = Renderer::new(&hidden)?.reference().to_rgb();
    let saturated = clean.pixels().filter(|p| p.0[2] == 255).count();
    assert!(
        saturated > clean.pixels().count() / 3,
        "{saturated} saturated pixels"
    );
    let mut frame = clean.clone();
    add_seams_and_specks(&mut frame);
    let path = dir.join("empty.png");
    frame.save(&path)?;
    let start = Sensor::preset("paper")?;
    let c = calibrate::calibrate(&quick(start.clone(), vec![path]), &|_| {})?;
    let truth = &hidden.config.lens;
    let focal = value(&c, "lens.focal_px");
    let centre = (value(&c, "lens.cx") - truth.cx).hypot(value(&c, "lens.cy") - truth.cy);
    // Judged against the clean frame: what the seams and specks hide.
    let after = psnr_against(
        &Sensor::from_config("fitted", c.config.clone())?,
        &clean,
        &c.circle,
    );
    let before = psnr_against(&start, &clean, &c.circle);
    eprintln!("focal {focal:.2} (truth {:.2}), centre {centre:.3} px off, PSNR against the clean frame {before:.2} -> {after:.2} dB", truth.focal_px);
    assert!((focal / truth.focal_px - 1.0).abs() < 0.01, "focal {focal}");
    assert!(centre < 1.0, "centre {centre} px off");
    assert!(after >= 35.0, "PSNR against the clean frame {after:.2} dB");
    assert!(
        before < 35.0,
        "the start sensor already scores {before:.2} dB"
    );
    Ok(())
}

#[test]
fn known_contacts_give_back_the_imprint() -> Result<()> {
    let dir = tempdir("contacts")?;
    let mut c = hidden_sensor().config;
    c.elastomer.blend_mm = 0.8;
    c.elastomer.drape_mm = 3.0;
    c.elastomer.bulge = 0.55;
    let hidden = Sensor::from_config("hidden-gel", c)?;
    let empty = empty_frames(&hidden, 1, &dir)?;
    let mut renderer = Renderer::new(&hidden)?;
    let mut lines = Vec::new();
    for (k, (at, azimuth)) in [
        ("rotation=25", 40.0),
        ("rotation=50", 200.0),
        ("translation=3", 300.0),
    ]
    .into_iter()
    .enumerate()
    {
        let spec = geltip::scene::ContactSpec {
            object: "sphere".into(),
            at: Some(geltip::scene::At::Text(at.into())),
            azimuth: Some(azimuth),
            depth: Some(1.0),
            ..Default::default()
        };
        let press = spec.press(&mut geltip::object::ObjectCache::default())?;
        renderer
            .render(&press)?
            .0
            .to_rgb()
            .save(dir.join(format!("contact{k}.png")))?;
        let mut line = serde_json::to_value(&spec)?;
        line["image"] = format!("contact{k}.png").into();
        lines.push(line.to_string());
    }
    let contacts = dir.join("contacts.jsonl");
    std::fs::write(&contacts, lines.join("\n") + "\n")?;
    // The start knows the light (so that the imprint alone is fitted) but not the gel.
    let mut start = hidden.config.clone();
    start.elastomer = Default::default();
    let start = Sensor::from_config("start", start)?;
    let mut options = quick(start.clone(), empty);
    options.contacts = Some(contacts);
    let c = calibrate::calibrate(&options, &|_| {})?;
    let fit = c.contacts.as_ref().expect("a contact fit");
    let e = &c.config.elastomer;
    eprintln!(
        "blend {:.3} drape {:.3} bulge {:.3} specular {:.3}; change rms {:.2} -> {:.2} over {} renders",
        e.blend_mm, e.drape_mm, e.bulge, c.config.paint.specular, fit.rms_before, fit.rms_after, fit.renders
    );
    let close = |e: &geltip::sensor::ElastomerConfig| {
        (e.blend_mm - 0.8).abs() < 0.1
            && (e.drape_mm - 3.0).abs() < 0.5
            && (e.bulge - 0.55).abs() < 0.1
    };
    assert!(close(e), "{e:?}");
    assert!(!close(&start.config.elastomer));
    assert!(fit.rms_after < 0.5 * fit.rms_before);
    Ok(())
}

/// Runs calibrate on `empty` (and `contacts`) and returns its one-line error.
fn refused(empty: Vec<PathBuf>, contacts: Option<PathBuf>) -> String {
    let mut o = quick(Sensor::preset("paper").unwrap(), empty);
    o.contacts = contacts;
    let e = calibrate::calibrate(&o, &|_| {})
        .expect_err("must be refused")
        .to_string();
    assert!(!e.contains('\n'), "{e}");
    e
}

#[test]
fn bad_frames_are_refused_on_one_line() -> Result<()> {
    let dir = tempdir("bad")?;
    let good = empty_frames(&hidden_sensor(), 1, &dir)?.remove(0);
    let save = |name: &str, img: image::RgbImage| -> Result<PathBuf> {
        let p = dir.join(name);
        img.save(&p)?;
        Ok(p)
    };
    let small = save(
        "small.png",
        image::RgbImage::from_pixel(320, 240, image::Rgb([90, 60, 200])),
    )?;
    let e = refused(vec![good.clone(), small], None);
    assert!(e.contains("small.png") && e.contains("one camera"), "{e}");

    let flat = save(
        "flat.png",
        image::RgbImage::from_pixel(640, 480, image::Rgb([90, 60, 200])),
    )?;
    assert!(refused(vec![flat], None).contains("no image circle"));

    let black = save("black.png", image::RgbImage::new(640, 480))?;
    let e = refused(vec![black], None);
    assert!(e.contains("black.png") && e.contains("is black"), "{e}");

    let text = dir.join("notes.png");
    std::fs::write(&text, "not a picture")?;
    let e = refused(vec![text], None);
    assert!(e.contains("notes.png") && e.contains("not an image"), "{e}");

    let missing = dir.join("missing.png");
    let e = refused(vec![missing], None);
    assert!(e.contains("missing.png"), "{e}");

    let contacts = dir.join("contacts.jsonl");
    std::fs::write(
        &contacts,
        r#"{"image": "nowhere.png", "object": "sphere", "at": "rotation=30", "depth": 1}"#,
    )?;
    let e = refused(vec![good.clone()], Some(contacts.clone()));
    assert!(
        e.contains("contacts.jsonl line 1") && e.contains("nowhere.png"),
        "{e}"
    );
    std::fs::write(
        &contacts,
        r#"{"image": "empty0.png", "object": "sphere", "depth": 1}"#,
    )?;
    let e = refused(vec![good], Some(contacts));
    assert!(e.contains("line 1") && e.contains("at"), "{e}");
    Ok(())
}

/// A sensor file as `geltip calibrate` writes it (listed LEDs, ambient light, vignetting,
/// per-channel noise) runs through every command that takes a sensor.
#[test]
fn every_command_takes_a_calibrated_sensor_file() -> Result<()> {
    use std::process::Command;
    let dir = tempdir("commands")?;
    let mut c = hidden_sensor().config;
    c.light.vignetting = [-0.3, 0.1];
    c.render.noise = Noise::Rgb([1.0, 2.0, 0.5]);
    let path = dir.join("sensor.toml");
    std::fs::write(&path, geltip::jobs::calibrate::sensor_toml(&c)?)?;
    // Each command's words (SENSOR: the file), then the path it writes.
    let runs = [
        (
            "render --sensor SENSOR --object sphere --at rotation=30 --depth 1 -o",
            "sphere.png",
        ),
        ("dataset --sensor SENSOR --count 3 --seed 1 --out", "set"),
        ("preview --sensors SENSOR --out", "preview"),
        (
            "stability --sensor SENSOR --positions 3 --azimuths 1 --out",
            "stability",
        ),
        (
            "evaluate --suite paper --sensor SENSOR --method surface --out",
            "evaluate",
        ),
    ];
    for (words, written) in runs {
        let mut command = Command::new(env!("CARGO_BIN_EXE_geltip"));
        for word in words.split_whitespace() {
            match word {
                "SENSOR" => command.arg(&path),
                _ => command.arg(word),
            };
        }
        let done = command.arg(dir.join(written)).output()?;
        assert!(
            done.status.success(),
            "geltip {words}: {}",
            String::from_utf8_lossy(&done.stderr)
        );
    }
    // The calibrated look reaches the files: the dataset's set keeps the sensor's light.
    let manifest = std::fs::read_to_string(dir.join("set").join("dataset.json"))?;
    assert!(
        manifest.contains("vignetting") && manifest.contains("azimuth_deg"),
        "{manifest}"
    );
    Ok(())
}

/// `--fit glow`: the LEDs' glow at a clear shell's end (two of the AllSight preset's nine
/// LEDs glowing, one red and blue, one green with less blue), fitted alone over the start's
/// light, comes back where the frame shows it: the glow round the end, azimuth by azimuth,
/// within 0.1 per channel, the picture to 40 dB; every other value is held. The start (no
/// glow) fails both.
#[test]
fn a_hidden_glow_at_the_shell_end_comes_back_over_the_held_light() -> Result<()> {
    let dir = tempdir("glow")?;
    let mut c = Sensor::preset("allsight")?.config;
    // The light's model is unblurred: the frame too, so the glow alone can explain it.
    c.camera.blur_px = 0.0;
    if let Some(end) = c.shell_end.as_mut() {
        end.led_glow_deg = Some(30.0);
    }
    without_end_glow(&mut c);
    let start = Sensor::from_config("start", c.clone())?;
    if let Leds::List(list) = &mut c.leds {
        list[0].end_glow = [0.8, 0.0, 0.3];
        list[4].end_glow = [0.0, 0.6, -0.3];
    }
    let hidden = Sensor::from_config("hidden", c)?;
    let frames = empty_frames(&hidden, 1, &dir)?;
    let mut o = quick(start.clone(), frames);
    o.fit = calibrate::FitSet::parse("glow")?;
    o.samples = 4000;
    let c = calibrate::calibrate(&o, &|_| {})?;
    assert_eq!(
        c.values.len(),
        28,
        "only the glow and its spread are fitted"
    );
    let fitted = Sensor::from_config("fitted", c.config.clone())?;
    assert_eq!(fitted.config.camera, start.config.camera);
    let glow_round = |s: &Sensor| -> Vec<glam::DVec3> {
        let light = s.lighting();
        let spread = light.shell_end.and_then(|e| e.led_glow_deg).unwrap();
        (0..36)
            .map(|k| {
                let a = (10.0 * k as f64).to_radians();
                let ray = glam::DVec3::new(a.cos(), a.sin(), 1.0);
                geltip::render::leds::end_glow(&light.leds, spread, ray)
            })
            .collect()
    };
    let off = |s: &Sensor| {
        glow_round(s)
            .iter()
            .zip(glow_round(&hidden))
            .map(|(a, b)| (*a - b).abs().max_element())
            .fold(0.0, f64::max)
    };
    let after = psnr_against(&fitted, &c.empty, &c.circle);
    let before = psnr_against(&start, &c.empty, &c.circle);
    eprintln!(
        "glow off by {:.3} (start {:.3}), PSNR {before:.2} -> {after:.2} dB",
        off(&fitted),
        off(&start)
    );
    assert!(off(&fitted) < 0.1, "the glow is off by {}", off(&fitted));
    assert!(off(&start) > 0.1);
    assert!(after >= 40.0, "re-rendered PSNR {after:.2} dB");
    assert!(before < 40.0, "the start already scores {before:.2} dB");

    // With the light (which fits the glow itself), or from an end that sets no spread: one
    // line each, naming what is wrong.
    let err = calibrate::FitSet::parse("glow,light")
        .unwrap_err()
        .to_string();
    assert!(err.contains("glow") && !err.contains('\n'), "{err}");
    let mut plain = Sensor::preset("allsight")?.config;
    if let Some(end) = plain.shell_end.as_mut() {
        end.led_glow_deg = None;
    }
    without_end_glow(&mut plain);
    o.start = Sensor::from_config("plain end", plain)?;
    let err = calibrate::calibrate(&o, &|_| {}).unwrap_err().to_string();
    assert!(err.contains("led_glow_deg") && !err.contains('\n'), "{err}");
    Ok(())
}
