//! `geltip dataset --background DIR`: each sample put on one of a folder's real empty frames,
//! drawn from the seed and its index; its label names the background and its own empty
//! frame (`references/<name>.png`), which `geltip evaluate` then subtracts; shards merge with
//! their references; folders without images or with a misfit image are refused on one line.

mod common;

use common::{error_line, geltip, temp_in};
use image::RgbImage;
use serde_json::Value;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn ok(args: &[&str]) -> String {
    let (code, out, err) = geltip(args);
    assert_eq!(code, 0, "{err}");
    out
}

fn load(path: &Path) -> RgbImage {
    image::open(path).unwrap().to_rgb8()
}

fn labels(dir: &Path) -> Vec<Value> {
    let mut v: Vec<Value> = std::fs::read_to_string(dir.join("labels.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    v.sort_by_key(|l| l["index"].as_u64());
    v
}

/// Three 640x480 backgrounds unlike each other and the finger, and a file that is not one.
fn backgrounds(dir: &Path) -> Vec<String> {
    std::fs::create_dir_all(dir).unwrap();
    let names = vec!["a.png".to_string(), "b.png".into(), "c.jpg".into()];
    for (k, name) in names.iter().enumerate() {
        let k = k as u32;
        let img = RgbImage::from_fn(640, 480, |x, y| {
            image::Rgb([
                ((x + 60 * k) % 256) as u8,
                ((y * (k + 1)) % 256) as u8,
                (40 + 70 * k) as u8,
            ])
        });
        img.save(dir.join(name)).unwrap();
    }
    std::fs::write(dir.join("notes.txt"), "not an image\n").unwrap();
    names
}

const COUNT: &str = "12";

/// Runs `geltip dataset` (paper, COUNT samples, seed 3) into `out`; returns its stdout.
fn dataset(out: &Path, background: Option<&Path>, extra: &[&str]) -> String {
    let mut args = vec![
        "dataset",
        "--sensor",
        "paper",
        "--count",
        COUNT,
        "--seed",
        "3",
        "--out",
        s(out),
    ];
    if let Some(b) = background {
        args.extend(["--background", s(b)]);
    }
    args.extend(extra);
    ok(&args)
}

#[test]
fn each_sample_is_put_on_a_drawn_background_and_scored_against_it() {
    let folder = temp_in("backgrounds", "folder");
    let names = backgrounds(&folder);
    let on = temp_in("backgrounds", "on");
    let plain = temp_in("backgrounds", "plain");
    dataset(&on, Some(&folder), &[]);
    dataset(&plain, None, &[]);

    let plain_reference = load(&plain.join("reference.png"));
    let mut used = BTreeSet::new();
    for (label, plain_label) in labels(&on).iter().zip(labels(&plain)) {
        let name = label["background"].as_str().expect("a background named");
        assert!(names.iter().any(|n| n == name), "{name}");
        used.insert(name.to_string());
        let reference = label["reference"].as_str().unwrap();
        let stem = name.rsplit_once('.').unwrap().0;
        assert_eq!(reference, format!("references/{stem}.png"));
        // The sample's empty frame is its background (the set has no noise), and its image
        // is that background plus the rendered change, clamped.
        let bg = image::open(folder.join(name)).unwrap().to_rgb8();
        assert_eq!(load(&on.join(reference)), bg);
        let image = load(&on.join(label["image"].as_str().unwrap()));
        let rendered = load(&plain.join(plain_label["image"].as_str().unwrap()));
        for (((o, b), r), e) in image
            .pixels()
            .zip(bg.pixels())
            .zip(rendered.pixels())
            .zip(plain_reference.pixels())
        {
            for c in 0..3 {
                let want = (b[c] as i32 + r[c] as i32 - e[c] as i32).clamp(0, 255) as u8;
                assert_eq!(o[c], want);
            }
        }
    }
    // Samples on different backgrounds (how evenly they are drawn: look.rs's unit test).
    assert!(used.len() >= 2, "{used:?}");
    // reference.png is the first background's empty frame.
    assert_eq!(load(&on.join("reference.png")), load(&folder.join("a.png")));

    // A second run keeps every sample.
    let out = dataset(&on, Some(&folder), &[]);
    assert!(out.contains("\"rendered\":0"), "{out}");

    // Scored against each sample's own empty frame, the set scores as the plain one does:
    // against reference.png alone, the other backgrounds' samples would be all change.
    let summary = |set: &Path, name: &str| -> Value {
        let out = temp_in("backgrounds", name);
        ok(&[
            "evaluate",
            "--dataset",
            s(set),
            "--method",
            "surface",
            "--out",
            s(&out),
        ]);
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
    };
    let (a, b) = (summary(&on, "eval-on"), summary(&plain, "eval-plain"));
    assert_eq!(a["recall"], b["recall"]);
    assert!(a["recall"].as_f64().unwrap() > 0.5, "{a}");
}

#[test]
fn shards_merge_with_their_backgrounds_empty_frames() {
    let folder = temp_in("backgrounds-merge", "folder");
    backgrounds(&folder);
    let whole = temp_in("backgrounds-merge", "whole");
    dataset(&whole, Some(&folder), &[]);
    let shards: Vec<PathBuf> = (0..2)
        .map(|i| {
            let dir = temp_in("backgrounds-merge", &format!("s{i}"));
            dataset(&dir, Some(&folder), &["--shard", &format!("{i}/2")]);
            dir
        })
        .collect();
    let merged = temp_in("backgrounds-merge", "merged");
    ok(&[
        "dataset",
        "--merge",
        s(&merged),
        s(&shards[0]),
        s(&shards[1]),
    ]);
    for (a, b) in labels(&whole).iter().zip(labels(&merged)) {
        assert_eq!(a["background"], b["background"]);
        for key in ["image", "reference"] {
            let rel = a[key].as_str().unwrap();
            assert_eq!(load(&whole.join(rel)), load(&merged.join(rel)), "{rel}");
        }
    }
}

#[test]
fn folders_without_fitting_images_are_refused_on_one_line() {
    let empty = temp_in("backgrounds-bad", "empty");
    std::fs::create_dir_all(&empty).unwrap();
    std::fs::write(empty.join("readme.txt"), "no images here\n").unwrap();
    let misfit = temp_in("backgrounds-bad", "misfit");
    backgrounds(&misfit);
    RgbImage::new(64, 48)
        .save(misfit.join("small.png"))
        .unwrap();
    let out = temp_in("backgrounds-bad", "out");
    for (folder, says, names) in [
        (&empty, "holds no PNG or JPEG images", s(&empty).to_string()),
        (
            &misfit,
            "is 64x48, the sensor's images are 640x480",
            s(&misfit.join("small.png")).to_string(),
        ),
    ] {
        let (code, _, err) = geltip(&[
            "dataset",
            "--sensor",
            "paper",
            "--count",
            "2",
            "--background",
            s(folder),
            "--out",
            s(&out),
        ]);
        assert_ne!(code, 0);
        let line = error_line(&err);
        assert!(line.contains(says) && line.contains(&names), "{line}");
        assert!(!out.join("labels.jsonl").exists());
    }
}

/// `--drift`: where the contact changes nothing each image is its empty frame with its light
/// drifted (smoothly: neighbouring pixels move alike), differently per sample and the same
/// run after run; the empty frame itself is not drifted; out of range refused.
#[test]
fn drift_moves_the_light_smoothly_and_reproducibly() {
    let run = |name: &str, drift: &str| {
        let out = temp_in("backgrounds-drift", name);
        dataset(&out, None, &["--drift", drift]);
        out
    };
    let (a, b, none) = (run("a", "1"), run("b", "1"), run("none", "0"));
    let reference = load(&a.join("reference.png"));
    assert_eq!(reference, load(&none.join("reference.png")));
    let mut means = Vec::new();
    for (((la, lb), ln), k) in labels(&a)
        .iter()
        .zip(labels(&b))
        .zip(labels(&none))
        .zip(0..)
    {
        let file = |dir: &Path, l: &Value, key: &str| load(&dir.join(l[key].as_str().unwrap()));
        let (img, again, plain) = (
            file(&a, la, "image"),
            file(&b, &lb, "image"),
            file(&none, &ln, "image"),
        );
        assert_eq!(img, again, "sample {k} differs between runs");
        let (mut sum, mut n, mut rough) = (0.0, 0usize, 0usize);
        for y in 0..480 {
            for x in 0..639 {
                let (p, q) = (reference.get_pixel(x, y), reference.get_pixel(x + 1, y));
                // Where the contact changed nothing: the drifted image is the empty frame
                // with its light drifted.
                if plain.get_pixel(x, y) != p || plain.get_pixel(x + 1, y) != q {
                    continue;
                }
                for c in 0..3 {
                    let (r0, r1) = (p[c] as f64, q[c] as f64);
                    if !(40.0..=215.0).contains(&r0) || !(40.0..=215.0).contains(&r1) {
                        continue;
                    }
                    let (v0, v1) = (
                        img.get_pixel(x, y)[c] as f64,
                        img.get_pixel(x + 1, y)[c] as f64,
                    );
                    sum += (v0 - r0).abs();
                    n += 1;
                    // Rounding moves a value by half a level: the ratio of neighbours agrees
                    // within that.
                    if ((v0 - r0) - (v1 - r1)).abs() > 3.0 {
                        rough += 1;
                    }
                }
            }
        }
        assert!(n > 10_000, "{n}");
        assert!(
            rough * 100 < n,
            "sample {k}: {rough} of {n} neighbours disagree"
        );
        means.push(sum / n as f64);
    }
    assert!(means.iter().all(|&m| m > 0.5), "{means:?}");
    assert!(
        means.iter().any(|&m| (m - means[0]).abs() > 0.5),
        "{means:?}"
    );
    let (code, _, err) = geltip(&[
        "dataset",
        "--sensor",
        "paper",
        "--count",
        "2",
        "--drift",
        "1.5",
        "--out",
        s(&temp_in("backgrounds-drift", "bad")),
    ]);
    assert_ne!(code, 0);
    assert!(error_line(&err).contains("--drift"), "{err}");
}
