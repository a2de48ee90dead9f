//! `geltip evaluate` with detectors written for the test: an oracle that reports the labels'
//! contact centres, the oracle moved 1 mm along the finger, a blind one, one with an extra
//! detection per frame, one that reports two contacts in swapped order; each bad
//! predictions file and each failing detector program; the same detector through a file and
//! a program.

use geltip::evaluate::{DatasetSource, Predictions, Source, Target};
use geltip::jobs::{dataset, evaluate};
use geltip::sensor::Sensor;
use geltip::SurfaceCoord;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// A temporary directory of this test binary.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("geltip-evaluate-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A set of 30 frames: a fifth empty, the others with one or two contacts.
fn mixed_set() -> &'static Path {
    static SET: OnceLock<PathBuf> = OnceLock::new();
    SET.get_or_init(|| make_set("mixed", 30, 0.2, (1, 2)))
}

/// A set of 12 frames of two contacts each.
fn pairs_set() -> &'static Path {
    static SET: OnceLock<PathBuf> = OnceLock::new();
    SET.get_or_init(|| make_set("pairs", 12, 0.0, (2, 2)))
}

fn make_set(name: &str, count: u64, empty: f64, contacts: (u32, u32)) -> PathBuf {
    // Mesa's loader probes for a display where none is needed.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    let dir = scratch(name);
    let sensor = Sensor::preset("paper").unwrap();
    let mut spec = dataset::Spec::new("paper", sensor, count, 5);
    spec.empty_fraction = empty;
    spec.contacts_per_sample = contacts;
    spec.streams = 1;
    dataset::run(&spec, Some(&dir), |_| {}).unwrap();
    dir
}

/// Each label line of a set: (index, its contacts' JSON).
fn labels(set: &Path) -> Vec<(u64, Vec<Value>)> {
    std::fs::read_to_string(set.join("labels.jsonl"))
        .unwrap()
        .lines()
        .map(|l| {
            let v: Value = serde_json::from_str(l).unwrap();
            let contacts = v["contacts"]
                .as_array()
                .cloned()
                .unwrap_or_else(|| vec![v.clone()]);
            (v["index"].as_u64().unwrap(), contacts)
        })
        .collect()
}

fn centre(c: &Value) -> [f64; 3] {
    let p = c["contact_centre"]
        .as_array()
        .unwrap_or_else(|| c["point"].as_array().unwrap());
    [
        p[0].as_f64().unwrap(),
        p[1].as_f64().unwrap(),
        p[2].as_f64().unwrap(),
    ]
}

/// A predictions file: each frame's detections from its contacts (those the lens sees).
fn predictions(set: &Path, name: &str, detect: impl Fn(&[Value]) -> Vec<Value>) -> PathBuf {
    let mut text = String::new();
    for (k, contacts) in labels(set) {
        let visible: Vec<Value> = contacts
            .into_iter()
            .filter(|c| !c["pixel"].is_null())
            .collect();
        text.push_str(&json!({"sample": k, "detections": detect(&visible)}).to_string());
        text.push('\n');
    }
    let path = scratch(name).join("predictions.jsonl");
    std::fs::write(&path, text).unwrap();
    path
}

/// Scores a predictions file on a set through the library; returns `summary.json`'s object.
fn score(set: &Path, file: &Path) -> Value {
    let source = Source::Dataset(DatasetSource::open(set, Target::ContactCentre).unwrap());
    let mut detector = Predictions::read(file, source.sensor()).unwrap();
    evaluate::run(&source, &mut detector, Some(3.0), None, None, |_, _| {})
        .unwrap()
        .summary
}

fn oracle(contacts: &[Value]) -> Vec<Value> {
    contacts
        .iter()
        .map(|c| json!({"point": centre(c), "confidence": 0.9}))
        .collect()
}

