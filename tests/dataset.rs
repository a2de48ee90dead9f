//! `geltip dataset` end to end, through the built binary: determinism, shards and merge,
//! resume after SIGKILL and after a torn manifest line, one run at a time in a directory,
//! labels against masks, and the one-line errors.

mod sets;

use sets::{assert_complete, dataset, error_of, files, geltip, labels, run, scratch};
use std::fs;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const OPTS: [&str; 12] = [
    "--count",
    "9",
    "--seed",
    "7",
    "--masks",
    "--depth-maps",
    "--noise",
    "2",
    "--light-jitter",
    "0.1",
    "--paint-jitter",
    "0.2",
];

#[test]
fn same_seed_gives_identical_files_and_pixels_lie_in_masks() {
    let root = scratch("same_seed");
    let (a, b, c) = (root.join("a"), root.join("b"), root.join("c"));
    dataset(&a, &OPTS);
    dataset(&b, &OPTS);
    assert_complete(&a, 9);
    let fa = files(&a);
    // dataset.json, labels.jsonl, reference.png, and an image, depth map and mask a sample.
    assert_eq!(fa.len(), 3 + 3 * 9);
    assert!(fa.contains_key("reference.png"));
    assert!(fa == files(&b), "two runs with the same seed differ");

    // Render streams share out the batches, not the samples' draws: one stream and four
    // write the same files.
    for (name, streams) in [("one", "1"), ("four", "4")] {
        let d = root.join(name);
        let mut opts = OPTS.to_vec();
        opts.extend(["--streams", streams]);
        dataset(&d, &opts);
        assert!(
            fa == files(&d),
            "{streams} render streams changed the files"
        );
    }

    // Another seed gives other samples.
    let mut other = OPTS;
    other[3] = "8";
    dataset(&c, &other);
    assert_ne!(fa["images/000000.png"], files(&c)["images/000000.png"]);

    // Each contact's pixel lies in its mask (where the skin is pressed at the contact point:
    // a tube's hole is not).
    let mut checked = 0;
    for l in labels(&a) {
        let Some(px) = l["pixel"].as_array() else {
            continue;
        };
        if l["contact_indentation_mm"].as_f64().unwrap() <= 0.05 {
            continue;
        }
        let mask = image::open(a.join(l["mask"].as_str().unwrap()))
            .unwrap()
            .to_luma8();
        let (u, v) = (px[0].as_f64().unwrap(), px[1].as_f64().unwrap());
        let (u, v) = (u.round() as u32, v.round() as u32);
        assert_eq!(
            mask.get_pixel(u, v).0[0],
            255,
            "sample {}: pixel ({u}, {v}) outside its mask",
            l["index"]
        );
        let count = mask.pixels().filter(|p| p.0[0] == 255).count() as u64;
        assert_eq!(count, l["mask_pixels"].as_u64().unwrap());
        checked += 1;
    }
    assert!(checked >= 5, "only {checked} labels checked");
}

/// Without a look (noise, jitter, background), images are encoded against the empty
/// finger's cached rows (`output::PngRowCache`): each must decode to exactly the frame the
/// renderer gives for the same contact.
#[test]
fn images_decode_to_the_rendered_frames() {
    use geltip::jobs::dataset::{default_depth_range, load_objects, sample_contact, Spec};
    let dir = scratch("decode");
    dataset(&dir, &["--count", "6", "--seed", "3"]);
    let sensor = geltip::sensor::Sensor::preset("paper").unwrap();
    let spec = Spec::new("paper", sensor.clone(), 6, 3);
    let objects = load_objects(&spec.objects).unwrap();
    let depths = default_depth_range(sensor.finger.shell_thickness);
    let mut renderer = geltip::render::gpu::Renderer::new(&sensor).unwrap();
    for l in labels(&dir) {
        let k = l["index"].as_u64().unwrap();
        let contact = sample_contact(&sensor, &objects, depths, 3, k).unwrap();
        let (frame, _) = renderer.render(&contact).unwrap();
        let png = image::open(dir.join(l["image"].as_str().unwrap()))
            .unwrap()
            .to_rgb8();
        assert!(
            png.as_raw() == frame.to_rgb().as_raw(),
            "sample {k}: the image differs from the rendered frame"
        );
    }
}

