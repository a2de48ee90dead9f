//! The `geltip` binary as external scripts use it: exact JSON shapes, exit codes and
//! one-line errors.

mod common;

use common::{error_line, geltip};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn json(stdout: &str) -> Value {
    serde_json::from_str(stdout.trim())
        .unwrap_or_else(|e| panic!("not one JSON object ({e}): {stdout}"))
}

fn temp(name: &str) -> PathBuf {
    common::temp_in("cli", name)
}

#[test]
fn sensors_lists_the_presets() {
    let (code, out, _) = geltip(&["sensors"]);
    assert_eq!(code, 0);
    for name in ["paper", "webcam70", "tube13", "tube21"] {
        assert!(out.contains(name), "{out}");
    }
}

#[test]
fn unproject_and_project() {
    let (code, out, _) = geltip(&["unproject", "--sensor", "paper", "320", "240"]);
    assert_eq!(code, 0);
    let v = json(&out);
    assert_eq!(v["region"], "hemisphere");
    let p: Vec<f64> = v["point"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!((p[2] - 27.5).abs() < 1e-9 && p[0].abs() < 1e-9, "{out}");
    assert_eq!(v["normal"].as_array().unwrap().len(), 3);
    assert_eq!(v.as_object().unwrap().len(), 3);

    let (_, out, _) = geltip(&["unproject", "--sensor", "paper", "580", "240"]);
    assert_eq!(json(&out)["region"], "cylinder");
    let (_, out, _) = geltip(&["unproject", "--sensor", "paper", "0", "0"]);
    assert_eq!(out.trim(), r#"{"region":"none"}"#);

    let (code, out, _) = geltip(&["project", "--sensor", "paper", "0", "0", "27.5"]);
    assert_eq!(code, 0);
    assert_eq!(json(&out)["pixel"], serde_json::json!([320.0, 240.0]));
    // Negative coordinates are numbers, not flags.
    let (code, out, _) = geltip(&["project", "--sensor", "paper", "-7.5", "0", "10"]);
    assert_eq!(code, 0, "{out}");
    assert!(json(&out)["pixel"].is_array());
    let (_, out, _) = geltip(&["project", "--sensor", "paper", "0", "0", "40"]);
    let v = json(&out);
    assert!(
        v["pixel"].is_null() && v["reason"].as_str().unwrap().contains("outside the finger"),
        "{out}"
    );
}

#[test]
fn bad_sensor_files_are_one_line_errors_naming_the_field() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/sensors/paper.toml"
    ))
    .unwrap();
    let path = temp("bad.toml");
    std::fs::write(&path, text.replace("radius_mm = 7.5", "radius_mm = 0.0")).unwrap();
    let (code, out, err) = geltip(&["unproject", "--sensor", path.to_str().unwrap(), "1", "1"]);
    assert_eq!(code, 1);
    assert!(out.is_empty());
    assert!(error_line(&err).contains("finger.radius_mm"), "{err}");
    let (code, _, err) = geltip(&["sensors-typo"]);
    assert_ne!(code, 0);
    assert!(!err.is_empty());
    let (code, _, err) = geltip(&["project", "--sensor", "nope", "0", "0", "1"]);
    assert_eq!(code, 1);
    assert!(error_line(&err).contains("unknown sensor 'nope'"), "{err}");
}