#[test]
fn the_oracle_finds_every_visible_contact_exactly() {
    let set = mixed_set();
    let s = score(set, &predictions(set, "oracle", oracle));
    assert_eq!(s["recall"], 1.0, "{s}");
    assert!(s["error_mm"]["max"].as_f64().unwrap() <= 0.05, "{s}");
    assert_eq!(s["false_positives"], 0);
    assert_eq!(s["average_precision"], 1.0);
    assert!(
        s["empty_frames"].as_u64().unwrap() > 0,
        "the set holds empty frames: {s}"
    );
    assert!(
        s["visible"].as_u64().unwrap()
            > s["samples"].as_u64().unwrap() - s["empty_frames"].as_u64().unwrap()
    );
}

#[test]
fn the_oracle_moved_1_mm_along_the_finger_is_1_mm_off() {
    let set = mixed_set();
    let finger = Sensor::preset("paper").unwrap().finger;
    let moved = |contacts: &[Value]| -> Vec<Value> {
        contacts
            .iter()
            .map(|c| {
                let [x, y, z] = centre(c);
                let at = finger.coord_of(glam::DVec3::new(x, y, z));
                let p = finger
                    .point_at(SurfaceCoord {
                        s: at.s + 1.0,
                        phi: at.phi,
                    })
                    .point;
                json!({"point": p.to_array()})
            })
            .collect()
    };
    let s = score(set, &predictions(set, "moved", moved));
    assert_eq!(s["recall"], 1.0, "{s}");
    for key in ["mean", "median", "max"] {
        let e = s["error_mm"][key].as_f64().unwrap();
        assert!((e - 1.0).abs() <= 0.05, "{key} {e}: {s}");
    }
    let min = s["by_object"]
        .as_object()
        .unwrap()
        .values()
        .map(|g| g["error_mm"]["mean"].as_f64().unwrap())
        .fold(f64::INFINITY, f64::min);
    assert!(min >= 0.95, "{s}");
}

#[test]
fn a_blind_detector_recalls_nothing() {
    let set = mixed_set();
    let s = score(set, &predictions(set, "blind", |_| Vec::new()));
    assert_eq!(
        (s["recall"].as_f64(), s["detected"].as_u64()),
        (Some(0.0), Some(0))
    );
    assert_eq!(s["false_positives"], 0);
    assert_eq!(s["average_precision"], 0.0);
    assert!(s["error_mm"]["mean"].is_null());
}