#[test]
fn shards_merged_equal_the_unsharded_set() {
    let root = scratch("shards");
    let whole = root.join("whole");
    dataset(&whole, &OPTS);
    let mut shard_dirs = Vec::new();
    for i in 0..3 {
        let dir = root.join(format!("s{i}"));
        let mut args = OPTS.to_vec();
        let shard = format!("{i}/3");
        args.extend(["--shard", &shard]);
        dataset(&dir, &args);
        assert_eq!(labels(&dir).len(), 3);
        shard_dirs.push(dir);
    }
    let merged = root.join("merged");
    let mut args = vec!["dataset", "--merge", merged.to_str().unwrap()];
    // Any order of shards.
    for d in shard_dirs.iter().rev() {
        args.push(d.to_str().unwrap());
    }
    let o = run(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_complete(&merged, 9);
    let (fw, fm) = (files(&whole), files(&merged));
    assert_eq!(fw.keys().collect::<Vec<_>>(), fm.keys().collect::<Vec<_>>());
    for (k, v) in &fw {
        assert!(
            fm[k] == *v,
            "{k} differs between the merged and the unsharded set"
        );
    }

    // A missing shard is refused.
    let o = run(&[
        "dataset",
        "--merge",
        root.join("m2").to_str().unwrap(),
        shard_dirs[0].to_str().unwrap(),
        shard_dirs[2].to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("missing shards 1/3"),
        "{err}"
    );

    // A merge into a directory another run is writing is refused, and so is a merge of a
    // shard another run is writing (this test process holds their locks).
    let mut args = vec!["dataset", "--merge", merged.to_str().unwrap()];
    args.extend(shard_dirs.iter().map(|d| d.to_str().unwrap()));
    let before = files(&merged);
    let lock = geltip::output::DirLock::acquire(&merged, "test").unwrap();
    let e = error_of(&args);
    let holder = format!(
        "is being written by another run (pid {} on ",
        std::process::id()
    );
    assert!(
        e.contains(&format!("--merge {}: {holder}", merged.display())),
        "{e}"
    );
    drop(lock);
    assert!(files(&merged) == before, "a refused merge changed the set");
    let lock = geltip::output::DirLock::acquire(&shard_dirs[1], "test").unwrap();
    let e = error_of(&args);
    assert!(
        e.contains(&format!("shard {}: {holder}", shard_dirs[1].display())),
        "{e}"
    );
    drop(lock);
}

#[test]
fn killed_run_resumes_to_a_complete_set() {
    let root = scratch("killed");
    let out = root.join("set");
    let n = 40;
    let count = n.to_string();
    let mut child = geltip()
        .args([
            "dataset", "--sensor", "paper", "--seed", "3", "--masks", "--count", &count,
        ])
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        let lines = fs::read_to_string(out.join("labels.jsonl"))
            .map(|t| t.lines().count())
            .unwrap_or(0);
        if lines >= 1 {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no sample landed"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let before = labels(&out).len();
    assert!(before < n, "the run finished before it was killed");
    // The killed run's lock file is left behind; its lock went with the process.
    assert!(out.join(geltip::output::LOCK_FILE).exists());

    let report = dataset(&out, &["--seed", "3", "--masks", "--count", &count]);
    assert!(report["kept"].as_u64().unwrap() >= 1);
    assert_eq!(
        report["kept"].as_u64().unwrap() + report["rendered"].as_u64().unwrap(),
        n as u64
    );
    assert_complete(&out, n as u64);

    // The resumed set equals one made in one go.
    let fresh = root.join("fresh");
    dataset(&fresh, &["--seed", "3", "--masks", "--count", &count]);
    assert!(
        files(&out) == files(&fresh),
        "the resumed set differs from a fresh one"
    );
}

/// Two runs into one directory at once: the second fails at once naming the first (pid,
/// host, start time) and touches nothing; the first completes as if alone.
#[test]
fn a_second_run_into_a_directory_being_written_is_refused() {
    let root = scratch("two_runs");
    let out = root.join("set");
    let opts = [
        "--seed",
        "6",
        "--masks",
        "--count",
        "64",
        "--streams",
        "1",
        "--jobs",
        "1",
    ];
    let mut first = geltip()
        .args(["dataset", "--sensor", "paper"])
        .args(opts)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !out.join("dataset.json").exists() {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "the first run wrote no manifest"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    let mut args = vec![
        "dataset",
        "--sensor",
        "paper",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(opts);
    let second = run(&args);
    let first_running = first.try_wait().unwrap().is_none();
    let err = String::from_utf8_lossy(&second.stderr).trim().to_string();
    assert!(!second.status.success(), "the second run succeeded: {err}");
    assert_eq!(err.lines().count(), 1, "not one line: {err}");
    let host = fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_default();
    let expected = format!(
        "--out {}: is being written by another run (pid {} on {}, started ",
        out.display(),
        first.id(),
        host.trim()
    );
    assert!(err.contains(&expected), "{err}\nexpected: {expected}");
    assert!(err.contains(" UTC); "), "{err}");
    assert!(
        first_running,
        "the first run ended before the second was refused: make it longer"
    );

    let first = first.wait_with_output().unwrap();
    assert!(
        first.status.success(),
        "the first run failed: {}",
        String::from_utf8_lossy(&first.stderr)
    );
    assert_complete(&out, 64);
    let fresh = root.join("fresh");
    dataset(&fresh, &opts);
    assert!(
        files(&out) == files(&fresh),
        "the first run's set differs from a fresh one"
    );
}

#[test]
fn torn_line_and_missing_file_are_redone() {
    let root = scratch("torn");
    let out = root.join("set");
    let args = ["--count", "6", "--seed", "2"];
    dataset(&out, &args);
    let before = files(&out);
    // A line torn by a crash, a sample whose image is gone, a stale temporary file.
    let mut text = fs::read_to_string(out.join("labels.jsonl")).unwrap();
    text.push_str("{\"index\": 9, \"ima");
    fs::write(out.join("labels.jsonl"), text).unwrap();
    fs::remove_file(out.join("images/000004.png")).unwrap();
    fs::write(out.join("images/.000005.png.1.0.tmp"), b"half").unwrap();
    let report = dataset(&out, &args);
    assert_eq!(report["kept"], 5);
    assert_eq!(report["rendered"], 1);
    assert_complete(&out, 6);
    assert!(files(&out) == before);
}

/// The labels' one rule (`jobs::dataset::labels`): only an unfinished last line is dropped
/// on resume; a bad line elsewhere stops the run with a one-line error naming it, and the
/// set is left as it was.
#[test]
fn a_bad_label_line_before_the_last_is_refused_on_resume() {
    let root = scratch("bad-line");
    let out = root.join("set");
    let args = ["--count", "4", "--seed", "2"];
    dataset(&out, &args);
    let text = fs::read_to_string(out.join("labels.jsonl")).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    lines.insert(1, "{\"index\": 7, \"ima");
    let bad = lines.join("\n") + "\n";
    fs::write(out.join("labels.jsonl"), &bad).unwrap();
    let before = files(&out);
    let dir = out.to_str().unwrap();
    let call = [&["dataset", "--sensor", "paper", "--out", dir][..], &args].concat();
    let e = error_of(&call);
    assert!(e.contains("labels.jsonl: line 2: not valid JSON"), "{e}");
    assert!(files(&out) == before, "the set changed");
}

/// A shard's manifest naming no shard of its set (an index past the count, a count of 0)
/// is refused by a merge with a one-line error, whichever shard it is given as.
#[test]
fn merge_refuses_a_manifest_that_names_no_shard() {
    let root = scratch("no-shard");
    let manifest = |shard: [u64; 2]| {
        serde_json::json!({"geltip_version": "0", "options": {"count": 2}, "shard": shard})
            .to_string()
    };
    for (k, bad) in [[0, 0], [u64::MAX, 2], [2, 2]].into_iter().enumerate() {
        for bad_first in [true, false] {
            let (a, b) = (
                root.join(format!("{k}{bad_first}a")),
                root.join(format!("{k}{bad_first}b")),
            );
            let (first, second) = if bad_first {
                (bad, [1, 2])
            } else {
                ([0, 2], bad)
            };
            for (dir, shard) in [(&a, first), (&b, second)] {
                fs::create_dir_all(dir).unwrap();
                fs::write(dir.join("dataset.json"), manifest(shard)).unwrap();
                // The good shard complete: its sample's line and file.
                fs::create_dir_all(dir.join("images")).unwrap();
                fs::write(dir.join("images/000000.png"), b"png").unwrap();
                let line = r#"{"index": 0, "image": "images/000000.png"}"#;
                fs::write(dir.join("labels.jsonl"), format!("{line}\n")).unwrap();
            }
            let out = root.join(format!("{k}{bad_first}out"));
            let e = ::geltip::jobs::dataset::merge(&out, &[a, b], &[])
                .unwrap_err()
                .to_string();
            let named = format!("names shard {}/{}", bad[0], bad[1]);
            assert!(e.contains(&named) && !e.contains('\n'), "{bad:?}: {e}");
        }
    }
}

#[test]
fn bad_input_gives_one_line_errors() {
    let root = scratch("errors");
    let out = root.join("set");
    let o = out.to_str().unwrap();
    let base = ["dataset", "--sensor", "paper", "--out", o];
    let with = |extra: &[&str]| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        error_of(&a)
    };
    assert!(with(&["--count", "0"]).contains("--count: must be at least 1"));
    let e = with(&["--count", "5", "--shard", "3/3"]);
    assert!(
        e.contains("--shard 3/3") && e.contains("below the shard count"),
        "{e}"
    );
    let e = with(&["--count", "5", "--shard", "1/0"]);
    assert!(e.contains("--shard 1/0") && e.contains("at least 1"), "{e}");
    let e = with(&["--count", "5", "--objects", "sphere,teapot"]);
    assert!(e.contains("object 'teapot'"), "{e}");
    let e = with(&["--count", "5", "--depth-range", "2..1"]);
    assert!(e.contains("--depth-range"), "{e}");
    // A range deeper than the objects can press names the range, not a contact's depth.
    let e = with(&["--count", "5", "--depth-range", "0.2..1e9"]);
    assert!(
        e.starts_with("error: --depth-range 0.2..1000000000: the ") && e.contains("only up to"),
        "{e}"
    );
    for streams in ["0", "5"] {
        let e = with(&["--count", "5", "--streams", streams]);
        assert!(e.contains("--streams: must lie in 1..=4"), "{e}");
    }

    // A directory that cannot be made: under a regular file.
    let file = root.join("a-file");
    fs::write(&file, b"x").unwrap();
    let under = file.join("set");
    let e = error_of(&[
        "dataset",
        "--sensor",
        "paper",
        "--count",
        "2",
        "--out",
        under.to_str().unwrap(),
    ]);
    assert!(e.contains("a-file/set"), "{e}");

    // A background of the wrong size.
    let bg = root.join("bg.png");
    image::RgbImage::new(10, 10).save(&bg).unwrap();
    let e = with(&["--count", "2", "--background", bg.to_str().unwrap()]);
    assert!(
        e.contains("bg.png") && e.contains("10x10") && e.contains("640x480"),
        "{e}"
    );
    assert!(
        !out.join("dataset.json").exists(),
        "a refused run wrote its manifest"
    );

    // A rerun with other options into the same directory.
    dataset(&out, &["--count", "1", "--seed", "4"]);
    let e = with(&["--count", "2", "--seed", "4"]);
    assert!(e.contains("different options (count)"), "{e}");
    let e = with(&["--count", "1", "--seed", "4", "--masks"]);
    assert!(e.contains("different options (masks)"), "{e}");
    // The same options resume (nothing to do).
    let report = dataset(&out, &["--count", "1", "--seed", "4"]);
    assert_eq!(report["rendered"], 0);
}

/// The library names a set's options by their own names (the fields of `Spec`, the
/// arguments of `merge`); only the command line speaks of flags.
#[test]
fn library_errors_name_the_options_not_flags() {
    let sensor = geltip::sensor::Sensor::preset("paper").unwrap();
    let spec = geltip::jobs::dataset::Spec::new("paper", sensor, 5, 0);
    let error = |change: &dyn Fn(&mut geltip::jobs::dataset::Spec)| {
        let mut s = spec.clone();
        change(&mut s);
        let e = geltip::jobs::dataset::run(&s, None, |_| {})
            .unwrap_err()
            .to_string();
        assert!(!e.contains("--"), "{e}");
        e
    };
    assert_eq!(error(&|s| s.count = 0), "count: must be at least 1, got 0");
    let e = error(&|s| s.depth_range = (2.0, 1.0));
    assert!(e.starts_with("depth_range 2..1: needs 0 <= min"), "{e}");
    let e = error(&|s| s.depth_range = (0.2, 1e9));
    assert!(e.starts_with("depth_range 0.2..1000000000: the "), "{e}");
    let e = error(&|s| s.empty_fraction = 1.0);
    assert!(e.starts_with("empty_fraction: "), "{e}");
    let e = error(&|s| s.contacts_per_sample = (0, 2));
    assert!(e.starts_with("contacts_per_sample 0..2: "), "{e}");
    let e = error(&|s| s.noise = geltip::sensor::Noise::from(300.0));
    assert!(e.starts_with("noise: "), "{e}");
    let e = error(&|s| s.paint_jitter = 1.0);
    assert!(e.starts_with("paint_jitter: "), "{e}");
    let e = geltip::jobs::dataset::Shard::parse("3/3")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("shard 3/3: "), "{e}");

    let root = scratch("library-errors");
    let e = geltip::jobs::dataset::merge(&root.join("m"), &[], &[])
        .unwrap_err()
        .to_string();
    assert_eq!(e, "shards: name the shard directories to join");
}

#[test]
fn python_snippet_loads_a_set() {
    let has_deps = Command::new("python3")
        .args(["-c", "import numpy, PIL"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_deps {
        eprintln!("skipped: python3 with numpy and Pillow not found (pip install numpy pillow)");
        return;
    }
    let root = scratch("python");
    let out = root.join("set");
    dataset(
        &out,
        &["--count", "4", "--seed", "5", "--masks", "--depth-maps"],
    );
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/load_dataset.py");
    let o = Command::new("python3")
        .arg(&script)
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(stdout.contains("4 samples of 640x480"), "{stdout}");
}