#[test]
fn render_localise_round_trip() {
    let reference = temp("ref.png");
    let image = temp("sphere.png");
    let labels = temp("sphere.json");
    let depth = temp("sphere.npy");
    let (code, _, err) = geltip(&[
        "render",
        "--sensor",
        "paper",
        "--reference",
        "-o",
        reference.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, out, err) = geltip(&[
        "render",
        "--sensor",
        "paper",
        "--object",
        "sphere",
        "--at",
        "rotation=45",
        "--azimuth",
        "-30",
        "--depth",
        "1",
        "-o",
        image.to_str().unwrap(),
        "--labels",
        labels.to_str().unwrap(),
        "--depth-map",
        depth.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let truth = json(&out);
    let on_disk: Value = serde_json::from_str(&std::fs::read_to_string(&labels).unwrap()).unwrap();
    assert_eq!(truth, on_disk);
    for key in ["object", "point", "pixel", "normal", "depth_mm", "region"] {
        assert!(!truth[key].is_null(), "labels lack {key}");
    }
    assert!(std::fs::read(&depth).unwrap().starts_with(b"\x93NUMPY"));
    let (code, out, err) = geltip(&[
        "localise",
        "--sensor",
        "paper",
        "--reference",
        reference.to_str().unwrap(),
        "--method",
        "surface",
        image.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let d = json(&out);
    assert_eq!(d["detected"], true);
    let p: Vec<f64> = d["point"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let t: Vec<f64> = truth["point"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let err_mm = ((p[0] - t[0]).powi(2) + (p[1] - t[1]).powi(2) + (p[2] - t[2]).powi(2)).sqrt();
    assert!(err_mm < 0.5, "{err_mm} mm");
    // The reference against itself: no contact, not an error.
    let (code, out, _) = geltip(&[
        "localise",
        "--sensor",
        "paper",
        "--reference",
        reference.to_str().unwrap(),
        reference.to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    assert_eq!(json(&out)["detected"], false);
}

#[test]
fn bad_render_and_localise_input() {
    let out_png = temp("never.png");
    for (args, needle) in bad_render_args() {
        let mut all = vec!["render", "--sensor", "paper"];
        all.extend(args);
        all.extend(["-o", out_png.to_str().unwrap()]);
        let (code, _, err) = geltip(&all);
        assert_eq!(code, 1, "{all:?}");
        assert!(error_line(&err).contains(needle), "{all:?}: {err}");
        assert!(!out_png.exists(), "a failed render left a file");
    }
    bad_localise_inputs_are_refused();
}

/// Render arguments that must fail, and what the error line must say.
fn bad_render_args() -> Vec<(Vec<&'static str>, &'static str)> {
    vec![
        (
            vec!["--object", "sphere", "--at", "rotation=x", "--depth", "1"],
            "--at: the value of 'rotation=x' is not a number",
        ),
        (
            vec![
                "--object",
                "sphere",
                "--at",
                "translation=99",
                "--depth",
                "1",
            ],
            "--at",
        ),
        (
            vec!["--object", "sphere", "--at", "rotation=10", "--depth", "-1"],
            "--depth: a press depth cannot be negative, got -1 mm",
        ),
        (
            vec![
                "--object",
                "sphere",
                "--at",
                "rotation=10",
                "--depth",
                "1",
                "--tilt-towards",
                "nan",
            ],
            "--tilt-towards: must be a finite number, got NaN",
        ),
        (
            vec!["--object", "sphere", "--pose", "0,0,x,1,0,0,0"],
            "--pose: 'x' is not a number",
        ),
        (
            vec!["--object", "sphere", "--pose", "0 0 0 2 0 0 0"],
            "--pose: the quaternion w x y z must have length 1",
        ),
        (
            vec![
                "--object",
                "no-such.obj",
                "--at",
                "rotation=10",
                "--depth",
                "1",
            ],
            "no-such.obj",
        ),
        (
            vec!["--object", "pyramid", "--at", "rotation=10", "--depth", "1"],
            "pyramid",
        ),
    ]
}

/// A frame of the wrong size and a missing reference: one-line errors naming them.
fn bad_localise_inputs_are_refused() {
    let small = temp("small.png");
    image::RgbImage::new(10, 10).save(&small).unwrap();
    let (code, _, err) = geltip(&[
        "localise",
        "--sensor",
        "paper",
        "--reference",
        small.to_str().unwrap(),
        small.to_str().unwrap(),
    ]);
    assert_eq!(code, 1);
    assert!(error_line(&err).contains("10x10"), "{err}");
    let (code, _, err) = geltip(&[
        "localise",
        "--sensor",
        "paper",
        "--reference",
        "/nonexistent.png",
        small.to_str().unwrap(),
    ]);
    assert_eq!(code, 1);
    assert!(error_line(&err).contains("/nonexistent.png"), "{err}");
}

/// `--pose` with the labels' pose renders the bytes of the `--at/--spin/--tilt` render; a
/// scene file gives one label per contact plus the union mask; bad scenes and poses are
/// one-line errors.
#[test]
fn render_pose_and_scene() {
    the_labels_pose_renders_the_same_bytes();
    let scene = temp("scene.toml");
    let png = temp("scene.png");
    a_scene_labels_each_contact(&scene, &png);
    bad_scenes_and_poses_are_one_line_errors(&scene, &png);
}

/// `--pose` with the labels' pose renders the bytes of the `--at/--spin/--tilt` render.
fn the_labels_pose_renders_the_same_bytes() {
    let (a_png, a_json) = (temp("tilted.png"), temp("tilted.json"));
    let (code, _, err) = geltip(&[
        "render",
        "--sensor",
        "paper",
        "--object",
        "cylinder",
        "--at",
        "rotation=40",
        "--azimuth",
        "25",
        "--spin",
        "30",
        "--tilt",
        "15",
        "--tilt-towards",
        "60",
        "--depth",
        "0.7",
        "-o",
        a_png.to_str().unwrap(),
        "--labels",
        a_json.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let labels: Value = serde_json::from_str(&std::fs::read_to_string(&a_json).unwrap()).unwrap();
    assert_eq!(labels["score_against"], "contact_centre");
    let pose: Vec<String> = labels["pose"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap().to_string())
        .collect();
    let b_png = temp("posed.png");
    let (code, out, err) = geltip(&[
        "render",
        "--sensor",
        "paper",
        "--object",
        "cylinder",
        "--pose",
        &pose.join(","),
        "-o",
        b_png.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(json(&out)["depth_mm"].as_f64().unwrap() > 0.0);
    assert!(std::fs::read(&a_png).unwrap() == std::fs::read(&b_png).unwrap());
}

/// A scene file of two contacts: one label per contact and the union mask.
fn a_scene_labels_each_contact(scene: &Path, png: &Path) {
    std::fs::write(
        scene,
        "[[contacts]]\nobject = \"sphere\"\nat = \"rotation=30\"\ndepth = 1.0\n\n[[contacts]]\nobject = \"torus\"\nat = \"translation=8\"\nazimuth = 180\ndepth = 0.6\n",
    )
    .unwrap();
    let (code, out, err) = geltip(&[
        "render",
        "--sensor",
        "paper",
        "--scene",
        scene.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let v = json(&out);
    let contacts = v["contacts"].as_array().unwrap();
    assert_eq!(contacts.len(), 2);
    assert_eq!(contacts[1]["object"], "torus");
    // Each contact's mask counts the pressed pixels of its own footprint's rectangle: the
    // union is no more than their sum (rectangles may overlap) and no less than either.
    let per: Vec<u64> = contacts
        .iter()
        .map(|c| c["mask_pixels"].as_u64().unwrap())
        .collect();
    let union = v["mask_pixels"].as_u64().unwrap();
    assert!(
        union <= per[0] + per[1] && union >= per[0].max(per[1]) && per[1] > 1000,
        "{union} {per:?}"
    );
}

/// A contact without a depth, and a pose short of touching.
fn bad_scenes_and_poses_are_one_line_errors(scene: &Path, png: &Path) {
    std::fs::write(
        scene,
        "[[contacts]]\nobject = \"sphere\"\nat = \"rotation=30\"\n",
    )
    .unwrap();
    let (code, _, err) = geltip(&[
        "render",
        "--sensor",
        "paper",
        "--scene",
        scene.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_ne!(code, 0);
    assert!(
        error_line(&err).contains(&format!(
            "scene {}: contacts[0].depth: required",
            scene.display()
        )),
        "{err}"
    );
    let (code, _, err) = geltip(&[
        "render",
        "--sensor",
        "paper",
        "--object",
        "sphere",
        "--pose",
        "1,0,0,0,0,-1,0,0,0,0,-1,40,0,0,0,1",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_ne!(code, 0);
    assert!(error_line(&err).contains("short of touching"), "{err}");
}

/// Scene files take `at` as text or a table and name the file and the contact in errors.
#[test]
fn scene_errors_name_the_contact() {
    let png = temp("scene-errors.png");
    let render = |scene: &std::path::Path| {
        geltip(&[
            "render",
            "--sensor",
            "paper",
            "--scene",
            scene.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
        ])
    };
    let scene = temp("scene-errors.json");
    for (contacts, says) in [
        (
            r#"[{"object": "sphere", "at": {"rotation": 30}, "depth": 1}, {"object": "cone", "at": "s=4", "depth": -2}]"#,
            "contacts[1].depth: a press depth cannot be negative, got -2 mm",
        ),
        (
            r#"[{"object": "sphere", "at": {"rotation": 30, "s": 1}, "depth": 1}]"#,
            "contacts[0].at: expected one key of rotation, translation, s",
        ),
        (
            r#"[{"object": "sphere", "at": "rotation=30", "depth": "deep"}]"#,
            "contacts[0].depth: invalid type: string",
        ),
        (
            r#"[{"object": "sphere", "at": "rotation=30", "depht": 1}]"#,
            "contacts[0].depht: unknown field `depht`",
        ),
        (
            r#"[{"object": "sphere", "at": "translation=99", "depth": 1}]"#,
            "contacts[0].at: translation 99 mm is",
        ),
        (
            r#"[{"object": "pyramid", "at": "rotation=30", "depth": 1}]"#,
            "contacts[0]: object 'pyramid'",
        ),
    ] {
        std::fs::write(&scene, format!(r#"{{"contacts": {contacts}}}"#)).unwrap();
        let (code, _, err) = render(&scene);
        assert_eq!(code, 1, "{contacts}");
        let line = error_line(&err);
        let prefix = format!("error: scene {}: ", scene.display());
        assert!(
            line.starts_with(&prefix) && line.contains(says),
            "{contacts}: {line}"
        );
        assert!(!png.exists(), "a refused scene left a file");
    }
    // The same scene in TOML, with a table for `at`, renders.
    let toml = temp("scene-table.toml");
    std::fs::write(
        &toml,
        "[[contacts]]\nobject = \"sphere\"\nat = {rotation = 30}\ndepth = 1.0\n",
    )
    .unwrap();
    let (code, out, err) = render(&toml);
    assert_eq!(code, 0, "{err}");
    assert_eq!(json(&out)["contacts"][0]["place"], "rotation 30 deg");
}

/// A press the finger and the object cannot make is a one-line error saying how deep it
/// can go, not an empty frame labelled as if pressed.
#[test]
fn a_press_through_the_finger_is_refused() {
    let png = temp("through.png");
    let (code, out, err) = geltip(&[
        "render",
        "--sensor",
        "paper",
        "--object",
        "sphere",
        "--at",
        "rotation=0",
        "--depth",
        "1e9",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{out}");
    let line = error_line(&err);
    assert!(
        line.starts_with("error: --depth: the sphere pressed 1000000000 mm deep")
            && line.contains("only up to"),
        "{line}"
    );
    assert!(!png.exists(), "a refused press left a file");
}

/// A failed write says its cause once.
#[test]
fn io_errors_say_their_cause_once() {
    let file = temp("a-regular-file");
    std::fs::write(&file, b"").unwrap();
    let png = file.join("x.png");
    let (code, _, err) = geltip(&[
        "render",
        "--sensor",
        "paper",
        "--reference",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 1);
    let line = error_line(&err);
    assert!(
        line.starts_with(&format!("error: {}: ", png.display())),
        "{line}"
    );
    assert_eq!(line.matches("(os error").count(), 1, "{line}");
}