#[test]
fn an_extra_detection_is_one_false_positive_per_frame() {
    let set = mixed_set();
    // The extra detection is on the finger where no contact of the frame is near: the tip
    // or the side, whichever is farther from them.
    let extra = |contacts: &[Value]| -> Vec<Value> {
        let mut d = oracle(contacts);
        let far_from_all = |p: [f64; 3]| {
            contacts.iter().all(|c| {
                let q = centre(c);
                (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>().sqrt() > 6.0
            })
        };
        let spot = [
            [0.0, 0.0, 27.5],
            [7.5, 0.0, 12.0],
            [-7.5, 0.0, 12.0],
            [0.0, 7.5, 12.0],
        ]
        .into_iter()
        .find(|&p| far_from_all(p))
        .unwrap();
        d.push(json!({"point": spot, "confidence": 0.1}));
        d
    };
    let s = score(set, &predictions(set, "extra", extra));
    assert_eq!(s["false_positives"], s["samples"], "{s}");
    assert_eq!(s["false_positives_on_empty_frames"], s["empty_frames"]);
    assert_eq!(s["recall"], 1.0);
    // Every extra detection is less sure than every right one: precision 1 up to recall 1.
    assert_eq!(s["average_precision"], 1.0);
}

#[test]
fn two_contacts_reported_in_swapped_order_match_their_own() {
    let set = pairs_set();
    let swapped = |contacts: &[Value]| -> Vec<Value> {
        let mut d = oracle(contacts);
        d.reverse();
        d
    };
    let file = predictions(set, "swapped", swapped);
    let s = score(set, &file);
    assert_eq!(s["recall"], 1.0, "{s}");
    assert!(s["error_mm"]["max"].as_f64().unwrap() <= 0.05, "{s}");
    // The per-sample file says which detection matched which contact.
    let out = scratch("swapped-out");
    let source = Source::Dataset(DatasetSource::open(set, Target::ContactCentre).unwrap());
    let mut detector = Predictions::read(&file, source.sensor()).unwrap();
    evaluate::run(
        &source,
        &mut detector,
        Some(3.0),
        Some(&out),
        None,
        |_, _| {},
    )
    .unwrap();
    let per_sample = std::fs::read_to_string(out.join("per_sample.jsonl")).unwrap();
    let mut both = 0;
    for line in per_sample.lines() {
        let v: Value = serde_json::from_str(line).unwrap();
        if v["visible"] == 2 {
            both += 1;
            for m in v["matched"].as_array().unwrap() {
                assert_eq!(
                    m["contact"].as_u64().unwrap() + m["detection"].as_u64().unwrap(),
                    1,
                    "{v}"
                );
            }
        }
    }
    assert!(both > 0, "some frame has both contacts in view");
}

fn geltip(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_geltip"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap()
}

fn summary_without_run_fields(dir: &Path) -> Value {
    let mut v: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    for key in ["seconds", "detector"] {
        v.as_object_mut().unwrap().remove(key);
    }
    v
}

#[test]
fn a_file_and_a_program_give_the_same_summary() {
    let set = mixed_set();
    let file = predictions(set, "same", oracle);
    let (a, b) = (scratch("same-file"), scratch("same-program"));
    let set_arg = set.to_str().unwrap();
    let by_file = geltip(&[
        "evaluate",
        "--dataset",
        set_arg,
        "--predictions",
        file.to_str().unwrap(),
        "--out",
        a.to_str().unwrap(),
    ]);
    assert!(
        by_file.status.success(),
        "{}",
        String::from_utf8_lossy(&by_file.stderr)
    );
    // The program answers each frame with its line of the file, in order.
    let program = format!(
        "while IFS= read -r request; do IFS= read -r answer <&3; printf '%s\\n' \"$answer\"; done 3< '{}'",
        file.display()
    );
    let by_program = geltip(&[
        "evaluate",
        "--dataset",
        set_arg,
        "--detector",
        &program,
        "--out",
        b.to_str().unwrap(),
    ]);
    assert!(
        by_program.status.success(),
        "{}",
        String::from_utf8_lossy(&by_program.stderr)
    );
    assert_eq!(
        summary_without_run_fields(&a),
        summary_without_run_fields(&b)
    );
    assert_eq!(
        std::fs::read(a.join("per_sample.jsonl")).unwrap(),
        std::fs::read(b.join("per_sample.jsonl")).unwrap()
    );
    for f in [
        "tables.md",
        "by_depth.svg",
        "by_region.svg",
        "failure_map.svg",
        "precision_recall.svg",
    ] {
        assert!(a.join(f).is_file(), "{f}");
    }
}

/// `--compare`: a second detector's report beside another run's; tables.md and the charts
/// name both. A directory that is not an evaluate output is refused on one line.
#[test]
fn compare_sets_two_detectors_side_by_side() {
    let set = mixed_set();
    let set_arg = set.to_str().unwrap();
    let oracle_file = predictions(set, "compare-oracle", oracle);
    let blind_file = predictions(set, "compare-blind", |_| Vec::new());
    let (first, second) = (scratch("compare-first"), scratch("compare-second"));
    let ok = |args: &[&str]| {
        let run = geltip(args);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
    };
    ok(&[
        "evaluate",
        "--dataset",
        set_arg,
        "--predictions",
        oracle_file.to_str().unwrap(),
        "--name",
        "the-oracle",
        "--out",
        first.to_str().unwrap(),
    ]);
    ok(&[
        "evaluate",
        "--dataset",
        set_arg,
        "--predictions",
        blind_file.to_str().unwrap(),
        "--name",
        "the-blind-one",
        "--out",
        second.to_str().unwrap(),
        "--compare",
        first.to_str().unwrap(),
    ]);
    let read = |name: &str| std::fs::read_to_string(second.join(name)).unwrap();
    let tables = read("tables.md");
    assert!(
        tables.contains("| | `the-blind-one` | `the-oracle` |"),
        "{tables}"
    );
    assert!(tables.contains("`the-oracle`: found"), "{tables}");
    for chart in ["by_depth.svg", "by_region.svg", "precision_recall.svg"] {
        let svg = read(chart);
        assert!(
            svg.contains("the-blind-one") && svg.contains("the-oracle"),
            "{chart} names one detector"
        );
    }
    // The compared run's own summary stays its own.
    let summary = summary_without_run_fields(&second);
    assert_eq!(summary["recall"], 0.0, "{summary}");

    // Not an evaluate output: a set's directory (no summary.json), and a directory whose
    // summary.json is some other file's.
    let oracle_arg = oracle_file.to_str().unwrap();
    refused(
        "compare-a-set",
        &["--predictions", oracle_arg, "--compare", set_arg],
        "summary.json: ",
    );
    let foreign = scratch("foreign-summary");
    std::fs::write(foreign.join("summary.json"), "{\"recall\": 1}\n").unwrap();
    refused(
        "compare-foreign",
        &[
            "--predictions",
            oracle_arg,
            "--compare",
            foreign.to_str().unwrap(),
        ],
        "is this a geltip evaluate summary?",
    );
}

/// The library refuses a sensor given with a set (the set holds its own), as the command
/// line does, rather than ignoring it.
#[test]
fn a_sensor_given_with_a_dataset_is_refused() {
    let sensor = Sensor::preset("paper").unwrap();
    let e = evaluate::source(Some(mixed_set()), None, Some(&sensor))
        .err()
        .expect("a sensor with a set was accepted");
    assert!(
        e.to_string()
            .starts_with("sensor: a dataset holds its own sensor"),
        "{e}"
    );
}

/// Runs evaluate on the mixed set with `args`, expecting a one-line error holding `says`,
/// and an output directory left without a file.
fn refused(name: &str, args: &[&str], says: &str) {
    let out = scratch(name).join("out");
    let mut all = vec![
        "evaluate",
        "--dataset",
        mixed_set().to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    all.extend_from_slice(args);
    let run = geltip(&all);
    let err = String::from_utf8_lossy(&run.stderr);
    let err = err
        .lines()
        .filter(|l| l.starts_with("error:"))
        .collect::<Vec<_>>();
    assert!(!run.status.success(), "{name}: accepted");
    assert_eq!(err.len(), 1, "{name}: {err:?}");
    assert!(err[0].contains(says), "{name}: {:?} lacks {says:?}", err[0]);
    let written = std::fs::read_dir(&out).map(|d| d.count()).unwrap_or(0);
    assert_eq!(written, 0, "{name}: files left in --out");
}

#[test]
fn bad_predictions_are_refused_naming_the_line() {
    let good = json!({"sample": 0, "detections": []}).to_string();
    let cases: [(&str, String, &str); 9] = [
        (
            "malformed",
            format!("{good}\n{{\"sample\": 1, \"detections\": [}}\n"),
            "line 2: not valid JSON",
        ),
        (
            "nan",
            format!("{good}\n{{\"sample\": 1, \"detections\": [{{\"pixel\": [NaN, 3]}}]}}\n"),
            "line 2: not valid JSON",
        ),
        (
            "infinite",
            "{\"sample\": 0, \"detections\": [{\"point\": [1e999, 0, 0]}]}\n".into(),
            "line 1: not valid JSON",
        ),
        (
            "unknown sample",
            format!("{good}\n{{\"sample\": 99999, \"detections\": []}}\n"),
            "line 2: sample 99999 is not in the set",
        ),
        (
            "repeated sample",
            format!("{good}\n{good}\n"),
            "line 2: sample 0 again (first on line 1)",
        ),
        (
            "no sample",
            "{\"detections\": []}\n".into(),
            "line 1: sample: required",
        ),
        (
            "no detections",
            "{\"sample\": 0}\n".into(),
            "line 1: detections: required",
        ),
        (
            "no place",
            "{\"sample\": 0, \"detections\": [{\"confidence\": 1}]}\n".into(),
            "line 1: detections[0]: needs",
        ),
        (
            "pixel outside",
            "{\"sample\": 0, \"detections\": [{\"pixel\": [640.5, 10]}]}\n".into(),
            "line 1: detections[0]: pixel: (640.5, 10) is outside the 640x480 image",
        ),
    ];
    for (name, text, says) in cases {
        let file = scratch(&format!("bad-{}", name.replace(' ', "-"))).join("p.jsonl");
        std::fs::write(&file, text).unwrap();
        refused(name, &["--predictions", file.to_str().unwrap()], says);
    }
    // A file that misses a frame is refused too, naming the frame.
    let file = scratch("bad-missing").join("p.jsonl");
    std::fs::write(&file, format!("{good}\n")).unwrap();
    refused(
        "missing",
        &["--predictions", file.to_str().unwrap()],
        "no line for sample 1",
    );
}

#[test]
fn a_failing_detector_program_is_named_with_the_sample() {
    refused("exits", &["--detector", "exit 3"], "sample 0");
    refused(
        "exits-later",
        &[
            "--detector",
            "read -r a; echo '{\"detections\": []}'; exit 4",
        ],
        "sample 1",
    );
    refused(
        "hangs",
        &["--detector", "sleep 30", "--timeout-s", "0.5"],
        "sample 0: no answer within 0.5 s",
    );
    refused(
        "garbage",
        &["--detector", "while read -r l; do echo 'no json'; done"],
        "sample 0: its answer: not valid JSON",
    );
    refused(
        "wrong sample",
        &[
            "--detector",
            "while read -r l; do echo '{\"sample\": 7, \"detections\": []}'; done",
        ],
        "its answer names sample 7",
    );
}

/// A compared summary.json as `--compare` reads it: the oracle's on the mixed set, changed
/// by `edit`.
fn compared_summary(name: &str, edit: impl Fn(&mut Value)) -> geltip::Result<Value> {
    let set = mixed_set();
    let mut summary = score(set, &predictions(set, name, oracle));
    edit(&mut summary);
    let dir = scratch(&format!("{name}-compared"));
    std::fs::write(dir.join("summary.json"), summary.to_string()).unwrap();
    geltip::evaluate::report::read_summary(&dir)
}

/// Regression (fuzz): a compared summary's shares outside [0, 1] and negative errors, which
/// the tables and charts computed with (`inf%` in tables.md, an overflow drawing the
/// charts), are refused naming the number.
#[test]
fn a_compared_summary_with_numbers_no_summary_holds_is_refused() {
    assert!(compared_summary("compared-real", |_| {}).is_ok());
    let refused = |name: &str, edit: &dyn Fn(&mut Value), says: &str| {
        let e = compared_summary(name, edit).unwrap_err().to_string();
        assert!(
            e.contains(says) && e.ends_with("is this a geltip evaluate summary?"),
            "{name}: {e}"
        );
    };
    refused(
        "compared-recall",
        &|s| s["recall"] = json!(1e308),
        "recall: 1e308 is not a share in [0, 1]",
    );
    refused(
        "compared-group-recall",
        &|s| {
            let group = s["by_object"].as_object_mut().unwrap().values_mut().next();
            group.unwrap()["recall"] = json!(-7.6e18);
        },
        ".recall: -7.6e18 is not a share in [0, 1]",
    );
    refused(
        "compared-curve",
        &|s| s["precision_recall"][0][1] = json!(2),
        "precision_recall[0][1]: 2 is not a share",
    );
    refused(
        "compared-error",
        &|s| s["error_mm"]["p95"] = json!(-1),
        "error_mm.p95: -1 is not an error",
    );
}

/// Regression (fuzz): a group's error near the largest float made the error axis infinite,
/// and drawing its ticks never ended.
#[test]
fn an_error_near_the_largest_float_charts_in_bounded_time() {
    let summary = json!({"detector": "huge", "by_depth": {"1-1.5": {
        "visible": 2, "detected": 1, "recall": 0.5,
        "error_mm": {"mean": 0.1, "median": 0.1, "p95": f64::MAX, "max": f64::MAX},
    }}});
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let order = ["1-1.5".to_string()];
        let _ = tx.send(geltip::evaluate::charts::by_group(
            &[summary],
            "by_depth",
            &order,
        ));
    });
    let svg = rx
        .recv_timeout(std::time::Duration::from_secs(60))
        .expect("the chart is not drawn within a minute")
        .unwrap();
    assert!(svg.contains("<svg"), "{svg}");
}

