//! Fuzz tests of every parser a user feeds (sensor TOML, scene files, meshes, PNG frames,
//! poses and places, a dataset's files on resume and merge, predictions, a set's labels and
//! a compared summary as evaluate reads them, a calibration's contacts file and empty
//! frames): structure-aware mutations of
//! real inputs, each case refused with a one-line error or accepted with a sound value,
//! never a panic or a hang. See `tests/fuzz/mod.rs`; `cargo bench --bench fuzz -- --cases N`
//! runs longer. `GELTIP_FUZZ_CASES=N` sets every target's cases here.

#[path = "fuzz/mod.rs"]
mod fuzz;

use fuzz::targets::by_name;

/// Runs the target's CI cases (or `GELTIP_FUZZ_CASES`) and fails on any unsound case.
fn check(name: &str) {
    let target = by_name(name);
    let cases = std::env::var("GELTIP_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(target.ci_cases);
    let report = fuzz::run(target, cases);
    println!("{}\n{}", fuzz::header(), fuzz::describe(&report));
    assert!(report.failures.is_empty(), "{}", fuzz::describe(&report));
    assert_eq!(report.cases, cases);
    // Some mutated inputs are accepted: the mutations reach the checks behind the syntax.
    assert!(report.mutants_accepted > 0, "{}", fuzz::describe(&report));
}

#[test]
fn sensor_toml() {
    check("sensor toml");
}

#[test]
fn scene_json() {
    check("scene json");
}

#[test]
fn scene_toml() {
    check("scene toml");
}

#[test]
fn mesh_obj() {
    check("mesh obj");
}

#[test]
fn mesh_gltf() {
    check("mesh gltf");
}

#[test]
fn mesh_glb() {
    check("mesh glb");
}

#[test]
fn png_load_image() {
    check("png load_image");
}

#[test]
fn png_localise_frame() {
    check("png localise frame");
}

#[test]
fn png_dataset_background() {
    check("png dataset background");
}

#[test]
fn pose_text() {
    check("pose text");
}

#[test]
fn place_text() {
    check("place text");
}

#[test]
fn primitive_text() {
    check("primitive text");
}

#[test]
fn resume_dataset_json() {
    check("resume dataset.json");
}

#[test]
fn resume_labels_jsonl() {
    check("resume labels.jsonl");
}

#[test]
fn merge_dataset_json() {
    check("merge dataset.json");
}

#[test]
fn merge_first_dataset_json() {
    check("merge first dataset.json");
}

#[test]
fn merge_labels_jsonl() {
    check("merge labels.jsonl");
}

#[test]
fn evaluate_predictions_jsonl() {
    check("evaluate predictions.jsonl");
}

#[test]
fn evaluate_detector_answer() {
    check("evaluate detector answer");
}

#[test]
fn calibrate_contacts_jsonl() {
    check("calibrate contacts.jsonl");
}

#[test]
fn png_calibrate_empty_frame() {
    check("png calibrate empty frame");
}

#[test]
fn evaluate_labels_jsonl() {
    check("evaluate labels.jsonl");
}

#[test]
fn evaluate_compare_summary_json() {
    check("evaluate compare summary.json");
}

/// Every target in the table has a test above.
#[test]
fn every_target_is_tested() {
    let source = include_str!("fuzz.rs");
    for t in fuzz::targets::all() {
        assert!(
            source.contains(&format!("check(\"{}\")", t.name)),
            "no test runs the fuzz target '{}'",
            t.name
        );
    }
}
