//! Real labelled frames in `geltip evaluate` ([`geltip::evaluate::real`]): the set format's
//! checks and round trip on made-up lines, and on the AllSight set of `../shared/real` (its
//! README gives the source; skipped where absent) the change method scored through it,
//! against the surface method, which calls drift a contact.

mod common;

use geltip::evaluate::{evaluate_real, MethodDetector, RealSet};
use geltip::localise::Method;
use geltip::sensor::Sensor;
use std::path::Path;
use std::sync::Arc;

fn set_file(dir: &Path, lines: &[&str]) -> std::path::PathBuf {
    let path = dir.join("set.jsonl");
    std::fs::write(&path, lines.join("\n")).unwrap();
    path
}

#[test]
fn the_set_format_reads_partial_labels_and_refuses_bad_lines_on_one_line() {
    let dir = common::temp_in("evaluate-real-format", "set");
    std::fs::create_dir_all(&dir).unwrap();
    let good = [
        r#"{"image": "a.jpg", "reference": "a0.jpg", "contact": true, "pixel": [200.5, 436], "azimuth_deg": 101.4, "centre": [240, 240], "region": "cylinder", "group": "s1 push 2"}"#,
        r#"{"image": "b.jpg", "reference": "b0.jpg", "contact": true}"#,
        r#"{"image": "a0.jpg", "reference": "ref.jpg", "contact": false, "group": "drift"}"#,
    ];
    let path = set_file(&dir, &good);
    let set = RealSet::read(&path).unwrap();
    assert_eq!(set.frames.len(), 3);
    let first = &set.frames[0];
    assert_eq!(first.image, dir.join("a.jpg"));
    assert_eq!(first.label.pixel, Some(glam::DVec2::new(200.5, 436.0)));
    assert_eq!(first.label.region.as_deref(), Some("cylinder"));
    assert_eq!(set.frames[1].group, "all");
    assert!(!set.frames[2].label.contact);
    // Written out and read back: the same set.
    std::fs::write(&path, set.to_jsonl(&dir)).unwrap();
    assert_eq!(RealSet::read(&path).unwrap(), set);

    let bad = [
        (
            r#"{"image": "a.jpg", "reference": "a0.jpg"}"#,
            "contact: missing",
        ),
        (
            r#"{"image": "a.jpg", "reference": "a0.jpg", "contact": true, "pixel": [1]}"#,
            "pixel: must be 2 numbers",
        ),
        (
            r#"{"image": "a.jpg", "reference": "a0.jpg", "contact": false, "pixel": [1, 2]}"#,
            "a no-contact frame has no place",
        ),
        (
            r#"{"image": "a.jpg", "reference": "a0.jpg", "contact": true, "region": "elbow"}"#,
            "region: must be tip, hemisphere",
        ),
        (
            r#"{"image": "a.jpg", "reference": "a0.jpg", "contact": true, "colour": 1}"#,
            "colour: unknown field",
        ),
        (
            r#"{"image": "a.jpg", "contact": true}"#,
            "reference: missing",
        ),
        ("not json", "not JSON"),
    ];
    for (line, why) in bad {
        let path = set_file(&dir, &[good[1], line]);
        let e = RealSet::read(&path).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains(why), "{line}: {e}");
        assert!(!e.contains('\n'), "{e}");
    }
}

/// Every fourth contact frame and every fourth drift pair of the AllSight set (both
/// sessions, every push point): the change method finds the contacts at their azimuth and
/// calls no drift pair a contact, scored through the real-set path; the surface method
/// calls the drift pairs contacts.
#[test]
fn real_allsight_frames_score_through_the_real_set() {
    let Some(dir) = common::real("allsight") else {
        return;
    };
    let all = RealSet::read(&dir.join("labels.json")).unwrap();
    assert_eq!(
        all.frames.len(),
        600,
        "400 contact frames and 200 drift pairs"
    );
    let (contacts, drift): (Vec<_>, Vec<_>) = all.frames.into_iter().partition(|f| f.label.contact);
    let every_fourth = |v: Vec<_>| v.into_iter().step_by(4).collect::<Vec<_>>();
    let set = RealSet {
        frames: every_fourth(contacts)
            .into_iter()
            .chain(every_fourth(drift))
            .collect(),
    };
    let sensor = Arc::new(Sensor::preset("allsight").unwrap());
    let mut change = MethodDetector::new(Method::Change);
    let report = evaluate_real(&set, &sensor, None, &mut change, |_, _| {}).unwrap();
    let t = report.total();
    assert_eq!((t.contacts, t.empty), (100, 50));
    assert!(t.found >= 97, "{}", report.tables());
    assert!(
        t.at_azimuth as f64 >= 0.9 * t.with_azimuth as f64,
        "{}",
        report.tables()
    );
    assert!(t.false_contacts <= 2, "{}", report.tables());
    assert!(report.tables().contains("| s1 drift |"));

    let drift_only = RealSet {
        frames: set
            .frames
            .iter()
            .filter(|f| !f.label.contact)
            .take(20)
            .cloned()
            .collect(),
    };
    let mut surface = MethodDetector::new(Method::Surface);
    let report = evaluate_real(&drift_only, &sensor, None, &mut surface, |_, _| {}).unwrap();
    assert!(report.total().false_contacts >= 18, "{}", report.tables());
}

/// The CLI: `geltip evaluate --real` writes the report, `--threshold` reaches the change
/// method (at 0.5 noise spreads drift is a contact), and a threshold without the change
/// method is refused on one line.
#[test]
fn evaluate_real_from_the_command_line() {
    let Some(dir) = common::real("allsight") else {
        return;
    };
    let tmp = common::temp_in("evaluate-real-cli", "run");
    std::fs::create_dir_all(&tmp).unwrap();
    let rel = |name: &str| dir.join(name).display().to_string();
    let line = format!(
        r#"{{"image": "{}", "reference": "{}", "contact": false, "group": "drift"}}"#,
        rel("s1_image2_0.03_0.jpg"),
        rel("s1_ref_frame.jpg")
    );
    let set = set_file(&tmp, &[&line]);
    let out = tmp.join("out");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "evaluate",
            "--real",
            set.to_str().unwrap(),
            "--sensor",
            "allsight",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        common::geltip(&args)
    };
    let (code, _, stderr) = run(&["--method", "change"]);
    assert_eq!(code, 0, "{stderr}");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let all = summary["rows"].as_array().unwrap().last().unwrap().clone();
    assert_eq!(all["false_contacts"], 0, "{summary}");
    for name in ["per_frame.jsonl", "set.jsonl", "tables.md", "by_group.svg"] {
        assert!(out.join(name).is_file(), "{name}");
    }
    let (code, _, stderr) = run(&["--method", "change", "--threshold", "0.5"]);
    assert_eq!(code, 0, "{stderr}");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let all = summary["rows"].as_array().unwrap().last().unwrap().clone();
    assert_eq!(all["false_contacts"], 1, "{summary}");
    let (code, _, stderr) = run(&["--method", "surface", "--threshold", "5"]);
    assert_ne!(code, 0);
    let e = common::error_line(&stderr);
    assert!(e.contains("--threshold: applies to method 'change'"), "{e}");
}
