//! `geltip render --background`: a render's change from the empty finger on a real empty
//! frame, pixel by pixel; the empty finger on it is the background (plus the sensor's noise
//! when it has noise); backgrounds that are not images of the sensor's size are refused on
//! one line naming the file, with nothing written.

mod common;

use common::{error_line, geltip};
use image::RgbImage;
use std::path::{Path, PathBuf};

/// Runs geltip with `args`, which must succeed.
fn geltip_ok(args: &[&str]) {
    let (code, _, err) = geltip(args);
    assert_eq!(code, 0, "{err}");
}

/// Renders `sensor`'s empty finger (on `background`, if any) to `out`.
fn render_empty(sensor: &str, background: Option<&Path>, out: &Path) {
    let mut args = vec!["render", "--sensor", sensor, "--reference"];
    if let Some(bg) = background {
        args.extend(["--background", s(bg)]);
    }
    args.extend(["-o", s(out)]);
    geltip_ok(&args);
}

fn temp(name: &str) -> PathBuf {
    common::temp_in("background", name)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A 640x480 background unlike the rendered finger: ramps that reach 0 and 255, so that a
/// change is clamped at both ends somewhere.
fn background(path: &Path) {
    let img = RgbImage::from_fn(640, 480, |x, y| {
        image::Rgb([
            (x * 255 / 639) as u8,
            (y * 255 / 479) as u8,
            ((x + y) % 256) as u8,
        ])
    });
    img.save(path).unwrap();
}

fn load(path: &Path) -> RgbImage {
    image::open(path).unwrap().to_rgb8()
}

const SPHERE: [&str; 10] = [
    "render",
    "--sensor",
    "paper",
    "--object",
    "sphere",
    "--at",
    "rotation=40",
    "--depth",
    "1.2",
    "--azimuth",
];

#[test]
fn a_contact_on_a_background_is_the_background_plus_the_change() {
    let bg = temp("bg.png");
    background(&bg);
    let (plain, reference, on) = (temp("plain.png"), temp("ref.png"), temp("on.png"));
    let contact = |out: &Path, extra: &[&str]| {
        let mut args = SPHERE.to_vec();
        args.extend(["30", "-o", s(out)]);
        args.extend(extra);
        geltip_ok(&args);
    };
    contact(&plain, &[]);
    contact(&on, &["--background", s(&bg)]);
    render_empty("paper", None, &reference);

    let (plain, reference, on, bg) = (load(&plain), load(&reference), load(&on), load(&bg));
    let mut changed = 0;
    for (k, (((p, r), b), o)) in plain
        .as_raw()
        .iter()
        .zip(reference.as_raw())
        .zip(bg.as_raw())
        .zip(on.as_raw())
        .enumerate()
    {
        let change = *p as i32 - *r as i32;
        changed += (change != 0) as usize;
        let want = (*b as i32 + change).clamp(0, 255) as u8;
        assert_eq!(*o, want, "value {k} (pixel {}, channel {})", k / 3, k % 3);
    }
    assert!(changed > 1000, "the contact changed only {changed} values");
}

#[test]
fn the_empty_finger_on_a_background_is_the_background() {
    let bg = temp("bg-empty.png");
    background(&bg);
    let out = temp("ref-on-bg.png");
    render_empty("paper", Some(&bg), &out);
    assert_eq!(load(&out), load(&bg));

    // A noisy sensor adds its noise to the background: zero-mean, of the sensor's spread,
    // where the lens sees the finger (the renderer adds none elsewhere) and neither the
    // render nor the background clamps it.
    let mut toml = std::fs::read_to_string("assets/sensors/paper.toml").unwrap();
    toml.push_str("\n[render]\nnoise = 3.0\nnoise_seed = 11\n");
    let noisy = temp("noisy.toml");
    std::fs::write(&noisy, toml).unwrap();
    render_empty(s(&noisy), Some(&bg), &out);
    let (out, bg) = (load(&out), load(&bg));
    // The noise-free empty finger: the same sensor without [render].
    let reference = temp("ref-plain.png");
    render_empty("paper", None, &reference);
    let reference = load(&reference);
    let unclamped = |v: u8| (12..=243).contains(&v);
    let mut diffs = Vec::new();
    for (x, y, o) in out.enumerate_pixels() {
        if (x as f64 - 320.0).hypot(y as f64 - 240.0) > 220.0 {
            continue;
        }
        for c in 0..3 {
            let (b, r) = (bg.get_pixel(x, y)[c], reference.get_pixel(x, y)[c]);
            if unclamped(b) && unclamped(r) {
                diffs.push(o[c] as f64 - b as f64);
            }
        }
    }
    assert!(diffs.len() > 100_000, "{} values compared", diffs.len());
    let n = diffs.len() as f64;
    let mean = diffs.iter().sum::<f64>() / n;
    let sd = (diffs.iter().map(|d| d * d).sum::<f64>() / n).sqrt();
    assert!(
        mean.abs() < 0.1 && (sd - 3.0).abs() < 0.3,
        "mean {mean}, sd {sd}"
    );
}

#[test]
fn backgrounds_that_do_not_fit_are_refused_naming_the_file() {
    let small = temp("small.png");
    RgbImage::new(64, 48).save(&small).unwrap();
    let text = temp("not-an-image.png");
    std::fs::write(&text, "not a picture\n").unwrap();
    let missing = temp("missing.png");
    let out = temp("refused.png");
    for (bg, says) in [
        (&small, "is 64x48, the sensor's images are 640x480"),
        (&text, "format could not be determined"),
        (&missing, "No such file"),
    ] {
        for args in [
            vec!["render", "--sensor", "paper", "--reference"],
            SPHERE.iter().copied().chain(["0"]).collect(),
        ] {
            let mut args = args;
            args.extend(["--background", s(bg), "-o", s(&out)]);
            let (code, _, err) = geltip(&args);
            assert_ne!(code, 0);
            let line = error_line(&err);
            assert!(line.contains(s(bg)) && line.contains(says), "{line}");
            assert!(!out.exists(), "a refused render wrote {}", out.display());
        }
    }
}