/// Regression (fuzz): a label's arc length far past the finger (read from a set's file)
/// overflowed the failure map's pixels; it is drawn at the finger's end, as a false
/// positive is.
#[test]
fn a_contact_far_past_the_finger_is_drawn_on_the_failure_map() {
    use geltip::evaluate::{Evaluation, LabelledContact, SampleScore, SampleTruth, Scored};
    let sensor = Sensor::preset("paper").unwrap();
    let contact = |s_mm: f64| LabelledContact {
        target: glam::DVec3::new(7.5, 0.0, 15.0),
        pixel: Some(glam::DVec2::new(400.0, 240.0)),
        visible: true,
        object: "sphere".into(),
        depth_mm: 1.0,
        s_mm,
        azimuth_deg: -1e300,
        region: "side",
    };
    let eval = Evaluation {
        detector: "blind".into(),
        frames: vec![Scored {
            truth: SampleTruth {
                index: 0,
                contacts: vec![contact(1e300), contact(-1e300)],
            },
            found: Vec::new(),
            score: SampleScore {
                missed: vec![0, 1],
                ..SampleScore::default()
            },
        }],
    };
    let svg = geltip::evaluate::charts::failure_map(&eval, &sensor).unwrap();
    assert!(svg.contains("missed (2)"), "{svg}");
}

/// A copy of the mixed set's manifest with `labels` as its labels.jsonl.
fn set_with_labels(name: &str, labels: &str) -> PathBuf {
    let dir = scratch(name);
    std::fs::copy(mixed_set().join("dataset.json"), dir.join("dataset.json")).unwrap();
    std::fs::write(dir.join("labels.jsonl"), labels).unwrap();
    dir
}

/// Regression (fuzz): a set's labels that name a sample twice (it was scored twice, and
/// another went unscored) or one outside the set are refused, naming the line.
#[test]
fn labels_naming_a_sample_twice_or_outside_the_set_are_refused() {
    let text = std::fs::read_to_string(mixed_set().join("labels.jsonl")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let open = |name: &str, labels: Vec<String>| {
        let dir = set_with_labels(name, &(labels.join("\n") + "\n"));
        DatasetSource::open(&dir, Target::ContactCentre)
            .err()
            .map(|e| e.to_string())
    };
    let all: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    assert_eq!(open("labels-all", all.clone()), None);
    let mut twice = all.clone();
    twice[1] = twice[0].clone();
    let e = open("labels-twice", twice).expect("a sample twice was accepted");
    assert!(
        e.ends_with("labels.jsonl: line 2: index: sample 0 again (first on line 1)"),
        "{e}"
    );
    let mut outside = all;
    let mut last: Value = serde_json::from_str(outside.last().unwrap()).unwrap();
    last["index"] = json!(4294967295u64);
    *outside.last_mut().unwrap() = last.to_string();
    let e = open("labels-outside", outside).expect("a sample outside the set was accepted");
    assert!(
        e.ends_with("line 30: index: sample 4294967295 is not one of the set's samples 0..30"),
        "{e}"
    );
}
